"""Campaigns at a chosen scale, then their report: ``make noise`` runs issue 28's.

    python -m sim.tools.campaign NAME [NAME ...] [--scale 50] [--out sim_build/campaign/NAME]

Each NAME is a ``@cocotb.test`` of sim/scenarios/campaigns.py (``--list`` prints them), run in
turn. The figures and coverage go to ``--out`` (emptied first; default: named after the first
campaign), the tables of sim/tools/campaign_report.py to the terminal and ``report.md`` there.
Exits non-zero if a campaign finds a defect (after running the others and the report).
"""

import argparse
import shutil
import sys
from pathlib import Path

from sim.shared import discovery, runner
from sim.tools import campaign_report


def main(argv=None):
    names = [s.name for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS)]
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", nargs="*", metavar="NAME", help="one or more of --list")
    ap.add_argument("--scale", type=float, default=1, help="size: 1 is make test's slice")
    ap.add_argument("--out", default=None, help="results folder")
    ap.add_argument("--list", action="store_true", help="list the campaigns and exit")
    args = ap.parse_args(argv)
    if args.list or not args.name:
        print("\n".join(names))
        return 0 if args.list else 2
    unknown = [n for n in args.name if n not in names]
    if unknown:
        ap.error(f"not a campaign: {', '.join(unknown)} (--list prints them)")
    # Absolute: the simulator runs in its build directory.
    out = runner.BUILD / "campaign" / args.name[0] if args.out is None else Path(args.out).resolve()
    shutil.rmtree(out, ignore_errors=True)
    failed = []
    for name in args.name:
        try:
            runner.run_campaign(name, args.scale, out)
        except AssertionError as e:     # a failed campaign: the others and the report still run
            failed.append(f"{name}: {e}")
    status = campaign_report.main([str(out)])
    for f in failed:
        print("FAILED:", f)
    return 1 if failed or status else 0


if __name__ == "__main__":
    sys.exit(main())
