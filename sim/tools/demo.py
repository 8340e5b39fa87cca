"""make demo: simulate a RESOLUTE FS RSH encoder on the generated Verilog, print its frames.

    python -m sim.tools.demo [--sim verilator|icarus]
"""

import argparse
import os
import sys
import xml.etree.ElementTree as ET

from sim.shared import runner
from sim.shared.runner import output_to



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
            xml = runner.run(r, build_dir, "sim.scenarios.demo", waves=True,
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
        print(f"Open it:  make waves (one frame as a PNG), then gtkwave {waves[0]} "
              "sim_build/waves/biss_master.gtkw")
    else:
        print(f"\n(no waveform was written; see {log})")


if __name__ == "__main__":
    main()
