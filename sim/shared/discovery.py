"""Which cocotb scenarios a scenario module holds, and where each must run, read from its source.

pytest (sim/test_regression.py, sim/test_campaigns.py) runs one simulator process per scenario.
It finds the scenarios by parsing the module with :mod:`ast`, without importing it (a scenario
module imports cocotb and expects a simulator): every top-level function decorated with
``@cocotb.test`` is a scenario. A scenario that needs something other than the default build
at the default clock says so with a marker right under ``@cocotb.test()``:

    @cocotb.test()
    @only_on_builds("biss-c", "biss-c-lean")     # bissmaster.generate presets, generated then
    async def biss_c_only_build(dut): ...

    @cocotb.test()
    @also_at_fast_clock                          # once more on Verilator at FAST_CLK_HZ
    async def edge_jitter(dut): ...

    @cocotb.test()
    @long_on_icarus                              # on Icarus only in make sim-long, not make test
    async def bp3_lengths(dut): ...

    @cocotb.test()
    @full_in_sim_long(200_000_000)               # make test: a subset at this clock (Verilator);
    async def safety_and_biss_c_presets(dut): ...   # the whole (BISS_FULL=1) in make sim-long

    @cocotb.test()
    @expected_to_fail("issue 12: ...")           # fails on today's core; pytest xfail, strict
    async def glitch_in_the_ack(dut): ...

The markers change nothing when the simulator runs the function; only this reader sees them, so
their arguments must be literals.
"""

import ast
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_BUILD = "default"
#: The same Verilog at another system clock (the core's times are all in clocks): 200 MHz gives
#: 10..400 clocks per MA half period over the five MA rates.
FAST_CLK_HZ = 200_000_000


def only_on_builds(*presets):
    """Marker: run this scenario on these ``bissmaster.generate`` presets, not the default build."""
    def mark(func):
        return func
    return mark


def only_on_buses(*buses):
    """Marker (bus scenarios, sim/scenarios/bus.py): run on these bus tops only ("axil", "wb")
    instead of both."""
    def mark(func):
        return func
    return mark


def also_at_fast_clock(func):
    """Marker: run this scenario a second time, on Verilator at :data:`FAST_CLK_HZ`."""
    return func


def long_on_icarus(func):
    """Marker: on Icarus this scenario takes minutes and repeats what its Verilator run checks;
    its Icarus run carries the pytest mark ``long`` and runs in ``make sim-long``, not in
    ``make test``, which keeps within its time budget. Verilator runs it in both."""
    return func


def full_in_sim_long(*clocks_hz):
    """Marker: on Verilator at these system clocks, ``make test`` runs a subset of this
    scenario (the scenario reads :data:`FULL_ENV` and chooses; see its docstring for what the
    subset keeps); one more Verilator run at each clock with ``BISS_FULL=1`` runs the whole,
    with the pytest mark ``long``, in ``make sim-long``."""
    def mark(func):
        return func
    return mark


#: Set to "1" in the simulator's environment for the full run of a ``full_in_sim_long`` scenario.
FULL_ENV = "BISS_FULL"


def full_run():
    """In the simulator: True in the full run of a ``full_in_sim_long`` scenario (or whenever
    ``BISS_FULL=1`` is set by hand)."""
    import os
    return os.environ.get(FULL_ENV) == "1"


def expected_to_fail(reason):
    """Marker: the scenario fails on today's core for ``reason`` (an open issue): pytest runs it
    as a strict xfail, so it fails loudly once it passes (remove the marker with the fix)."""
    def mark(func):
        return func
    return mark


@dataclass(frozen=True)
class Scenario:
    module: str                         # dotted name, as the simulator imports it
    name: str                           # the cocotb test (runner.run's ``testcase``)
    builds: tuple = (DEFAULT_BUILD,)
    fast_clock: bool = False
    xfail: str | None = None            # expected_to_fail's reason
    buses: tuple = ("axil", "wb")       # bus scenarios: the bus tops to run on
    long_on_icarus: bool = False        # Icarus run only in make sim-long
    full_clocks: tuple = ()             # full_in_sim_long: the whole at these clocks (sim-long)


def pytest_marks(scenario, sim):
    """The pytest marks of ``scenario``'s run on ``sim``, for every pytest entry (regression,
    bus tops, driver): a strict xfail for ``expected_to_fail`` (passing fails the run), and the
    mark ``long`` on the Icarus run of a ``long_on_icarus`` scenario (make test: ``-m 'not
    long'``, make sim-long: ``-m long``)."""
    import pytest       # here, not at the top: the simulator imports this module too
    out = [pytest.mark.xfail(strict=True, reason=scenario.xfail)] if scenario.xfail else []
    if scenario.long_on_icarus and sim == "icarus":
        out.append(pytest.mark.long)
    return out


def _dotted(node):
    """``cocotb.test`` for the decorator ``@cocotb.test()`` or ``@cocotb.test``."""
    if isinstance(node, ast.Call):
        return _dotted(node.func)
    if isinstance(node, ast.Attribute):
        return f"{_dotted(node.value)}.{node.attr}"
    return node.id if isinstance(node, ast.Name) else ""


def scenarios(module):
    """Every ``@cocotb.test`` function of ``module`` (dotted, under the repository root), in
    source order."""
    tree = ast.parse((ROOT / (module.replace(".", "/") + ".py")).read_text())
    found = []
    for node in tree.body:
        if not isinstance(node, (ast.AsyncFunctionDef, ast.FunctionDef)):
            continue
        marks = {_dotted(d): d for d in node.decorator_list}
        if "cocotb.test" not in marks:
            continue
        builds = (DEFAULT_BUILD,)
        if "only_on_builds" in marks:
            builds = tuple(ast.literal_eval(a) for a in marks["only_on_builds"].args)
        xfail = None
        if "expected_to_fail" in marks:
            xfail = ast.literal_eval(marks["expected_to_fail"].args[0])
        buses = Scenario.buses
        if "only_on_buses" in marks:
            buses = tuple(ast.literal_eval(a) for a in marks["only_on_buses"].args)
        full_clocks = ()
        if "full_in_sim_long" in marks:
            full_clocks = tuple(ast.literal_eval(a) for a in marks["full_in_sim_long"].args)
        found.append(Scenario(module, node.name, builds, "also_at_fast_clock" in marks, xfail,
                              buses, "long_on_icarus" in marks, full_clocks))
    if not found:
        raise ValueError(f"{module} has no @cocotb.test function")
    return found
