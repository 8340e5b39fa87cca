"""make demo: simulate a RESOLUTE FS RSH encoder on the generated Verilog, print its frames.

    python sim/demo.py [--sim verilator|icarus]
"""

import argparse
import contextlib
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import runner  # noqa: E402

GTKW = runner.ROOT / "scripts" / "biss_master.gtkw"


@contextlib.contextmanager
def output_to(path):
    """Send this process's and its children's stdout/stderr to a log file."""
    sys.stdout.flush(); sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(path, "w") as log:
        os.dup2(log.fileno(), 1); os.dup2(log.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush(); sys.stderr.flush()
            os.dup2(saved[0], 1); os.dup2(saved[1], 2)
            os.close(saved[0]); os.close(saved[1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=os.environ.get("SIM", "verilator"), choices=runner.SIMULATORS)
    args = ap.parse_args()

    out = runner.BUILD / "demo"
    out.mkdir(parents=True, exist_ok=True)
    table = out / "frames.txt"
    log = out / "demo.log"
    table.unlink(missing_ok=True)
    print(f"Simulating biss_master ({args.sim}) with a RESOLUTE FS RSH encoder model "
          f"(BiSS Safety, CPW 36 + SPW 28 bits) ...", flush=True)
    try:
        with output_to(log):
            r, build_dir = runner.build(args.sim, waves=True, tag="-demo")
            xml = runner.run(r, build_dir, "cocotb_demo", waves=True,
                             extra_env={"BISS_DEMO_TABLE": str(table)})
        ok = all(not c.findall("failure") and not c.findall("error")
                 for c in ET.parse(xml).getroot().iter("testcase"))
    except BaseException as e:          # the runner raises SystemExit on a failed test
        ok = False
        print(f"simulation failed: {e!r}")
    if not ok or not table.exists():
        print(f"The demo failed; the simulator's output is in {log}")
        sys.exit(1)
    print()
    print(table.read_text(), end="")
    print()
    print("Every frame was checked field by field against what the encoder model sent.")
    print("delay/ns: round trip measured by the core (ceil, in 10 ns clocks); "
          "model/ns: cable + 42.5 ns encoder delay.")
    waves = sorted(build_dir.glob("dump.*"))
    if waves:
        print(f"\nWaveform: {waves[0]}")
        print(f"Open it:  gtkwave {waves[0]} {GTKW}")
    else:
        print(f"\n(no waveform was written; see {log})")


if __name__ == "__main__":
    main()
