"""pytest entry: the bus tops' cocotb scenarios (sim/scenarios/bus.py) on Verilator and Icarus,
each on the committed AXI4-Lite and Wishbone tops (rtl/generated/biss_master_{axil,wb}.v); the
``uart_*`` scenarios on the UART-bridge top (generated at 3 Mbaud, sim/shared/runner.py).

``SIM=verilator`` or ``SIM=icarus`` picks one simulator; by default both run. Every
``@cocotb.test`` of the scenario module runs; ``@only_on_buses(...)`` narrows the buses.
"""

import os

import pytest

from sim.shared import discovery, runner

SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)
SCENARIOS = discovery.scenarios(runner.BUS_SCENARIOS)

CASES = [pytest.param(sim, bus, s.name, id=f"{sim}-{bus}-{s.name}",
                      marks=discovery.pytest_marks(s, sim))
         for sim in SIMS for s in SCENARIOS for bus in s.buses]


@pytest.mark.parametrize("sim,bus,scenario", CASES)
def test_bus_scenario(sim, bus, scenario):
    r, build_dir = runner.build_bus_once(sim, bus)
    xml = runner.run(r, build_dir, runner.BUS_SCENARIOS, testcase=scenario,
                     toplevel=runner.bus_top(bus)[1], extra_env=runner.bus_env(bus))
    runner.check(xml)
