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

The expected values are never taken from the RTL: they come from the protocol digest
(``shared/spec/biss-protocol.md``), from the independent encoder model in ``tb/encoder_model``,
from ``tb/master_contract.py`` (the documented codes), or from the small reference functions in
the test files. The RTL is imported only for the blocks under test and ``MasterParams`` (and
the ``Crc`` names it takes) to build them.
"""

from amaranth.sim import Simulator

#: The slave's Start bit is a 1 (protocol digest, section 2).
START_BIT = 1

CLOCK_PERIOD_S = 1e-8


def simulate(dut, testbench):
    """Run ``testbench`` (an async ``ctx`` function) against ``dut`` on one clock."""
    sim = Simulator(dut)
    sim.add_clock(CLOCK_PERIOD_S)
    sim.add_testbench(testbench)
    sim.run()
