"""What the block tests (``test_<block>.py``) share: running a testbench, and the conventions.

Not a test module: each ``test_<block>.py`` imports it as a sibling (pytest puts the test
file's folder on ``sys.path``).

Conventions used throughout
---------------------------
Every testbench runs the same loop per system clock: set the inputs for the clock, read the
outputs, ``await ctx.tick()``. "Cycle ``t``" is the stretch after the ``t``-th clock edge, so a
registered output read in cycle ``t`` is what the edge that *ended* cycle ``t - 1`` stored, and a
combinational output read in cycle ``t`` already reflects the inputs set for cycle ``t``. An input
set in cycle ``t`` is what the edge ending cycle ``t`` samples.

The expected values are never taken from the RTL: they come from docs/protocol.md
(``docs/protocol.md``), from the independent encoder model in ``tb/encoder_model``,
from ``tb/master_contract.py`` (the documented codes), or from the small reference functions in
the test files. The RTL is imported only for the blocks under test and ``MasterParams`` (and
the ``Crc`` names it takes) to build them.
"""

import pytest
from amaranth.hdl import ClockDomain, Elaboratable, Module
from amaranth.lib import data
from amaranth.sim import Simulator

#: The slave's Start bit is a 1 (docs/protocol.md, section 2).
START_BIT = 1

CLOCK_PERIOD_S = 1e-8


def simulate(dut, testbench):
    """Run ``testbench`` (an async ``ctx`` function) against ``dut`` on one clock.

    The ``sync`` domain is made at the top, so that a purely combinational block runs the same
    way (one clock per testbench step)."""
    top = Module()
    top.domains.sync = ClockDomain()
    top.submodules.dut = dut
    sim = Simulator(top)
    sim.add_clock(CLOCK_PERIOD_S)
    sim.add_testbench(testbench)
    sim.run()


def simulate_with_reset(dut, testbench):
    """As :func:`simulate`, for a testbench that drives the ``sync`` domain's reset as well:
    it is called as ``testbench(ctx, rst)``."""
    top = Module()
    top.domains.sync = sync = ClockDomain()
    top.submodules.dut = dut
    sim = Simulator(top)
    sim.add_clock(CLOCK_PERIOD_S)

    async def bench(ctx):
        await testbench(ctx, sync.rst)

    sim.add_testbench(bench)
    sim.run()


def member(obj, path):
    """The member of a component or view at a dotted path: ``"live.w0.data_bits"``, ``"words.1"``."""
    for name in path.split("."):
        obj = obj[int(name)] if name.isdigit() else getattr(obj, name)
    return obj


def _settable(obj, value):
    # A whole struct set from an int is set bit for bit (see ``pack``).
    if isinstance(obj, data.View) and isinstance(value, int):
        return obj.as_value()
    return obj


def run_clocks(dut, steps, outputs, *, defaults=None):
    """Drive ``dut`` for one clock per step, and read ``outputs`` in every clock.

    A step is a dict ``{input path: value}`` (paths as for :func:`member`); in each clock the
    inputs of ``defaults`` are set first, then the step's, then every path of ``outputs`` is read
    (a struct as its raw bits, an enum as its integer code), then the clock ticks. Returns one
    ``{path: value}`` per clock.
    """
    trace = []

    async def tb(ctx):
        held = {}
        for step in steps:
            for path, value in {**(defaults or {}), **step}.items():
                if path not in held or held[path] != value:     # set only what changes
                    obj = member(dut, path)
                    ctx.set(_settable(obj, value), value)
                    held[path] = value
            row = {}
            for path in outputs:
                obj = member(dut, path)
                row[path] = int(ctx.get(obj.as_value() if isinstance(obj, data.View) else obj))
            trace.append(row)
            await ctx.tick()

    simulate(dut, tb)
    return trace


def unpack(layout, value):
    """The fields of the raw bits ``value`` of a struct layout, as nested dicts of ints."""
    out = {}
    for name, fld in layout:
        bits = (value >> fld.offset) & ((1 << fld.width) - 1)
        out[name] = unpack(fld.shape, bits) if isinstance(fld.shape, data.StructLayout) else bits
    return out


def pack(layout, values):
    """The raw bits of nested dicts of ints (missing fields 0) for a struct layout."""
    raw = 0
    for name, fld in layout:
        if isinstance(fld.shape, data.StructLayout):
            value = pack(fld.shape, values.get(name, {}))
        else:
            value = values.get(name, 0)
        raw |= (value & ((1 << fld.width) - 1)) << fld.offset
    return raw


def protocol_clocks(microseconds, clk_hz):
    """A protocol time in whole system clocks, rounded up (the defaults: 40 us, 80 us)."""
    return -(-microseconds * clk_hz // 1_000_000)


def refused(make, message):
    """``make()`` raises ValueError(``message``). The components whose constructor raised (the
    ``self`` of each frame of the traceback: a top, and a part it was building) were never
    meant to be elaborated: Amaranth's per-object switch silences their UnusedElaboratable
    warning, which they would give when collected."""
    with pytest.raises(ValueError, match=message) as info:
        make()
    tb = info.value.__traceback__
    while tb is not None:
        obj = tb.tb_frame.f_locals.get("self")
        if isinstance(obj, Elaboratable):
            obj._MustUse__silence = True
        tb = tb.tb_next
