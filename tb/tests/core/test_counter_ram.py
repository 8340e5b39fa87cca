"""CounterRam on Amaranth's simulator: counters in a memory, against a reference of its
documented contract (the class docstring; docs/ports.md, Counters).

The contract, as tested here: a read issued in cycle ``r`` (``read_en``, ``read_addr``) returns
in cycle ``r + 1`` each slot's events of the cycles up to ``r - 4`` at most, and of every cycle
up to ``r - SETTLE`` at least (the words take turns, one per cycle, so an event lands between
the two bounds by its word's turn, and each bound is reached), counted since the last clear (a
clear drops the events of its own cycle) and saturating; from ``SETTLE`` cycles after a clear,
no count from before it is seen; from ``words + 2`` cycles after a reset's, every count is 0.
``busy`` is high from the cycle after an event or a clear up to ``SETTLE`` cycles after it (low
from then, if nothing else came), and for ``words + 1`` cycles after power-up. Counts never fall
except at a clear, and no event is lost however fast they come.

Cycle conventions: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.counter_ram import CounterRam

from testkit.block_sim import simulate_with_reset

#: Sixteen counters, two per word, one slot left without a counter (it must read 0).
SLOTS = tuple(f"c{i}" for i in range(15)) + (None,)
NAMES = [s for s in SLOTS if s is not None]
WORDS = len(SLOTS) // 2
#: A read issued this many cycles after an event's cycle returns it in any case (docs/ports.md,
#: Counters: "words + 3"); one issued 4 cycles after it may.
SETTLE = WORDS + 3
EARLIEST = 4


def reference(events, clears, t, width, slot):
    """Slot ``slot``'s count from the events of cycles up to ``t``, since the last clear."""
    last_clear = max((c for c in range(t + 1) if clears[c]), default=-1)
    n = sum(events[c].get(slot, 0) for c in range(last_clear + 1, t + 1))
    return min(n, 2**width - 1)


def run(events, clears, width=16, slots=SLOTS, reads=None, resets=(), busy=None):
    """Drive ``events`` (one dict per cycle: name -> 1) and ``clears`` (one bool per cycle);
    each cycle issue a read (``reads[t]``: a word, default the words in turn). Returns
    ``[(cycle issued, word, data)]``; ``busy``, a list, gets ``busy`` of each cycle."""
    dut = CounterRam(slots, width)
    words = (len(slots) + 1) // 2
    reads = reads or [t % words for t in range(len(events))]
    got = []

    async def tb(ctx, rst):
        issued = None
        for t, (ev, clear) in enumerate(zip(events, clears)):
            for name in (s for s in slots if s is not None):
                ctx.set(dut.events[name], ev.get(name, 0))
            ctx.set(dut.clear, clear)
            ctx.set(rst, t in resets)
            ctx.set(dut.read_en, 1)
            ctx.set(dut.read_addr, reads[t])
            if issued is not None:
                got.append((*issued, ctx.get(dut.read_data)))
            issued = (t, reads[t])
            if busy is not None:
                busy.append(ctx.get(dut.busy))
            await ctx.tick()

    simulate_with_reset(dut, tb)
    return got


def halves(data):
    return data & 0xFFFF, data >> 16


def check_bounds(got, events, clears, width, slots=SLOTS):
    """Every read against the reference bounds, but those close after a clear (or the reset's
    sweep). Returns the number of counts checked."""
    n, checked = len(slots), 0
    words = (n + 1) // 2
    for r, word, data in got:
        if any(clears[max(0, r - SETTLE):r + 1]) or r < SETTLE:
            continue
        for half, value in zip((0, 1), halves(data)):
            s = 2 * word + half
            name = slots[s] if s < n else None
            if name is None:
                assert value == 0, (r, s, value)
                continue
            hi = reference(events, clears, r - EARLIEST, width, name)
            lo = reference(events, clears, r - SETTLE, width, name)
            assert lo <= value <= hi, (r, name, lo, value, hi)
            checked += 1
    return checked


def test_one_event_is_read_within_the_bounds_at_every_phase():
    """A lone event at each of WORDS successive cycles (every phase of the turns): it is read
    from somewhere in [t0 + EARLIEST, t0 + SETTLE] on, never before, and both ends occur."""
    for name in ("c0", "c7", "c14"):
        s = NAMES.index(name)
        delays = set()
        for t0 in range(30, 30 + WORDS):
            events = [{} for _ in range(60)]
            events[t0] = {name: 1}
            got = run(events, [0] * 60, reads=[s // 2] * 60)
            value = {r: halves(d)[s % 2] for r, _, d in got}
            first = min(r for r in value if value[r] == 1)
            assert all(value[r] == (r >= first) for r in value), (name, t0)
            assert t0 + EARLIEST <= first <= t0 + SETTLE, (name, t0, first)
            delays.add(first - t0)
        assert min(delays) == EARLIEST and max(delays) == SETTLE, (name, sorted(delays))


def test_every_counter_every_cycle_loses_nothing():
    """All 15 counters strobe in every cycle for 200 cycles: each counts 200 exactly."""
    events = [{name: 1 for name in NAMES} for _ in range(200)] + [{} for _ in range(40)]
    got = run(events, [0] * 240)
    last = {}
    for r, word, data in got:
        for half, value in zip((0, 1), halves(data)):
            last[2 * word + half] = value
    assert [last[s] for s in range(15)] == [200] * 15
    assert last[15] == 0
    assert check_bounds(got, events, [0] * 240, 16) > 400


def test_saturates_at_the_width():
    width = 3
    events = [{"c1": 1, "c2": t % 3 == 0} for t in range(60)] + [{} for _ in range(30)]
    got = run(events, [0] * 90, width=width)
    final = halves(got[-1][2] if got[-1][1] == 1 else [d for _, w, d in got if w == 1][-1])
    assert final == (7, 0)                   # c2, c3 in word 1: c2 saturated, c3 never counted
    word0 = [d for _, w, d in got if w == 0][-1]
    assert halves(word0) == (0, 7)           # c0 never, c1 saturated
    check_bounds(got, events, [0] * 90, width)


@pytest.mark.parametrize("seed", range(6))
def test_random_events_and_clears_against_the_reference(seed):
    rng = random.Random(7100 + seed)
    cycles = 1500
    rate = rng.choice((0.002, 0.02, 0.2, 0.7)) if seed else 0.002
    events = [{name: 1 for name in NAMES if rng.random() < rate} for _ in range(cycles)]
    clears = [int(rng.random() < 0.01) for _ in range(cycles)]
    width = rng.choice((3, 5, 16))
    busy = []
    got = run(events, clears, width=width, busy=busy)
    assert check_bounds(got, events, clears, width) > 1500
    # Not busy: a read returns every event before its clock (after a clear, only those after).
    idle = 0
    for r, word, data in got:
        if not busy[r] and r > 0:
            for half, value in zip((0, 1), halves(data)):
                name = SLOTS[2 * word + half]
                want = reference(events, clears, r - 1, width, name) if name else 0
                assert value == want, (r, name, value, want)
            idle += 1
    assert rate > 0.01 or idle > 300


def test_busy_falls_once_the_events_are_written():
    events = [{} for _ in range(50)]
    events[20] = {name: 1 for name in NAMES}
    busy = []
    run(events, [0] * 50, busy=busy)
    # after power-up: the memory being zeroed, a word per cycle
    assert busy[:WORDS + 1] == [1] * (WORDS + 1) and busy[WORDS + 1] == 0
    assert busy[20] == 0 and busy[21] == 1        # quiet, then the event taken
    assert busy.index(0, 21) == 20 + SETTLE, busy
    assert not any(busy[20 + SETTLE:])


def test_a_clear_drops_the_events_of_its_cycle_and_keeps_those_after():
    events = [{name: 1 for name in NAMES} for _ in range(40)] + [{} for _ in range(40)]
    clears = [0] * 80
    clears[20] = 1
    got = run(events, clears)
    final = {}
    for _, word, data in got:
        final[2 * word], final[2 * word + 1] = halves(data)
    # 19 events after the clear's cycle (21..39).
    assert [final[s] for s in range(15)] == [19] * 15
    check_bounds(got, events, clears, 16)


def test_reset_zeroes_the_memory():
    events = [{name: 1 for name in NAMES} for _ in range(30)] + [{} for _ in range(60)]
    got = run(events, [0] * 90, resets=(50,))
    before = {2 * w + h: v for r, w, d in got if r == 49 or r == 49 - 1 or r < 50
              for h, v in zip((0, 1), halves(d))}
    assert before[0] == 30
    after = [halves(d) for r, _, d in got if r >= 50 + WORDS + 2]
    assert after and all(v == (0, 0) for v in after)


@pytest.mark.filterwarnings("ignore::amaranth.hdl.UnusedElaboratable")
def test_configuration_errors():
    with pytest.raises(ValueError, match="1 to 16 bits"):
        CounterRam(SLOTS, 17)
    with pytest.raises(ValueError, match="repeat"):
        CounterRam(("a", "a"), 4)
