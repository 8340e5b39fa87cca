"""pytest entry: the C driver (sw/) against the committed AXI4-Lite bus top
(sim/scenarios/driver.py) on Verilator and Icarus.

The driver is built first (sw/Makefile, strict C99, into sim_build/driver-<worker>/) and its
path handed to the simulator in ``BISS_DRIVER_LIB``. ``SIM=verilator`` or ``SIM=icarus`` picks
one simulator; by default both run. Every ``@cocotb.test`` of the scenario module runs.
"""

import os

import pytest

from sim.shared import discovery, runner

SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)
SCENARIOS = discovery.scenarios(runner.DRIVER_SCENARIOS)
BUS = "axil"

CASES = [pytest.param(sim, s.name, id=f"{sim}-{s.name}",
                      marks=discovery.pytest_marks(s, sim))
         for sim in SIMS for s in SCENARIOS]


@pytest.mark.parametrize("sim,scenario", CASES)
def test_driver_scenario(sim, scenario):
    lib = runner.build_driver()
    r, build_dir = runner.build_bus_once(sim, BUS)
    xml = runner.run(r, build_dir, runner.DRIVER_SCENARIOS, testcase=scenario,
                     toplevel=runner.bus_top(BUS)[1],
                     extra_env={"BISS_BUS": BUS, "BISS_DRIVER_LIB": str(lib)})
    runner.check(xml)
