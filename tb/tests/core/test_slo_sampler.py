"""SloSampler on Amaranth's simulator: line-delay measurement, mid-bit samples, glitches.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

import pytest
from amaranth.hdl import Module, ResetInserter, Signal

from bissmaster.params import MasterParams
from bissmaster.core.slo_sampler import SloSampler

from testkit.block_sim import CLOCK_PERIOD_S, START_BIT, simulate

# Timing reference. Cycle ``r`` is the cycle in which the master's MA is high for the second time
# (``arm`` strobes in it). The Ack falling edge "appears at clock r + d" means the sampler's
# ``slo`` input reads 1 in cycle r + d - 1 and 0 from cycle r + d on.
#
# Expected delay: in the real core ``slo`` comes out of a 2-flop FFSynchronizer. MA changes just
# after the edge that starts cycle r; say the true round trip (MA pin -> SLO pin) is T clocks,
# not an integer. The first flop captures the low level at the first edge at or after r + T,
# which starts cycle r + ceil(T); the second flop shows it one cycle later, r + ceil(T) + 1.
# So d = ceil(T) + 1 and the compensated delay is d - 1 = ceil(T): T <= delay < T + 1, as the
# module promises. The one flop of latency that is a whole clock is SYNC_LATENCY = 1; the
# first flop's sub-clock uncertainty stays in the result. Hence: delay == d - 1, and d = 1 (the
# fastest possible: SLO low in the cycle right after arm) reports 0.
# (In a purely synchronous simulation where the pin changes right after an edge, T is an integer
# and the first flop samples the old level at r + T, giving delay = T + 1: the "< T + 1" bound is
# open only for asynchronous edges.)
#
# Slots: slot k spans cycles r + d + 2*hp*k .. r + d + 2*hp*(k + 1) - 1; slot 0 is inside the
# Ack. Its middle is hp clocks after the slot start: cycle r + d + hp + 2*hp*k. The slot is
# decided by three votes, v clocks before the middle, at it and v clocks after it, and the
# decision (the ``sample`` strobe) comes with the third: cycle r + d + hp + 2*hp*k + v, where
# v = hp // 2 for hp >= 3 and 0 (one sample) for hp = 2 (docs/ports.md, "Noise immunity").

#: The synchronizer's whole clock of latency that the sampler subtracts (see above).
SYNC_LATENCY = 1


def vote_spacing(hp):
    """Clocks between a slot's votes (docs/ports.md): a quarter bit, none at hp = 2."""
    return hp // 2 if hp >= 3 else 0
SAMPLER_HALF_PERIODS = (2, 3, 5, 10)
SAMPLER_DELAY_WIDTH = MasterParams().delay_width


class DelayedEncoder:
    """SLO as the sampler sees it: high, Ack edge at relative cycle d, then 2*hp-clock slots."""

    def __init__(self, hp, d, slots, *, after=1, glitches=(), low_before=False):
        self.hp, self.d, self.slots, self.after = hp, d, list(slots), after
        self.glitches = set(glitches)
        self.low_before = low_before

    def level(self, c):
        """SLO in cycle r + c."""
        if c < self.d:
            if self.low_before:
                return 0
            return 0 if c in self.glitches else 1
        k = (c - self.d) // (2 * self.hp)
        return self.slots[k] if k < len(self.slots) else self.after

    def sample_cycles(self):
        """The decision of every slot: its third vote."""
        return [self.d + self.hp + 2 * self.hp * k + vote_spacing(self.hp)
                for k in range(len(self.slots))]


def _sampler_sim(width, hp, scenarios, *, extra=0, half_period_width=None):
    """Run scenarios [(encoder, cycles)] back to back, reset in between (as the master does).
    ``half_period_width``: a build with a narrower half-period setting (default: the default
    build's).

    Returns one trace per scenario: per relative cycle c = 0 (arm) .. cycles-1, a dict of outputs.
    """
    narrow = {} if half_period_width is None else {"half_period_width": half_period_width}
    sampler = SloSampler(width, synchronizer=False, **narrow)
    rst = Signal()
    top = ResetInserter(rst)(sampler)
    traces = []

    async def tb(ctx):
        ctx.set(sampler.half_period, hp)
        for enc, cycles in scenarios:
            ctx.set(rst, 1)
            ctx.set(sampler.arm, 0)
            ctx.set(sampler.slo, 1 if not enc.low_before else 0)
            await ctx.tick()
            ctx.set(rst, 0)
            for c in (-2, -1):
                ctx.set(sampler.slo, enc.level(c))
                await ctx.tick()
            trace = []
            for c in range(cycles + extra):
                ctx.set(sampler.arm, int(c == 0))
                ctx.set(sampler.slo, enc.level(c))
                trace.append({
                    "sample": ctx.get(sampler.sample), "bit": ctx.get(sampler.bit),
                    "delay": ctx.get(sampler.delay), "locked": ctx.get(sampler.locked),
                    "early": ctx.get(sampler.early), "noise": ctx.get(sampler.noise),
                })
                await ctx.tick()
            traces.append(trace)

    simulate(top, tb)
    return traces


def _samples(trace):
    return [(c, x["bit"]) for c, x in enumerate(trace) if x["sample"]]


def _random_slots(rng, n_data):
    acks = rng.randint(1, 3)
    return [0] * acks + [START_BIT] + [rng.randrange(2) for _ in range(n_data)]


def test_slo_sampler_sync_extra_latency_is_one_flop():
    # See the timing reference above: the 2nd synchronizer flop is a whole clock. (The one place
    # a test reads an RTL constant: the constant is what is under test here.)
    from bissmaster.core.slo_sampler import SYNC_EXTRA_LATENCY
    assert SYNC_EXTRA_LATENCY == SYNC_LATENCY


@pytest.mark.parametrize("hp", SAMPLER_HALF_PERIODS)
def test_slo_sampler_delay_and_mid_bit_samples_for_delays_1_to_60(hp):
    rng = random.Random(2000 + hp)
    scenarios = []
    for d in range(1, 61):
        enc = DelayedEncoder(hp, d, _random_slots(rng, 5 if hp > 3 else 8))
        scenarios.append((enc, d + 2 * hp * len(enc.slots)))
    traces = _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)
    for (enc, cycles), trace in zip(scenarios, traces):
        d = enc.d
        where = f"hp={hp} d={d}"
        # One sample per slot, in the middle of each bit, reading the bit that was sent.
        expected = list(zip(enc.sample_cycles(), enc.slots))
        assert _samples(trace) == expected, where
        first = expected[0][0]
        assert [x["locked"] for x in trace] == [0] * (first + 1) + [1] * (cycles - first - 1), where
        assert all(x["delay"] == d - 1 for x in trace[d + 1:]), where
        assert trace[-1]["delay"] == d - SYNC_LATENCY, where
        assert not any(x["early"] for x in trace), where


@pytest.mark.parametrize("hp", (2, 3, 128, 255))
def test_slo_sampler_of_an_8_bit_half_period_build_up_to_its_longest_half_period(hp):
    """A build with ``half_period_width`` 8 (MasterParams; the slowest MA 100 MHz / 510): its
    setting holds half periods up to 255, and at each of them, the shortest and the longest,
    the delay and every slot's decision are as at any half period of the default build."""
    assert 2**8 - 1 == 255
    rng = random.Random(2100 + hp)
    scenarios = []
    for d in (1, 2, 37, 700):
        enc = DelayedEncoder(hp, d, _random_slots(rng, 4))
        scenarios.append((enc, d + 2 * hp * len(enc.slots)))
    traces = _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios, half_period_width=8)
    for (enc, cycles), trace in zip(scenarios, traces):
        where = f"hp={hp} d={enc.d}"
        assert _samples(trace) == list(zip(enc.sample_cycles(), enc.slots)), where
        assert trace[-1]["delay"] == enc.d - SYNC_LATENCY, where
        assert not any(x["noise"] or x["early"] for x in trace), where


def test_slo_sampler_early_when_slo_low_at_arm():
    hp = 3
    # d = 0: SLO low in the arm cycle itself (and before): it cannot be the Ack.
    low = DelayedEncoder(hp, 0, [0] * 8, after=0, low_before=True)
    # d = 1: the fastest legal edge, one cycle after arm: not early, delay 0.
    fast = DelayedEncoder(hp, 1, [0, 1, 0, 1])
    # Low at arm, then high, then a later edge: early stays set (the master faults on it).
    bounce = DelayedEncoder(hp, 6, [0, 1, 1], glitches=(-2, -1, 0))
    traces = _sampler_sim(SAMPLER_DELAY_WIDTH, hp, [(low, 40), (fast, 40), (bounce, 40)])
    t_low, t_fast, t_bounce = traces
    assert t_low[0]["early"] == 0                   # registered: visible after the arm edge
    assert all(x["early"] == 1 for x in t_low[1:])
    assert not any(x["sample"] or x["locked"] for x in t_low)   # SLO stuck low: no edge
    assert not any(x["early"] for x in t_fast)
    assert t_fast[-1]["delay"] == 0
    assert _samples(t_fast)[:4] == list(zip(fast.sample_cycles(), fast.slots))
    assert all(x["early"] == 1 for x in t_bounce[1:])


@pytest.mark.parametrize("hp", (2, 5))
def test_slo_sampler_glitch_before_slot0_sample_is_ignored(hp):
    # One-clock glitches, each high again long before its slot-0 sample (hp clocks after it);
    # the real Ack edge comes after that sample point. Delay and sample times follow the real edge.
    scenarios = []
    for g, d in ((1, 1 + hp + 1), (3, 3 + hp + 4), (2, 40)):
        enc = DelayedEncoder(hp, d, [0, 0, 1, 0, 1, 1, 0], glitches=(g,))
        scenarios.append((enc, d + 2 * hp * len(enc.slots)))
    # Two glitches before the real edge.
    enc = DelayedEncoder(hp, 30, [0, 1, 1, 0, 1], glitches=(2, 2 + hp + 2))
    scenarios.append((enc, 30 + 2 * hp * 5))
    for (enc, _), trace in zip(scenarios, _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)):
        assert _samples(trace) == list(zip(enc.sample_cycles(), enc.slots)), enc.glitches
        assert trace[-1]["delay"] == enc.d - 1
        assert all(x["locked"] == 0 for x in trace[:enc.sample_cycles()[0] + 1])
        assert not any(x["early"] for x in trace)


@pytest.mark.parametrize("hp", (3, 5))
def test_slo_sampler_glitch_then_real_edge_within_half_period_uses_real_edge(hp):
    """A one-clock low glitch, high again at once, then the real Ack edge before the glitch's
    slot-0 centre (once an RTL bug: the sampler locked on the glitch's timing, every later
    sample that many clocks early, at d = g + hp on the bit's first clock).

    The rise right after the glitch sends the sampler back to wait for an edge. If the high
    lasts more than v clocks (the vote spacing), the glitch cannot have been the edge: the real
    edge is used, exactly. If it lasts v clocks or less, one glitch right at the real edge
    explains the line both ways (a short low before it, or a short high after an edge at g):
    the edge is taken halfway between the two falls, at most v clocks early, and every slot is
    still decided right."""
    g = 4
    v = vote_spacing(hp)
    scenarios = []
    for d in range(g + 2, g + hp + 1):
        enc = DelayedEncoder(hp, d, [0, 0, 1, 1, 0, 1, 0], glitches=(g,))
        scenarios.append((enc, d + 2 * hp * len(enc.slots) + hp))
    for (enc, _), trace in zip(scenarios, _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)):
        where = f"glitch at {g}, real Ack edge at {enc.d}"
        high = enc.d - g - 1                        # clocks of high between the two falls
        edge = enc.d if high > v else g + (enc.d - g) // 2
        assert trace[-1]["delay"] == edge - 1, where
        assert 0 <= enc.d - edge <= v, where
        samples = _samples(trace)[:len(enc.slots)]
        assert [b for _, b in samples] == enc.slots, where
        assert [c for c, _ in samples] == [c - (enc.d - edge) for c in enc.sample_cycles()], where


def test_slo_sampler_never_locks_when_no_edge_comes():
    # (The sampler no longer has a ``saturated`` port; the master's Ack limit catches this.)
    width = 5
    hp = 2
    silent = DelayedEncoder(hp, 10_000, [0])
    trace, = _sampler_sim(width, hp, [(silent, 200)])
    assert not any(x["sample"] or x["locked"] or x["early"] for x in trace)
    assert all(x["delay"] == 0 for x in trace)


def test_slo_sampler_delay_counter_saturates_for_late_edges():
    width = 5
    top = (1 << width) - 1                      # 31: elapsed reaches it in cycle r + 31
    hp = 2
    late = (40, 41, 60, 200)
    scenarios = [(DelayedEncoder(hp, d, [0, 1, 0, 1, 1]), d + 2 * hp * 5)
                 for d in (top - 1, top) + late]
    traces = _sampler_sim(width, hp, scenarios)
    delays = [t[-1]["delay"] for t in traces]
    saturated = delays[2]
    assert delays[0] == top - 2                        # exact below the counter's end
    assert delays[1] in (top - 1, saturated)           # the last count: exact or saturated
    assert delays[2:] == [saturated] * len(late)       # every later edge: one saturated value
    assert saturated >= top - 1
    for (enc, _), trace in zip(scenarios, traces):      # sampling does not depend on the count
        assert _samples(trace) == list(zip(enc.sample_cycles(), enc.slots))


@pytest.mark.parametrize("max_line_delay", (30, 62, 4094))
def test_slo_sampler_edge_after_saturation_reads_beyond_max_line_delay(max_line_delay):
    """RTL bug (see report): MasterParams.delay_width promises that "a saturated count is out of
    range for every limit", but the sampler reports ``elapsed - SYNC_EXTRA_LATENCY``: when
    ``max_line_delay == 2**k - 2`` an Ack edge after the counter saturated reads exactly
    ``max_line_delay``, which passes the master's ``delay > delay_limit`` check."""
    width = MasterParams(max_line_delay=max_line_delay).delay_width
    hp = 2
    late = DelayedEncoder(hp, (1 << width) + 5, [0, 1, 0])
    trace, = _sampler_sim(width, hp, [(late, late.d + 2 * hp * 3)])
    assert trace[-1]["locked"] == 1
    assert trace[-1]["delay"] > max_line_delay




# -- The product configuration: SloSampler(width), the 2-flop synchronizer inside ------------------
#
# The pin is driven with sub-clock timing: the true round trip is T = p + f clocks (f strictly
# between 0 and 1) from the MA edge that starts the arm cycle, so the Ack edge reaches the pin a
# fraction f into cycle r + p, and every later slot edge 2*hp clocks after the one before. The
# same pin also drives a sampler without the synchronizer, for the comparison.

PIN_FRACTIONS = (0.1, 0.5, 0.9)


def _pin_sim(hp, scenarios):
    """Run scenarios [(encoder, cycles, f)] back to back, both samplers reset in between.

    The encoder's ``level(c)`` is the pin after the fraction f of cycle r + c (and so
    ``level(c - 1)`` before it). Returns one trace per scenario: per relative cycle, the pin after
    the fraction, and each sampler's outputs read after it."""
    product = SloSampler(SAMPLER_DELAY_WIDTH)
    bare = SloSampler(SAMPLER_DELAY_WIDTH, synchronizer=False)
    rst = Signal()
    top = Module()
    top.submodules.product = ResetInserter(rst)(product)
    top.submodules.bare = ResetInserter(rst)(bare)
    traces = []

    async def tb(ctx):
        def pin(level):
            ctx.set(product.slo, level)
            ctx.set(bare.slo, level)

        def read(dut):
            return {"sample": ctx.get(dut.sample), "bit": ctx.get(dut.bit),
                    "delay": ctx.get(dut.delay), "early": ctx.get(dut.early),
                    "level": ctx.get(dut.level)}

        for dut in (product, bare):
            ctx.set(dut.half_period, hp)
        for enc, cycles, f in scenarios:
            ctx.set(rst, 1)
            pin(1)
            await ctx.tick()
            ctx.set(rst, 0)
            await ctx.tick().repeat(3)              # the synchronizer flushed to the high pin
            trace = []
            for c in range(cycles):
                ctx.set(product.arm, int(c == 0))
                ctx.set(bare.arm, int(c == 0))
                pin(enc.level(c - 1))
                await ctx.delay(f * CLOCK_PERIOD_S)
                pin(enc.level(c))
                trace.append({"pin": enc.level(c), "product": read(product), "bare": read(bare)})
                await ctx.tick()
            traces.append(trace)

    simulate(top, tb)
    return traces


def _sample_list(trace, which):
    return [(c, x[which]["bit"]) for c, x in enumerate(trace) if x[which]["sample"]]


@pytest.mark.parametrize("hp", (2, 3, 5))
def test_slo_sampler_with_synchronizer_delay_samples_and_level_from_the_pin(hp):
    rng = random.Random(2100 + hp)
    scenarios = []
    for p in range(0, 13):
        for f in PIN_FRACTIONS:
            enc = DelayedEncoder(hp, p, _random_slots(rng, 6))
            scenarios.append((enc, p + 2 * hp * len(enc.slots) + 4, f))
    traces = _pin_sim(hp, scenarios)
    for (enc, _, f), trace in zip(scenarios, traces):
        true = enc.d + f
        where = f"hp={hp} round trip {true} clocks"
        delay = trace[-1]["product"]["delay"]
        # Measured from the pin: true <= reported < true + 1 clock.
        assert true <= delay < true + 1, where
        assert not any(x["product"]["early"] for x in trace), where
        # Every slot sampled once, its bit, two clocks later than without the synchronizer, in
        # the clock docs/timing.md gives: arm + line_delay + 1 + hp + 2*hp*k.
        # (The trace runs on past the last slot: only the frame's samples are compared.)
        n = len(enc.slots)
        product, bare = _sample_list(trace, "product")[:n], _sample_list(trace, "bare")[:n]
        assert [b for _, b in product] == enc.slots, where
        assert [c for c, _ in product] == [delay + 1 + hp + 2 * hp * k + vote_spacing(hp)
                                           for k in range(n)], where
        if enc.d >= 1:      # (p = 0: the bare sampler sees the edge in the arm clock, early)
            assert [b for _, b in bare] == enc.slots, where
            assert [c for c, _ in product] == [c + 2 for c, _ in bare], where
        # ``level`` is the pin two clocks later (the bare sampler's is the pin itself).
        assert all(trace[c]["product"]["level"] == trace[c - 2]["pin"]
                   for c in range(2, len(trace))), where
        assert all(x["bare"]["level"] == x["pin"] for x in trace), where


class GlitchedEncoder(DelayedEncoder):
    """A DelayedEncoder whose line is inverted in cycles ``start`` .. ``start + length - 1``."""

    def __init__(self, hp, d, slots, start, length):
        super().__init__(hp, d, slots)
        self.window = range(start, start + length)

    def level(self, c):
        return super().level(c) ^ int(c in self.window)


def _glitch_sweep(hp, length, slots, d=7):
    """One glitch of ``length`` clocks at every position from before the Ack edge to past the
    last slot: the decided bits and the delay per position."""
    frame_end = d + 2 * hp * len(slots)
    scenarios = [(GlitchedEncoder(hp, d, slots, start, length), frame_end + 2 * hp)
                 for start in range(1, frame_end)]
    results = []
    for (enc, _), trace in zip(scenarios, _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)):
        bits = [b for _, b in _samples(trace)][:len(slots)]
        results.append((enc.window.start, bits, trace[-1]["delay"]))
    return results


#: Ack, Ack, Start, CDS, data with both levels and runs of each.
GLITCH_SLOTS = [0, 0, 1, 0, 1, 1, 0, 0, 1, 0]


@pytest.mark.parametrize("hp", (3, 4, 5, 8))
def test_slo_sampler_one_glitch_up_to_the_vote_spacing_never_changes_a_decision(hp):
    """Noise immunity (docs/ports.md): the line inverted for up to v clocks (v = hp // 2), once,
    anywhere (before the Ack edge, at it, inside the Ack, on any vote of any slot): every slot is
    still decided as sent, so no Start is faked and the frame never shifts; the delay is exact
    unless the glitch touches the edge (starts within u = hp - v clocks after it, the clocks up
    to slot 0's first vote, or ends within v before it), and then off by at most v clocks."""
    v = vote_spacing(hp)
    u = hp - v
    d = 7
    for length in range(1, v + 1):
        for start, bits, delay in _glitch_sweep(hp, length, GLITCH_SLOTS, d):
            where = f"hp {hp}: {length}-clock glitch from cycle {start}"
            assert bits == GLITCH_SLOTS, where
            assert abs(delay - (d - 1)) <= v, where
            if start > d + u or start + length < d - v:
                assert delay == d - 1, where


@pytest.mark.parametrize("hp", (3, 4, 5, 8))
def test_slo_sampler_a_glitch_longer_than_the_vote_spacing_can_change_a_decision(hp):
    """The immunity bound is tight: one glitch of v + 1 clocks, placed over two votes of a slot,
    changes that slot's decision (the sweep above would fail with it)."""
    v = vote_spacing(hp)
    wrong = [start for start, bits, _ in _glitch_sweep(hp, v + 1, GLITCH_SLOTS)
             if bits != GLITCH_SLOTS]
    assert wrong


# -- Noise (docs/ports.md, "Noise: the line checks") ------------------------------------------

def _noise_sim(hp, scenarios):
    """As _sampler_sim: per scenario, the cycles ``noise`` strobes in and the decided bits."""
    return [([c for c, x in enumerate(trace) if x["noise"]],
             [x["bit"] for x in trace if x["sample"]])
            for trace in _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)]


class JitteredEncoder(DelayedEncoder):
    """A clean line whose every change after the Ack edge moves by its own offset: the change
    into slot k comes ``offsets[k]`` clocks after its nominal start (negative: before)."""

    def __init__(self, hp, d, slots, offsets):
        super().__init__(hp, d, slots)
        self.offsets = offsets

    def level(self, c):
        if c < self.d:
            return 1
        level = self.slots[0]
        for k in range(1, len(self.slots) + 1):
            start = self.d + 2 * self.hp * k + self.offsets[k]
            if c >= start:
                level = self.slots[k] if k < len(self.slots) else self.after
        return level


@pytest.mark.parametrize("hp", (3, 4, 5, 8, 10))
def test_slo_sampler_a_clean_jittered_line_never_strobes_noise(hp):
    """A clean line changes at most once between two slot centres: every change moved anywhere
    from the slot before's third vote (its clock: the vote sees the new level) to the next
    slot's first vote (offsets v - hp .. hp - v: a quarter period each way, the jitter the
    protocol allows, when hp is even) leaves every decision right and ``noise`` low: no false
    alarm at any jitter the votes tolerate."""
    v = vote_spacing(hp)
    rng = random.Random(2800 + hp)
    scenarios = []
    for _ in range(60):
        slots = _random_slots(rng, 20)
        offsets = [0] + [rng.randint(v - hp, hp - v) for _ in range(len(slots))]
        if rng.random() < 0.3:        # every change at one extreme, or alternating extremes
            ends = [v - hp, hp - v]
            offsets = [0] + ([rng.choice(ends)] * len(slots) if rng.random() < 0.5
                             else [ends[k % 2] for k in range(len(slots))])
        enc = JitteredEncoder(hp, rng.randint(1, 30), slots, offsets)
        scenarios.append((enc, enc.d + 2 * hp * (len(slots) + 3)))
    for (enc, _), (strobes, bits) in zip(scenarios, _noise_sim(hp, scenarios)):
        assert strobes == [], (enc.slots, enc.offsets)
        assert bits[:len(enc.slots)] == enc.slots


def _noise_reference(enc, hp, n_slots):
    """The documented rules, applied to the votes the line gives (the edge taken as found):
    the decision cycles of the slots whose votes form a pattern no clean line gives, or before
    whose centre (since the centre before, or the Ack edge) the line changed twice; a slot
    whose slot before strobed does not strobe."""
    v = vote_spacing(hp)
    votes, decisions = [], []
    for k in range(n_slots):
        centre = enc.d + hp + 2 * hp * k
        trio = [enc.level(centre - v), enc.level(centre), enc.level(centre + v)]
        votes.append(trio)
        decisions.append(int(sum(trio) >= 2))
    strobes = []
    for k, (first, centre, third) in enumerate(votes):
        dec = decisions[k]
        last = decisions[k - 1] if k else 0
        odd = (first == third != centre) or (first != dec and last == dec)
        if k and votes[k - 1][2] != decisions[k - 1] and dec == decisions[k - 1]:
            odd = True
        # Two changes of the line between two slot centres: after the centre before (after
        # the Ack edge, for slot 0) up to and including this slot's centre.
        start = enc.d if k == 0 else enc.d + hp + 2 * hp * (k - 1)
        centre = enc.d + hp + 2 * hp * k
        if sum(enc.level(c) != enc.level(c - 1) for c in range(start + 1, centre + 1)) >= 2:
            odd = True
        # One strobe per disturbance: a slot strobes only if the slot before did not.
        if odd and not (strobes and strobes[-1] == enc.d + hp + 2 * hp * (k - 1) + v):
            strobes.append(enc.d + hp + 2 * hp * k + v)
    return strobes


@pytest.mark.parametrize("hp", (3, 5, 8))
def test_slo_sampler_noise_strobes_where_the_rules_say(hp):
    """Glitches of 1 .. 2 hp clocks anywhere after slot 0's first vote (the edge is found
    right; 150 random placements per half period): ``noise`` strobes exactly in the decision clocks of the slots whose votes break a
    documented rule (reference above), and a glitch over a centre vote alone is always seen
    (one over an outer vote alone looks like a late or early change when the neighbouring slot
    was decided the other way: not seen, by design)."""
    v = vote_spacing(hp)
    d = 7
    slots = GLITCH_SLOTS
    n = len(slots) + 2
    rng = random.Random(2810 + hp)
    places = [(start, length) for length in range(1, 2 * hp + 1)
              for start in range(d + hp - v + 1, d + 2 * hp * len(slots))]
    scenarios = [(GlitchedEncoder(hp, d, slots, start, length), d + 2 * hp * n)
                 for start, length in rng.sample(places, min(len(places), 150))]
    seen_single = 0
    for (enc, _), (strobes, _) in zip(scenarios, _noise_sim(hp, scenarios)):
        centre0 = d + hp
        if sum(enc.level(c) for c in (centre0 - v, centre0, centre0 + v)) >= 2:
            # Slot 0 decided high: the edge is dropped (and the sampler waits for another).
            assert strobes and strobes[0] == centre0 + v, (hp, enc.window)
            continue
        want = _noise_reference(enc, hp, n)
        assert strobes == want, (hp, enc.window)
        # A glitch over exactly one vote, a centre one, breaks a rule.
        votes = [d + hp + 2 * hp * k + o for k in range(n) for o in (-v, 0, v)]
        covered = [c for c in votes if c in enc.window]
        if len(covered) == 1 and (covered[0] - d - hp) % (2 * hp) == 0:
            seen_single += 1
            assert strobes, (hp, enc.window)
    assert seen_single


@pytest.mark.parametrize("hp", (3, 5))
def test_slo_sampler_a_dropped_edge_strobes_noise(hp):
    """A glitch taken for the Ack edge (a short low before it, SLO high again before slot 0's
    first vote) is dropped: ``noise`` strobes."""
    d = 20
    scenarios = [(DelayedEncoder(hp, d, GLITCH_SLOTS, glitches={g}), d + 2 * hp * 12)
                 for g in range(2, d - hp)]
    for (enc, _), (strobes, bits) in zip(scenarios, _noise_sim(hp, scenarios)):
        assert strobes and strobes[0] < d, enc.glitches
        assert bits[:len(GLITCH_SLOTS)] == GLITCH_SLOTS


@pytest.mark.parametrize("hp", (5, 8, 10))
def test_slo_sampler_a_glitch_between_two_votes_strobes_noise(hp):
    """A glitch that touches no vote (one clock, between a slot's first vote and its centre)
    changes no decision, and no vote pattern shows it; but the line changed twice between two
    slot centres, which a clean line never does: ``noise`` strobes in that slot's decision
    clock, in every slot of the frame."""
    v = vote_spacing(hp)
    d = 9
    slots = GLITCH_SLOTS
    scenarios = []
    for k in range(len(slots)):
        centre = d + hp + 2 * hp * k
        scenarios.append((GlitchedEncoder(hp, d, slots, centre - 1, 1), d + 2 * hp * (len(slots) + 2)))
    for k, ((enc, _), (strobes, bits)) in enumerate(zip(scenarios, _noise_sim(hp, scenarios))):
        assert bits[:len(slots)] == slots, (hp, k)
        assert strobes == [d + hp + 2 * hp * k + v], (hp, k, strobes)


@pytest.mark.parametrize("hp", (3, 5, 10))
def test_slo_sampler_a_clean_line_read_right_never_strobes_noise(hp):
    """Beyond the votes' margin: every change moved by up to hp - 1 clocks either way (up to
    half a period, so that two changes may squeeze a slot). Wherever the sampler still decides
    every slot right, ``noise`` stays low: the patterns it strobes for need noise, not just
    far-moved edges."""
    rng = random.Random(2820 + hp)
    scenarios = []
    for _ in range(80):
        slots = _random_slots(rng, 16)
        offsets = [0] + [rng.randint(1 - hp, hp - 1) for _ in range(len(slots))]
        enc = JitteredEncoder(hp, rng.randint(1, 30), slots, offsets)
        scenarios.append((enc, enc.d + 2 * hp * (len(slots) + 3)))
    read_right = 0
    for (enc, _), (strobes, bits) in zip(scenarios, _noise_sim(hp, scenarios)):
        if bits[:len(enc.slots)] == enc.slots:
            read_right += 1
            assert strobes == [], (enc.slots, enc.offsets)
    assert read_right >= 10


@pytest.mark.parametrize("hp", (5, 8))
def test_slo_sampler_noise_in_consecutive_slots_strobes_every_other_slot(hp):
    """One strobe per disturbance: glitches on the centre votes of n consecutive slots (each
    slot's votes broken) strobe ceil(n / 2) times, in the 1st, 3rd, ... of them; a noisy line
    still strobes often, a lone glitch across two slots once."""
    v = vote_spacing(hp)
    d = 9
    slots = [0, 0] + [1] * 10        # no data edge after Start: no span crowded by one
    for first, n in ((2, 1), (2, 2), (3, 5), (1, 8)):
        enc = DelayedEncoder(hp, d, slots)
        centres = {d + hp + 2 * hp * k for k in range(first, first + n)}
        enc.level = (lambda base: lambda c: base(c) ^ int(c in centres))(enc.level)
        [(strobes, bits)] = _noise_sim(hp, [(enc, d + 2 * hp * (len(slots) + 2))])
        assert bits[:len(slots)] == slots
        assert strobes == [d + hp + 2 * hp * k + v for k in range(first, first + n, 2)], \
            (hp, first, n, strobes)
