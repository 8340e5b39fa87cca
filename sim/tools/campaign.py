"""One campaign at a chosen scale, then its report: ``make noise`` runs issue 28's baseline.

    python -m sim.tools.campaign NAME [--scale 50] [--out sim_build/campaign/NAME]

NAME is a ``@cocotb.test`` of sim/scenarios/campaigns.py (``--list`` prints them). The figures
and coverage go to ``--out`` (emptied first), the tables of sim/tools/campaign_report.py to the
terminal and ``report.md`` there. Exits non-zero if the campaign finds a defect.
"""

import argparse
import shutil
import sys

from sim.shared import discovery, runner
from sim.tools import campaign_report


def main(argv=None):
    names = [s.name for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS)]
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", nargs="?", choices=names, metavar="NAME")
    ap.add_argument("--scale", type=float, default=1, help="size: 1 is make test's slice")
    ap.add_argument("--out", default=None, help="results folder")
    ap.add_argument("--list", action="store_true", help="list the campaigns and exit")
    args = ap.parse_args(argv)
    if args.list or args.name is None:
        print("\n".join(names))
        return 0 if args.list else 2
    out = runner.BUILD / "campaign" / args.name if args.out is None else args.out
    shutil.rmtree(out, ignore_errors=True)
    runner.run_campaign(args.name, args.scale, out)
    return campaign_report.main([str(out)])


if __name__ == "__main__":
    sys.exit(main())
