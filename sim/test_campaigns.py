"""pytest entry: the reliability campaigns (sim/scenarios/campaigns.py) on Verilator.

Every ``@cocotb.test`` of the scenario module is a campaign and runs here (found by
sim/shared/discovery.py). ``make campaigns`` runs them at ``BISS_CAMPAIGN_SCALE`` = 1 (the fast
slice); ``make soak`` runs sim/tools/soak.py instead. Every campaign writes its figures and
coverage to sim_build/campaign/, and sim/tools/campaign_report.py turns them into tables.
"""

import os

import pytest

from sim.shared import discovery, runner

RESULTS = runner.BUILD / "campaign" / "slice"
# A campaign marked ``expected_to_fail`` (an open issue) is a strict xfail here too.
CASES = [pytest.param(s.name, build, id=s.name if build == discovery.DEFAULT_BUILD
                      else f"{build}-{s.name}", marks=discovery.pytest_marks(s, "verilator"))
         for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS) for build in s.builds]


@pytest.mark.parametrize("campaign,build", CASES)
def test_campaign(campaign, build):
    runner.run_campaign(campaign, os.environ.get("BISS_CAMPAIGN_SCALE", "1"), RESULTS,
                        preset=build)
