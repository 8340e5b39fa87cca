"""pytest entry: the reliability campaigns (sim/cocotb_campaign.py) on Verilator.

``make test`` runs them at ``BISS_CAMPAIGN_SCALE`` = 1 (the fast slice); ``make soak`` runs
sim/soak.py instead. Every campaign writes its figures and coverage to sim_build/campaign/,
and sim/campaign_report.py turns them into tables.
"""

import os

import pytest

import runner
from test_sim import _check

CAMPAIGNS = ["crc_detection", "line_faults", "sign_of_life", "config_fuzz", "random_mix"]
RESULTS = runner.BUILD / "campaign" / "slice"
_built = {}


def build(sim="verilator"):
    """The campaigns' build: the core with an in-simulator clock (sim/fastclk.py)."""
    if sim not in _built:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        _built[sim] = runner.build(sim, tag=f"-campaign-{worker}", internal_clock=True)
    return _built[sim]


def run(campaign, scale, results, sim="verilator", seed=None, extra_env=None):
    r, build_dir = build(sim)
    env = {"BISS_CAMPAIGN_SCALE": str(scale), "BISS_CAMPAIGN_RESULTS": str(results),
           **(extra_env or {})}
    xml = runner.run(r, build_dir, "cocotb_campaign", testcase=campaign, internal_clock=True,
                     seed=seed, extra_env=env)
    _check(xml)


@pytest.mark.parametrize("campaign", CAMPAIGNS)
def test_campaign(campaign):
    run(campaign, os.environ.get("BISS_CAMPAIGN_SCALE", "1"), RESULTS)
