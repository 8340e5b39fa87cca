"""pytest entry: the cocotb regression (sim/scenarios/master.py) on Verilator and Icarus.

``SIM=verilator`` or ``SIM=icarus`` picks one simulator; by default both run. Every
``@cocotb.test`` of the scenario module runs, on the builds and clocks its markers ask for
(sim/shared/discovery.py): a new scenario needs no edit here.
"""

import os

import pytest

from sim.shared import discovery, runner

SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)
SCENARIOS = discovery.scenarios(runner.MASTER_SCENARIOS)


def marks(s):
    """A scenario marked ``expected_to_fail`` is a strict xfail: passing fails the run."""
    return [pytest.mark.xfail(strict=True, reason=s.xfail)] if s.xfail else []


CASES = [pytest.param(sim, build, s.name, runner.CLK_HZ, id="-".join(
             [sim] + ([] if build == discovery.DEFAULT_BUILD else [build]) + [s.name]),
             marks=marks(s))
         for sim in SIMS for s in SCENARIOS for build in s.builds]
CASES += [pytest.param("verilator", discovery.DEFAULT_BUILD, s.name, discovery.FAST_CLK_HZ,
                       id=f"verilator-200MHz-{s.name}", marks=marks(s))
          for s in SCENARIOS if s.fast_clock and "verilator" in SIMS]


@pytest.mark.parametrize("sim,build,scenario,clk_hz", CASES)
def test_scenario(sim, build, scenario, clk_hz):
    r, build_dir = runner.build_once(sim, build)
    xml = runner.run(r, build_dir, runner.MASTER_SCENARIOS, testcase=scenario,
                     extra_env={"BISS_CLK_HZ": str(clk_hz)})
    runner.check(xml)
