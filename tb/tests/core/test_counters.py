"""SaturatingCounter and CounterBank on Amaranth's simulator: counts, saturates, clear wins;
in the bank each event counts only its own counter.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.counters import CounterBank, SaturatingCounter
from master_contract import COUNTERS

from testkit.block_sim import run_clocks, simulate


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


# -- CounterBank ---------------------------------------------------------------------------------

#: The bank's register stage: a count changes this many clocks after its event or clear.
LAG = 1


def _bank(names, width, steps):
    """Drive ``events`` (a dict per clock) and ``clear``; returns the counts per clock, each the
    value ``LAG`` clocks after the edge that ended the step's clock."""
    trace = run_clocks(CounterBank(names, width),
                       [{**{f"events.{n}": e.get(n, 0) for n in names}, "clear": c}
                        for e, c in steps + [({}, 0)] * (1 + LAG)],
                       [f"counts.{n}" for n in names])
    return [{n: x[f"counts.{n}"] for n in names} for x in trace[1 + LAG:]]


def test_counter_bank_counts_one_clock_after_the_event_and_the_clear():
    # Read in the clocks themselves: nothing changes at the edge that ends the event's (or the
    # clear's) clock, the count does at the next.
    trace = run_clocks(CounterBank(COUNTERS[:1], 4),
                       [{"events." + COUNTERS[0]: e, "clear": c}
                        for e, c in [(1, 0), (0, 0), (0, 0), (0, 1), (0, 0), (0, 0)]],
                       ["counts." + COUNTERS[0]])
    assert [row["counts." + COUNTERS[0]] for row in trace] == [0, 0, 1, 1, 1, 0]


@pytest.mark.parametrize("name", COUNTERS)
def test_counter_bank_event_counts_only_its_own_counter(name):
    width = 3
    counts = _bank(COUNTERS, width, [({name: 1}, 0)] * 3 + [({}, 0)] * 2)
    assert [c[name] for c in counts] == [1, 2, 3, 3, 3]
    assert all(c[other] == 0 for c in counts for other in COUNTERS if other != name)


def test_counter_bank_random_clear_overrides_saturates():
    width = 3
    names = COUNTERS[:5]
    rng = random.Random(6001)
    steps = [({n: int(rng.random() < 0.5) for n in names}, int(rng.random() < 0.03))
             for _ in range(400)]
    # A clear in the same clock as every event: the clear wins.
    steps[50] = ({n: 1 for n in names}, 1)
    got = _bank(names, width, steps)
    count = dict.fromkeys(names, 0)
    for (events, clear), row in zip(steps, got):
        for n in names:
            count[n] = 0 if clear else min(count[n] + events[n], 2**width - 1)
        assert row == count
    assert got[50] == dict.fromkeys(names, 0)
    assert sum(row[n] == 2**width - 1 for row in got for n in names) > 100
