"""SaturatingCounter on Amaranth's simulator: counts, saturates, clear wins.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

from bissmaster.counters import SaturatingCounter

from block_sim import simulate


def test_saturating_counter_counts_saturates_and_clear_wins():
    width = 3
    rng = random.Random(6000)
    ops = ([(1, 0)] * 5 + [(0, 0)] * 2 + [(1, 0)] * 6 + [(1, 1)] + [(1, 0)] * 3 + [(0, 1)]
           + [(rng.randrange(2), int(rng.random() < 0.05)) for _ in range(300)])
    dut = SaturatingCounter(width)
    got = []

    async def tb(ctx):
        for inc, clear in ops:
            ctx.set(dut.inc, inc)
            ctx.set(dut.clear, clear)
            await ctx.tick()
            got.append(ctx.get(dut.count))

    simulate(dut, tb)
    count, expected = 0, []
    for inc, clear in ops:
        count = 0 if clear else min(count + inc, (1 << width) - 1)
        expected.append(count)
    assert got == expected
    # By hand: 1..5, 5, 5, 6, 7 x5 (saturated), clear with inc -> 0, 1, 2, 3, clear -> 0.
    assert got[:18] == [1, 2, 3, 4, 5, 5, 5, 6, 7, 7, 7, 7, 7, 0, 1, 2, 3, 0]
    assert got.count(7) > 10


