"""SlotNoise alone: the noise judgement of the sampler's slots, against a slot-level reference
written from its documented rules (docs/ports.md, Noise; the class docstring).

Each slot takes 8 clocks: its first vote at clock 2, the centre at 4, the decision (third
vote) at 6 (a clock between the votes, as the sampler has at a half period of 4 or more).
The line is a list of levels, one per clock; the votes are the line's levels at those clocks,
as the sampler would take them. ``clear`` (the Ack edge: the line low from
there on) is clock 0.
"""

import random

import pytest

from bissmaster.core.slot_noise import SlotNoise

from testkit.block_sim import simulate

SLOT = 8
FIRST, CENTRE, THIRD = 2, 4, 6


def reference(line, n_slots):
    """Per slot: reported (a noise strobe) or not, from the rules on whole slots."""
    reported, last_dec, last_third, last_reported = [], 0, 0, False
    for k in range(n_slots):
        b = 1 + k * SLOT
        v1, v2, v3 = line[b + FIRST], line[b + CENTRE], line[b + THIRD]
        dec = int(v1 + v2 + v3 >= 2)
        span_start = 1 if k == 0 else b - SLOT + CENTRE + 1        # after the last centre
        edges = sum(line[t] != line[t - 1] for t in range(span_start, b + CENTRE + 1))
        odd = ((v1 == v3 != v2)                                    # the centre against both
               or (v1 != dec and last_dec == dec)                  # a change at the start, not
               or (last_third != last_dec and last_dec == dec)     # the slot before's end
               or edges >= 2)                                      # two edges in one span
        report = odd and not last_reported
        reported.append(report)
        last_dec, last_third, last_reported = dec, v3, report
    return reported


def run(line, n_slots, *more):
    """The reports of SlotNoise for a frame's line (its clock 0 the Ack edge, ``clear``); more
    frames (``line, n_slots`` pairs) follow in the same simulation, each with its own clear."""
    dut = SlotNoise()
    frames = [(line, n_slots)] + list(zip(more[::2], more[1::2]))
    strobes = []

    async def tb(ctx):
        for line, n_slots in frames:
            v1 = v2 = 0
            for t, level in enumerate(line):
                k, phase = divmod(t - 1, SLOT)
                in_frame = t >= 1 and k < n_slots
                v1 = level if in_frame and phase == FIRST else v1
                v2 = level if in_frame and phase == CENTRE else v2
                decided = in_frame and phase == THIRD
                ctx.set(dut.level, level)
                ctx.set(dut.edge, t > 0 and level != line[t - 1])
                ctx.set(dut.clear, t == 0)
                ctx.set(dut.centre, in_frame and phase == CENTRE)
                ctx.set(dut.decided, decided)
                ctx.set(dut.vote1, v1)
                ctx.set(dut.vote2, v2)
                ctx.set(dut.majority, int(v1 + v2 + level >= 2))
                odd = ctx.get(dut.odd)
                assert not odd or decided, f"a strobe off a decision at clock {t}"
                if decided:
                    strobes.append(bool(odd))
                await ctx.tick()

    simulate(dut, tb)
    return strobes


def clean_line(rng, n_slots):
    """Data bits whose changes fall anywhere after one centre and up to the next (one edge per
    span at most), drawn again until every slot's votes decide its bit: what jitter can do to
    a clean line read right."""
    while True:
        bits = [rng.randrange(2) for _ in range(n_slots)]
        line = [0] * (1 + n_slots * SLOT + 2)  # low from the Ack edge (clock 0) on
        for k in range(n_slots):
            b = 1 + k * SLOT
            change = b - SLOT + CENTRE + 1 + rng.randrange(SLOT) if k else b + rng.randrange(
                CENTRE + 1)
            for t in range(max(1, change), len(line)):
                line[t] = bits[k]
        votes = [[line[1 + k * SLOT + p] for p in (FIRST, CENTRE, THIRD)] for k in range(n_slots)]
        if all(int(sum(v) >= 2) == bit for v, bit in zip(votes, bits)):
            return line


@pytest.mark.parametrize("seed", range(20))
def test_a_clean_line_is_never_reported(seed):
    rng = random.Random(seed)
    n = 12
    line = clean_line(rng, n)
    assert reference(line, n) == [False] * n       # the rules themselves pass a clean line
    assert run(line, n) == [False] * n


@pytest.mark.parametrize("seed", range(60))
def test_glitched_lines_are_judged_as_the_rules_say(seed):
    """Clean lines with 1..4 glitches of 1..4 clocks anywhere: every slot's report as the
    slot-level reference gives it; some seeds give reports, some not (checked overall)."""
    rng = random.Random(1000 + seed)
    n = 10
    line = clean_line(rng, n)
    for _ in range(rng.randint(1, 4)):
        at, width = rng.randrange(2, len(line) - 1), rng.randint(1, 4)
        for t in range(at, min(at + width, len(line))):
            line[t] ^= 1
    assert run(line, n) == reference(line, n)


def test_the_glitched_cases_do_report():
    """The random cases above are not all quiet: most seeds report something, and a run of
    odd slots reports every other one."""
    reporting = 0
    for seed in range(60):
        rng = random.Random(1000 + seed)
        line = clean_line(rng, 10)
        for _ in range(rng.randint(1, 4)):
            at, width = rng.randrange(2, len(line) - 1), rng.randint(1, 4)
            for t in range(at, min(at + width, len(line))):
                line[t] ^= 1
        reporting += any(reference(line, 10))
    assert reporting >= 30
    # The centre vote inverted in every slot of an all-low line: each slot is odd, every other
    # one reported.
    line = [0] * (1 + 4 * SLOT + 2)
    for k in range(4):
        line[1 + k * SLOT + CENTRE] = 1
    assert reference(line, 4) == [True, False, True, False]
    assert run(line, 4) == [True, False, True, False]


def test_clear_starts_a_new_frame():
    """After ``clear`` the slot before counts as decided low and not reported, and the edges
    before it are forgotten: a frame that reported in its last slot, then a frame whose first
    slot is odd, reports again there; a frame ending high (the slot before decided 1) does not
    make the next frame's low first slot look like a change."""
    first = [0] * (1 + 2 * SLOT + 2)
    first[1 + SLOT + CENTRE] = 1                   # slot 1's centre odd: reported
    second = [0] * (1 + SLOT + 2)
    second[1 + CENTRE] = 1                         # slot 0's centre odd
    assert run(first, 2, second, 1) == [False, True, True]
    high = [0] * (1 + 1 + FIRST) + [1] * (2 * SLOT)    # slots 0 and 1 high to the end
    low = [0] * (1 + SLOT + 2)
    assert reference(high, 2) == [False, False] and reference(low, 1) == [False]
    assert run(high, 2, low, 1) == [False, False, False]
