"""pytest entry: the cocotb regression (sim/scenarios/master.py and control_channel.py) on
Verilator and Icarus.

``SIM=verilator`` or ``SIM=icarus`` picks one simulator; by default both run. Every
``@cocotb.test`` of the scenario module runs, on the builds and clocks its markers ask for
(sim/shared/discovery.py): a new scenario needs no edit here.
"""

import os

import pytest

from sim.shared import discovery, runner

SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)
SCENARIOS = [s for module in runner.REGRESSION_SCENARIOS for s in discovery.scenarios(module)]
assert len({s.name for s in SCENARIOS}) == len(SCENARIOS), "scenario names must be unique"


def marks(s, sim="verilator"):
    """:func:`discovery.pytest_marks` (strict xfail, ``long`` on Icarus), and the mark
    ``control_channel`` on the control-channel scenarios (``-k control_channel`` runs them,
    ``-k 'not control_channel'`` leaves them out)."""
    out = discovery.pytest_marks(s, sim)
    if s.module == runner.CONTROL_SCENARIOS:
        out.append(pytest.mark.control_channel)
    return out


CASES = [pytest.param(sim, build, s, runner.CLK_HZ, False, id="-".join(
             [sim] + ([] if build == discovery.DEFAULT_BUILD else [build]) + [s.name]),
             marks=marks(s, sim))
         for sim in SIMS for s in SCENARIOS for build in s.builds]
CASES += [pytest.param("verilator", discovery.DEFAULT_BUILD, s, discovery.FAST_CLK_HZ, False,
                       id=f"verilator-200MHz-{s.name}", marks=marks(s))
          for s in SCENARIOS if s.fast_clock and "verilator" in SIMS]
# full_in_sim_long: the run above at that clock is a subset; the whole is one more Verilator
# run, marked long (make sim-long).
CASES += [pytest.param("verilator", discovery.DEFAULT_BUILD, s, clk, True,
                       id="-".join(["verilator"] + ([] if clk == runner.CLK_HZ else
                                                    [f"{clk // 1_000_000}MHz"])
                                   + ["full", s.name]),
                       marks=marks(s) + [pytest.mark.long])
          for s in SCENARIOS for clk in s.full_clocks if "verilator" in SIMS]


@pytest.mark.parametrize("sim,build,scenario,clk_hz,full", CASES)
def test_scenario(sim, build, scenario, clk_hz, full):
    r, build_dir = runner.build_once(sim, build)
    env = {"BISS_CLK_HZ": str(clk_hz)}
    if full:
        env[discovery.FULL_ENV] = "1"
    xml = runner.run(r, build_dir, scenario.module, testcase=scenario.name, extra_env=env)
    runner.check(xml)
