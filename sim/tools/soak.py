"""The long soak (``make soak``, not part of ``make test``): at least 100 000 request cycles of
random frames with random faults on Verilator, as many clean frames at the jitter limit that
issue 28's noise checks must not reject, then every other campaign at a larger scale.

    python -m sim.tools.soak [--frames 100000] [--jobs 2] [--scale 10]

The random mix and ``no_false_alarm`` are each split over ``--jobs`` simulator processes with
different seeds; each writes its figures to sim_build/campaign/soak/. Prints the campaign tables
(sim/tools/campaign_report.py) and the frames per second of wall time.
"""

import argparse
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

from sim.shared import discovery, runner
from sim.tools import campaign_report

RESULTS = runner.BUILD / "campaign" / "soak"
#: The campaigns sized by --frames, not --scale: the request cycles each runs at scale 1
#: (random_mix: RANDOM_MIX_CYCLES_AT_SCALE_1, no_false_alarm: FALSE_ALARM_FRAMES_AT_SCALE_1, in
#: sim/scenarios/campaigns.py).
FRAMES_AT_SCALE_1 = {"random_mix": 300, "no_false_alarm": 200}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100_000, help="random-mix cycles in all")
    ap.add_argument("--jobs", type=int, default=2, help="parallel simulator processes")
    ap.add_argument("--scale", type=float, default=10, help="scale of the other campaigns")
    ap.add_argument("--one", nargs=3, metavar=("CAMPAIGN", "SCALE", "SEED"),
                    help=argparse.SUPPRESS)     # internal: run one campaign in this process
    args = ap.parse_args(argv)
    if args.one:
        name, scale, seed = args.one
        env = {"BISS_SOAK_SEED": seed} if seed else {}
        runner.run_campaign(name, float(scale), RESULTS, seed=int(seed) if seed else None,
                            extra_env=env)
        return 0
    shutil.rmtree(RESULTS, ignore_errors=True)
    RESULTS.mkdir(parents=True)
    # Once, before the parallel runs: every build a campaign runs on (only_on_builds).
    for build in sorted({b for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS)
                         for b in s.builds}):
        runner.build_once("verilator", build, internal_clock=True)
    jobs = [(name, args.frames / args.jobs / at_1, 1000 + i)
            for name, at_1 in FRAMES_AT_SCALE_1.items() for i in range(args.jobs)]
    jobs += [(s.name, args.scale, None) for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS)
             if s.name not in FRAMES_AT_SCALE_1]
    t0 = time.monotonic()
    failures = []

    def one(job):
        # One simulator per subprocess: cocotb's runner object is not safe to share
        # between threads (its test() keeps per-run state).
        name, scale, seed = job
        cmd = [sys.executable, "-m", __spec__.name, "--one", name, str(scale), str(seed or "")]
        proc = subprocess.run(cmd, cwd=runner.ROOT, capture_output=True, text=True)
        log = RESULTS / f"{name}-{seed}.log"
        log.write_text(proc.stdout + proc.stderr)
        if proc.returncode:
            failures.append(f"{name} (seed {seed}): see {log}")
            return f"{name} (seed {seed}): FAIL"
        return f"{name} (seed {seed}): pass"

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for line in pool.map(one, jobs):
            print(line, flush=True)
    wall = time.monotonic() - t0
    status = campaign_report.main([str(RESULTS)])
    short = []
    for name in FRAMES_AT_SCALE_1:
        mix = [r for n, r in campaign_report.load(RESULTS).items() if n.startswith(name)]
        cycles = sum(r["cycles"] for r in mix)
        sim_wall = max((r["wall_s"] for r in mix), default=0)
        print(f"\nsoak: {cycles} {name} cycles in {sim_wall:.0f} s per process x {len(mix)} "
              f"processes: {cycles / sim_wall if sim_wall else 0:.0f} frames/s of wall time "
              f"({sum(r['cycles_per_s'] for r in mix):.0f} summed over processes)")
        if cycles < args.frames * 0.99:
            short.append(f"{name}: {cycles} cycles, fewer than --frames {args.frames}")
    print(f"whole soak {wall / 60:.1f} min")
    for f in failures + short:
        print("FAILED:", f)
    return 1 if failures or status or short else 0


if __name__ == "__main__":
    sys.exit(main())
