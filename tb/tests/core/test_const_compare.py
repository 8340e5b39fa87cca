"""const_compare on Amaranth's simulator: ``above`` and ``at_most`` against Python's compares,
every value of every width up to 7 bits against every constant from -1 to 2**width.

Cycle conventions: ``block_sim.py``.
"""

import pytest
from amaranth.hdl import Cat, Elaboratable, Module, Signal

from bissmaster.core.const_compare import above, at_most

from testkit.block_sim import simulate


@pytest.mark.parametrize("width", range(1, 8))
def test_above_and_at_most_match_the_compares(width):
    constants = list(range(-1, 2**width + 1))

    class Compares(Elaboratable):
        def __init__(self):
            self.value = Signal(width)
            self.above = Signal(len(constants))
            self.at_most = Signal(len(constants))

        def elaborate(self, platform):
            m = Module()
            m.d.comb += [self.above.eq(Cat(above(self.value, k) for k in constants)),
                         self.at_most.eq(Cat(at_most(self.value, k) for k in constants))]
            return m

    dut = Compares()
    got = {}

    async def tb(ctx):
        for v in range(2**width):
            ctx.set(dut.value, v)
            got[v] = (ctx.get(dut.above), ctx.get(dut.at_most))
            await ctx.tick()

    simulate(dut, tb)
    for v, (gt, le) in got.items():
        assert [gt >> i & 1 for i in range(len(constants))] == [int(v > k) for k in constants], v
        assert [le >> i & 1 for i in range(len(constants))] == [int(v <= k) for k in constants], v
