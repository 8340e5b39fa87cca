"""make demo / make demo-bp3: simulate an encoder model on the generated Verilog, print the result.

    python -m sim.tools.demo [--sim verilator|icarus]          RESOLUTE FS RSH frames + waveform
    python -m sim.tools.demo --bp3 [--sim verilator|icarus]    BP3 identification, EDS, positions
    python -m sim.tools.demo --waves-file [--sim ...]          print the first demo's waveform path
"""

import argparse
import os
import sys
import xml.etree.ElementTree as ET

from sim.shared import runner
from sim.shared.runner import output_to

DEMOS = {
    # flag: (scenario module, table file, what it simulates, waves, the notes printed after it)
    False: ("sim.scenarios.demo", "frames.txt",
            "a RESOLUTE FS RSH encoder model (BiSS Safety, CPW 36 + SPW 28 bits)", True,
            ["Every frame was checked field by field against what the encoder model sent.",
             "delay/ns: round trip measured by the core (ceil, in 10 ns clocks); "
             "model/ns: cable + 42.5 ns encoder delay."]),
    True: ("sim.scenarios.demo_bp3", "bp3.txt",
           "a BP3 encoder model (12 + 20 bits, CRC-6) identified over the control channel",
           False,
           ["bissmaster.bp3.identify() ran against the simulated core through its ca_* ports; "
            "every frame during and after it",
            "was checked against the encoder model, the positions with the derived settings "
            "only (docs/control.md)."]),
}


#: The demos' build trees: sim_build/<sim>-waves-demo (sim_build/icarus-demo: BP3 on Icarus).
TAG = "-demo"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=os.environ.get("SIM", "verilator"), choices=runner.SIMULATORS)
    ap.add_argument("--bp3", action="store_true",
                    help="identify a BP3 encoder, print its EDS, configure from it, read positions")
    ap.add_argument("--waves-file", action="store_true",
                    help="print the path of the waveform the (first) demo writes, run nothing "
                         "(make waves)")
    args = ap.parse_args()
    module, table_name, what, waves, notes = DEMOS[args.bp3]
    dump = runner.waves_file(args.sim, runner.build_dir_of(args.sim, waves=True, tag=TAG))
    if args.waves_file:
        if not dump.exists():
            sys.exit(f"demo: no waveform at {dump}; run make demo SIM={args.sim} first")
        print(dump)
        return

    out = runner.BUILD / "demo"
    out.mkdir(parents=True, exist_ok=True)
    table = out / table_name
    log = out / ("demo-bp3.log" if args.bp3 else "demo.log")
    table.unlink(missing_ok=True)
    if waves:
        dump.unlink(missing_ok=True)        # a waveform from an earlier run is not this one's
    print(f"Simulating biss_master ({args.sim}) with {what} ...", flush=True)
    try:
        with output_to(log):
            # Verilator: one build for both demos, with tracing compiled in (make waves reads
            # the first demo's dump; it writes one only when the run asks). Icarus dumps
            # whenever the build has tracing, so the BP3 demo has a build without.
            traced = waves or args.sim == "verilator"
            r, build_dir = runner.build(args.sim, waves=traced, tag=TAG)
            xml = runner.run(r, build_dir, module, waves=waves,
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
    for line in notes:
        print(line)
    if not waves:
        return
    if dump.exists():
        print(f"\nWaveform: {dump}")
        print(f"Open it:  make waves SIM={args.sim} (one frame as a PNG), then gtkwave {dump} "
              "sim_build/waves/biss_master.gtkw")
    else:
        print(f"\n(no waveform was written; see {log})")


if __name__ == "__main__":
    main()
