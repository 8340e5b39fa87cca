"""pytest entry: the C driver (sw/) against the bus tops on Verilator and Icarus: every
scenario of sim/scenarios/driver.py on the committed AXI4-Lite top, every scenario of
sim/scenarios/driver_chain.py (chains: words 2..7) on the ``axil_chain`` top
(runner.DRIVER_MODULES).

The driver is built first (sw/Makefile, strict C99, into sim_build/driver/) and its path handed
to the simulator in ``BISS_DRIVER_LIB``. ``SIM=verilator`` or ``SIM=icarus`` picks one
simulator; by default both run. Every ``@cocotb.test`` of each scenario module runs.
"""

import os

import pytest

from sim.shared import discovery, runner

SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)

CASES = [pytest.param(sim, module, bus, s.name, id=f"{sim}-{s.name}",
                      marks=discovery.pytest_marks(s, sim))
         for sim in SIMS for module, bus in runner.DRIVER_MODULES.items()
         for s in discovery.scenarios(module)]


@pytest.mark.parametrize("sim,module,bus,scenario", CASES)
def test_driver_scenario(sim, module, bus, scenario):
    lib = runner.build_driver()
    r, build_dir = runner.build_bus_once(sim, bus)
    xml = runner.run(r, build_dir, module, testcase=scenario,
                     toplevel=runner.bus_top(bus)[1],
                     extra_env={**runner.bus_env(bus), "BISS_DRIVER_LIB": str(lib)})
    runner.check(xml)
