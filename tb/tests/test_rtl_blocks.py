"""Fast unit tests of the small RTL blocks, on Amaranth's Python simulator.

Conventions used throughout
---------------------------
Every testbench runs the same loop per system clock: set the inputs for the clock, read the
outputs, ``await ctx.tick()``. "Cycle ``t``" is the stretch after the ``t``-th clock edge, so a
registered output read in cycle ``t`` is what the edge that *ended* cycle ``t - 1`` stored, and a
combinational output read in cycle ``t`` already reflects the inputs set for cycle ``t``. An input
set in cycle ``t`` is what the edge ending cycle ``t`` samples.

The expected values are never taken from the RTL: they come from the protocol digest
(``shared/spec/biss-protocol.md``), from the independent encoder model in ``tb/encoder_model``,
or from the small reference functions in this file.
"""

import random

import pytest
from amaranth.hdl import ResetInserter, Signal
from amaranth.sim import Simulator

from bissmaster import protocol
from bissmaster.counters import SaturatingCounter
from bissmaster.frame_decoder import FrameDecoder
from bissmaster.ma_clock import MaClock
from bissmaster.params import Crc, MasterParams
from bissmaster.sign_of_life import SignOfLife
from bissmaster.slo_sampler import SYNC_EXTRA_LATENCY, SloSampler
from bissmaster.spw_check import SpwCheck
from bissmaster.word_crc import WordCrc
from encoder_model.crc import crc6_biss, crc16_biss, int_to_bits
from encoder_model.frames import (CRC6, CRC16, CRC_NONE, PRESETS, FrameFaults, WordFormat,
                                  WordValue, bp3, build_frame, word_bits)
from encoder_model.frames import SignOfLife as ModelSignOfLife

CRC_CODE = {CRC_NONE: Crc.NONE, CRC6: Crc.CRC6, CRC16: Crc.CRC16}


def _simulate(dut, testbench):
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(testbench)
    sim.run()


def _runs(values):
    """Run-length encoding: [(value, length), ...]."""
    out = []
    for v in values:
        if out and out[-1][0] == v:
            out[-1][1] += 1
        else:
            out.append([v, 1])
    return [tuple(r) for r in out]


# =============================================================================================
# 1. MaClock
# =============================================================================================

MA_HALF_PERIODS = (2, 3, 5, 17)


def _ma_reference(hp, run):
    """Spec-level expectation of MaClock for the ``run`` waveform (one value per cycle).

    Period level, not a state-machine copy: the clock starts one cycle after ``run`` is seen
    high while idle; from then on it is low ``hp`` cycles, high ``hp`` cycles, and looks at
    ``run`` only in the last cycle of each high phase (low there = stop, MA stays high).
    Returns per-cycle lists (ma, rise, rises, busy) and the bursts [(start s, periods P)].
    """
    n = len(run)
    ma, rise, rises, busy = [1] * n, [0] * n, [0] * n, [0] * n
    bursts = []
    t, count = 0, 0
    while t < n:
        rises[t] = count
        if not run[t]:
            t += 1
            continue
        s = t
        periods = 1
        while s + 2 * hp * periods < n and run[s + 2 * hp * periods]:
            periods += 1
        end = s + 2 * hp * periods          # last busy cycle
        bursts.append((s, periods))
        count = 0
        for c in range(s + 1, min(end + 1, n)):
            k, phase = divmod(c - s - 1, 2 * hp)
            busy[c] = 1
            ma[c] = 0 if phase < hp else 1
            if phase == hp:
                rise[c] = 1
                count = k + 1
            rises[c] = count
        t = end + 1
    return ma, rise, rises, busy, bursts


def _ma_run_wave(hp, rng):
    """Bursts of ``run`` dropped at many offsets (mid-low = abort) with gaps of 0.. clocks."""
    offsets = sorted({1, max(1, hp // 2), hp - 1 or 1, hp, hp + 1, hp + (hp + 1) // 2,
                      2 * hp - 1, 2 * hp})
    run = [0, 0, 0]
    gaps = (0, 1, 2, 5)
    i = 0
    for periods in (1, 2, 3):
        for off in offsets:
            length = 2 * hp * (periods - 1) + off
            run += [1] * length
            total = 2 * hp * periods                   # burst busy cycles after its start
            run += [0] * (total - length + 1 + gaps[i % len(gaps)])
            i += 1
    # A dip of run that misses every sampling point (last clock of a high phase) stops nothing.
    run += [1] * (2 * hp + 1) + [0] * (2 * hp - 1) + [1] * (3 * hp) + [0] * (6 * hp)
    # A long random tail.
    run += [rng.randrange(2) for _ in range(20 * hp)] + [0] * (3 * hp)
    return run, 3 * len(offsets) + 1


@pytest.mark.parametrize("hp", MA_HALF_PERIODS)
def test_ma_clock_phases_rise_and_stop_at_any_offset(hp):
    rng = random.Random(1000 + hp)
    run, designed_bursts = _ma_run_wave(hp, rng)
    dut = MaClock()
    trace = []

    async def tb(ctx):
        ctx.set(dut.half_period, hp)
        for value in run:
            ctx.set(dut.run, value)
            trace.append((ctx.get(dut.ma), ctx.get(dut.rise), ctx.get(dut.rises),
                          ctx.get(dut.busy)))
            await ctx.tick()

    _simulate(dut, tb)
    ma = [x[0] for x in trace]
    rise = [x[1] for x in trace]
    rises = [x[2] for x in trace]
    busy = [x[3] for x in trace]
    exp_ma, exp_rise, exp_rises, exp_busy, bursts = _ma_reference(hp, run)
    assert len(bursts) > designed_bursts

    # Idle high before anything, first edge falling, exactly one cycle after run.
    assert ma[:bursts[0][0] + 1] == [1] * (bursts[0][0] + 1)
    for s, _ in bursts:
        assert (ma[s], ma[s + 1]) == (1, 0), f"burst at {s}: first edge must be falling at {s + 1}"

    # Measure every phase of MA. Low phases: exactly hp. High phases between two falls of one
    # burst: exactly hp. High phases that span an idle gap: hp + 1 + idle clocks (never < hp).
    phases = _runs(ma)
    assert phases[0][0] == 1
    for value, length in phases[1:-1]:
        if value == 0:
            assert length == hp, f"low phase of {length} clocks, half period {hp}"
        else:
            assert length >= hp, f"high phase of {length} clocks, half period {hp}"
    assert sum(1 for v, _ in phases if v == 0) == sum(p for _, p in bursts)
    # High phases inside a burst are exactly hp; across a gap exactly hp + 1 + gap.
    for (s0, p0), (s1, _) in zip(bursts, bursts[1:]):
        last_rise = s0 + 2 * hp * p0 - hp + 1
        assert ma[last_rise - 1:s1 + 2] == [0] + [1] * (s1 + 1 - last_rise) + [0]
        assert s1 + 1 - last_rise >= hp + 1
    # The last high phase before IDLE: busy exactly hp clocks after the last rise.
    for s, p in bursts:
        last_rise = s + 2 * hp * p - hp + 1
        high_busy = 0
        t = last_rise
        while t < len(busy) and busy[t]:
            assert ma[t] == 1
            high_busy += 1
            t += 1
        assert high_busy == hp, f"burst at {s}: final high phase busy for {high_busy} clocks"

    # rise strobes exactly in the first cycle MA is high after a rising edge.
    assert rise[0] == 0
    for t in range(1, len(ma)):
        assert rise[t] == int(ma[t - 1] == 0 and ma[t] == 1), f"rise wrong at cycle {t}"

    # Everything, cycle by cycle, against the period-level reference.
    for name, got, exp in (("ma", ma, exp_ma), ("rise", rise, exp_rise),
                           ("rises", rises, exp_rises), ("busy", busy, exp_busy)):
        if got != exp:
            t = next(i for i, (a, b) in enumerate(zip(got, exp)) if a != b)
            pytest.fail(f"{name} differs first at cycle {t}: got {got[t]}, expected {exp[t]}; "
                        f"run around it {run[max(0, t - 4):t + 4]}")
    # rises counts from 1 at the first rise of every burst.
    for s, p in bursts:
        assert rises[s + hp + 1] == 1 and rises[s + 2 * hp * p] == p


def test_ma_clock_abort_mid_low_completes_period_then_idles():
    hp = 5
    # run: 2 full periods, then dropped 2 clocks into the third low phase.
    run = [0, 0] + [1] * (2 * 2 * hp + 2) + [0] * (4 * hp)
    dut = MaClock()
    trace = []

    async def tb(ctx):
        ctx.set(dut.half_period, hp)
        for value in run:
            ctx.set(dut.run, value)
            trace.append((ctx.get(dut.ma), ctx.get(dut.busy), ctx.get(dut.rises)))
            await ctx.tick()

    _simulate(dut, tb)
    ma = [x[0] for x in trace]
    # Hand-written: idle(3) low5 high5 low5 high5 low5 high5, then idle high.
    assert _runs(ma) == [(1, 3), (0, 5), (1, 5), (0, 5), (1, 5), (0, 5), (1, len(run) - 28)]
    busy = [x[1] for x in trace]
    assert _runs(busy) == [(0, 3), (1, 30), (0, len(run) - 33)]
    assert trace[-1][2] == 3


# =============================================================================================
# 2. SloSampler
# =============================================================================================
#
# Timing reference. Cycle ``r`` is the cycle in which the master's MA is high for the second time
# (``arm`` strobes in it). The Ack falling edge "appears at clock r + d" means the sampler's
# ``slo`` input reads 1 in cycle r + d - 1 and 0 from cycle r + d on.
#
# Expected delay: in the real core ``slo`` comes out of a 2-flop FFSynchronizer. MA changes just
# after the edge that starts cycle r; say the true round trip (MA pin -> SLO pin) is T clocks,
# not an integer. The first flop captures the low level at the first edge at or after r + T,
# which starts cycle r + ceil(T); the second flop shows it one cycle later, r + ceil(T) + 1.
# So d = ceil(T) + 1 and the compensated delay is d - 1 = ceil(T): T <= delay < T + 1, as the
# module promises. The one flop of latency that is a whole clock is SYNC_EXTRA_LATENCY = 1; the
# first flop's sub-clock uncertainty stays in the result. Hence: delay == d - 1, and d = 1 (the
# fastest possible: SLO low in the cycle right after arm) reports 0.
# (In a purely synchronous simulation where the pin changes right after an edge, T is an integer
# and the first flop samples the old level at r + T, giving delay = T + 1: the "< T + 1" bound is
# open only for asynchronous edges.)
#
# Slots: slot k spans cycles r + d + 2*hp*k .. r + d + 2*hp*(k + 1) - 1; slot 0 is inside the
# Ack. Its middle (the sample) is hp clocks after the slot start: cycle r + d + hp + 2*hp*k.

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
        return [self.d + self.hp + 2 * self.hp * k for k in range(len(self.slots))]


def _sampler_sim(width, hp, scenarios, *, extra=0):
    """Run scenarios [(encoder, cycles)] back to back, reset in between (as the master does).

    Returns one trace per scenario: per relative cycle c = 0 (arm) .. cycles-1, a dict of outputs.
    """
    sampler = SloSampler(width)
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
                    "early": ctx.get(sampler.early),
                })
                await ctx.tick()
            traces.append(trace)

    sim = Simulator(top)
    sim.add_clock(1e-8)
    sim.add_testbench(tb)
    sim.run()
    return traces


def _samples(trace):
    return [(c, x["bit"]) for c, x in enumerate(trace) if x["sample"]]


def _random_slots(rng, n_data):
    acks = rng.randint(1, 3)
    return [0] * acks + [protocol.START_BIT] + [rng.randrange(2) for _ in range(n_data)]


def test_slo_sampler_sync_extra_latency_is_one_flop():
    # See the timing reference above: the 2nd synchronizer flop is a whole clock.
    assert SYNC_EXTRA_LATENCY == 1


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
        assert trace[-1]["delay"] == d - SYNC_EXTRA_LATENCY, where
        assert not any(x["early"] for x in trace), where


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
    """RTL bug (see report): a one-clock glitch, high again at once, followed by the real Ack edge
    *before* the glitch's slot-0 sample point.

    The sampler only looks at SLO again at the glitch's slot-0 sample; by then the real Ack holds
    it low, so it locks on the glitch's timing: the delay is short by (real - glitch) clocks and
    every later sample sits that many clocks before the middle of its bit (at d = g + hp, on the
    bit's first clock: no margin at all). The glitch must be ignored and the real edge used.
    """
    g = 4
    scenarios = []
    for d in range(g + 2, g + hp + 1):
        enc = DelayedEncoder(hp, d, [0, 0, 1, 1, 0, 1, 0], glitches=(g,))
        scenarios.append((enc, d + 2 * hp * len(enc.slots)))
    for (enc, _), trace in zip(scenarios, _sampler_sim(SAMPLER_DELAY_WIDTH, hp, scenarios)):
        assert (trace[-1]["delay"], [c for c, _ in _samples(trace)]) == \
            (enc.d - 1, enc.sample_cycles()), f"glitch at {g}, real Ack edge at {enc.d}"


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


# =============================================================================================
# 3. WordCrc
# =============================================================================================

def _random_word(rng, crc):
    fmt = WordFormat(rng.randint(1, 55), nenw=rng.random() < 0.7, lc=rng.random() < 0.3, crc=crc)
    value = WordValue(rng.randrange(1 << fmt.data_bits), rng.randrange(2), rng.randrange(2),
                      rng.randint(1, 63) if fmt.lc else None)
    return fmt, word_bits(fmt, value)


def _crc_sim(kinds, jobs, rng):
    """Feed each (kind, bits) job, one bit per 1..3 clocks, start with the first bit, junk on
    ``bit`` between valid strobes. Returns per job (ok one clock after the last bit, ok two
    idle clocks later)."""
    dut = WordCrc(kinds)
    results = []

    async def tb(ctx):
        for kind, bits in jobs:
            ctx.set(dut.kind, kind)
            for i, b in enumerate(bits):
                for _ in range(rng.randrange(3)):
                    ctx.set(dut.valid, 0)
                    ctx.set(dut.start, 0)
                    ctx.set(dut.bit, rng.randrange(2))
                    await ctx.tick()
                ctx.set(dut.valid, 1)
                ctx.set(dut.start, int(i == 0))
                ctx.set(dut.bit, b)
                await ctx.tick()
            ctx.set(dut.valid, 0)
            ctx.set(dut.start, 0)
            ctx.set(dut.bit, rng.randrange(2))
            ok_now = ctx.get(dut.ok)
            await ctx.tick()
            ctx.set(dut.bit, rng.randrange(2))
            await ctx.tick()
            results.append((ok_now, ctx.get(dut.ok)))

    _simulate(dut, tb)
    return results


def test_word_crc_encoder_model_words_pass_and_single_flips_fail():
    rng = random.Random(3000)
    jobs, expected = [], []
    for crc in (CRC6, CRC16, CRC_NONE):
        for _ in range(8):
            fmt, bits = _random_word(rng, crc)
            jobs.append((CRC_CODE[crc], bits))
            expected.append((1, 1))
    # Every single-bit flip of short words (data, nE/nW, LC and the CRC itself), a sample of
    # flips in long ones. CRC-6 (x^6+x+1) and CRC-16 both detect every single-bit error.
    for crc in (CRC6, CRC16):
        for data_bits, lc in ((3, False), (6, True), (40, True)):
            fmt = WordFormat(data_bits, nenw=True, lc=lc, crc=crc)
            value = WordValue(rng.randrange(1 << data_bits), 1, 0, rng.randint(1, 63) if lc else None)
            bits = word_bits(fmt, value)
            positions = range(len(bits)) if data_bits < 40 else rng.sample(range(len(bits)), 10)
            for i in positions:
                flipped = list(bits)
                flipped[i] ^= 1
                jobs.append((CRC_CODE[crc], flipped))
                expected.append((0, 0))
            jobs.append((CRC_CODE[crc], bits))      # a good word after bad ones: start resets
            expected.append((1, 1))
    # Without a CRC nothing is checked: a flipped word still reads ok.
    fmt, bits = _random_word(rng, CRC_NONE)
    jobs.append((Crc.NONE, [b ^ 1 for b in bits]))
    expected.append((1, 1))
    assert _crc_sim((Crc.CRC6, Crc.CRC16), jobs, rng) == expected


def test_word_crc_matches_encoder_model_crc_functions():
    # The words of the model end with crc6_biss / crc16_biss of everything before the CRC; a CRC
    # of the right function but the wrong neighbour value fails.
    rng = random.Random(3100)
    jobs, expected = [], []
    for _ in range(6):
        payload = [rng.randrange(2) for _ in range(rng.randint(1, 60))]
        for func, width, kind in ((crc6_biss, 6, Crc.CRC6), (crc16_biss, 16, Crc.CRC16)):
            good = func(payload)
            jobs.append((kind, payload + int_to_bits(good, width)))
            expected.append((1, 1))
            jobs.append((kind, payload + int_to_bits(good ^ 1, width)))
            expected.append((0, 0))
    assert _crc_sim((Crc.CRC6, Crc.CRC16), jobs, rng) == expected


def test_word_crc_kind_not_built_reads_failed():
    rng = random.Random(3200)
    fmt6, bits6 = _random_word(rng, CRC6)
    fmt16, bits16 = _random_word(rng, CRC16)
    jobs = [(Crc.CRC6, bits6), (Crc.CRC16, bits16), (3, bits6), (Crc.NONE, bits16)]
    # Only CRC-6 built: a correct CRC-16 word under kind CRC16 fails, code 3 fails, NONE passes.
    assert _crc_sim((Crc.CRC6,), jobs, rng) == [(1, 1), (0, 0), (0, 0), (1, 1)]
    jobs = [(Crc.CRC6, bits6), (Crc.CRC16, bits16), (3, bits16)]
    assert _crc_sim((Crc.CRC16,), jobs, rng) == [(0, 0), (1, 1), (0, 0)]


# =============================================================================================
# 4. SignOfLife
# =============================================================================================

class RefSignOfLife:
    """The LC rule of the protocol digest (5.2), independently: 1..63 then 1; 0 never valid."""

    def __init__(self):
        self.last = None        # None = not synced

    def judge(self, lc):
        """(repeat, skip, zero) for lc."""
        if lc == 0:
            return (0, 0, 1)
        if self.last is None:
            return (0, 0, 0)
        expected = 1 if self.last == 63 else self.last + 1
        return (int(lc == self.last), int(lc not in (self.last, expected)), 0)

    def check(self, lc):
        verdict = self.judge(lc)
        if lc != 0:
            self.last = lc
        return verdict


def _sol_sim(ops):
    """ops: ("check", lc) | ("peek", lc) (verdict without check) | ("resync",).
    Returns [(repeat, skip, zero, synced_before)] for check/peek ops."""
    dut = SignOfLife()
    out = []

    async def tb(ctx):
        for op in ops:
            ctx.set(dut.check, 0)
            ctx.set(dut.resync, 0)
            if op[0] == "resync":
                ctx.set(dut.resync, 1)
            else:
                ctx.set(dut.lc, op[1])
                ctx.set(dut.check, int(op[0] == "check"))
                out.append((ctx.get(dut.repeat), ctx.get(dut.skip), ctx.get(dut.zero),
                            ctx.get(dut.synced)))
            await ctx.tick()

    _simulate(dut, tb)
    return out


def _sol_expected(ops):
    ref = RefSignOfLife()
    out = []
    for op in ops:
        if op[0] == "resync":
            ref.last = None
        else:
            synced = int(ref.last is not None)
            verdict = ref.check(op[1]) if op[0] == "check" else ref.judge(op[1])
            out.append(verdict + (synced,))
    return out


def test_sign_of_life_normal_sequence_wraps_63_to_1():
    model = ModelSignOfLife()
    values = [model.next() for _ in range(63 * 2 + 5)]
    assert values[62:65] == [63, 1, 2]
    got = _sol_sim([("check", v) for v in values])
    assert got[0] == (0, 0, 0, 0)                      # first frame after reset: accepted
    assert got[1:] == [(0, 0, 0, 1)] * (len(values) - 1)


def test_sign_of_life_repeat_skip_zero_by_hand():
    ops = [("check", 5), ("check", 5), ("check", 6), ("check", 8), ("check", 0), ("check", 10),
           ("check", 0), ("check", 11), ("check", 63), ("check", 63), ("check", 1),
           ("check", 62), ("check", 1)]
    # 5 first: ok | 5 repeat | 6 ok | 8 skip | 0 zero | 10 vs 8: skip | 0 zero | 11 vs 10: ok |
    # 63 skip | 63 repeat | 1 ok (wrap) | 62 skip | 1 skip (62 -> 63 expected)
    assert _sol_sim(ops) == [
        (0, 0, 0, 0), (1, 0, 0, 1), (0, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1), (0, 1, 0, 1),
        (0, 0, 1, 1), (0, 0, 0, 1), (0, 1, 0, 1), (1, 0, 0, 1), (0, 0, 0, 1), (0, 1, 0, 1),
        (0, 1, 0, 1)]


def test_sign_of_life_frame_after_zero_judged_against_last_good():
    ops = [("check", 20), ("check", 0), ("check", 21), ("check", 0), ("check", 0),
           ("check", 21), ("check", 0), ("check", 23)]
    # 21 after (20, 0): ok. 21 after (21, 0, 0): repeat. 23 after (21, 0): skip.
    assert _sol_sim(ops) == [(0, 0, 0, 0), (0, 0, 1, 1), (0, 0, 0, 1), (0, 0, 1, 1),
                             (0, 0, 1, 1), (1, 0, 0, 1), (0, 0, 1, 1), (0, 1, 0, 1)]


def test_sign_of_life_every_value_after_every_value():
    # From each stored value 1..63, every LC 0..63 peeked (combinational verdict, no store).
    ops = []
    for last in range(1, 64):
        ops.append(("check", last))
        ops += [("peek", lc) for lc in range(64)]
    got = _sol_sim(ops)
    assert got == _sol_expected(ops)
    # Spot checks that the reference itself agrees with the protocol text.
    per = 65
    assert got[per * 62 + 1 + 1] == (0, 0, 0, 1)       # stored 63, peek 1: the wrap is fine
    assert got[per * 62 + 1 + 63] == (1, 0, 0, 1)      # stored 63, peek 63: repeat
    assert got[per * 62 + 1 + 0] == (0, 0, 1, 1)       # zero
    assert sum(v[1] for v in got[1:per]) == 61         # stored 1: 61 values skip (not 0, 1, 2)


def test_sign_of_life_skips_of_1_to_62_values():
    # The encoder model loses n values, then sends the next one. Losing 62 of a 63-value cycle
    # brings back the same value: that is a repeat, not a skip.
    for start in (1, 40, 63):
        ops = []
        for n in range(1, 63):
            model = ModelSignOfLife(start)
            ops += [("resync",), ("check", model.next()), ("check", model.skip(n))]
        got = _sol_sim(ops)
        assert got == _sol_expected(ops)
        assert [v[:3] for v in got[1::2]] == [(0, 1, 0)] * 61 + [(1, 0, 0)], start


def test_sign_of_life_resync_accepts_next_value_and_first_after_reset():
    ops = [("check", 0), ("check", 17), ("check", 18), ("resync",), ("check", 40), ("check", 41),
           ("resync",), ("check", 0), ("check", 41), ("peek", 9), ("check", 42)]
    got = _sol_sim(ops)
    assert got == [
        (0, 0, 1, 0),       # zero first after reset: flagged, not stored, still unsynced
        (0, 0, 0, 0),       # 17 first value: accepted
        (0, 0, 0, 1),
        (0, 0, 0, 0),       # 40 after resync: accepted
        (0, 0, 0, 1),
        (0, 0, 1, 0),       # zero after resync: flagged, does not sync
        (0, 0, 0, 0),       # 41 (equal to the old stored value) accepted: no repeat after resync
        (0, 1, 0, 1),       # peek 9: would be a skip, but is not stored
        (0, 0, 0, 1),       # 42 follows 41
    ]
    assert got == _sol_expected(ops)


def test_sign_of_life_random_sequences_against_reference():
    rng = random.Random(4000)
    model = ModelSignOfLife()
    ops = []
    sent = False                        # model.repeat() needs a value sent before
    for _ in range(600):
        r = rng.random()
        if r < 0.6 or (r < 0.7 and not sent):
            ops.append(("check", model.next()))
            sent = True
        elif r < 0.7:
            ops.append(("check", model.repeat()))
        elif r < 0.8:
            ops.append(("check", model.skip(rng.randint(1, 62))))
            sent = True
        elif r < 0.87:
            ops.append(("check", model.zero()))
        elif r < 0.93:
            ops.append(("peek", rng.randrange(64)))
        else:
            ops.append(("resync",))
    got = _sol_sim(ops)
    assert got == _sol_expected(ops)
    assert sum(v[0] for v in got) > 10 and sum(v[1] for v in got) > 10
    assert sum(v[2] for v in got) > 10


# =============================================================================================
# 5. SpwCheck
# =============================================================================================

def _spw_ref(cpw_top, spw, bits, tol):
    mod = 1 << bits
    return int((cpw_top - spw) % mod <= tol or (spw - cpw_top) % mod <= tol)


@pytest.mark.parametrize("width", (8, 28, 40))
def test_spw_check_distance_both_ways_modulo_bits_two_clocks_late(width):
    rng = random.Random(5000 + width)
    vectors = []
    for _ in range(500):
        bits = rng.randint(1, width)
        mod = 1 << bits
        tol = rng.choice((0, 1, 2, 3, 16, 127, 255, rng.randrange(256)))
        shape = rng.random()
        if shape < 0.3:                 # fully random, garbage above bit ``bits`` too
            cpw, spw = rng.randrange(1 << width), rng.randrange(1 << width)
        else:                           # near each other, often across the 0 / 2**bits-1 wrap
            base = rng.choice((0, 1, mod - 1, mod - 2, rng.randrange(mod)))
            delta = rng.randint(-tol - 2, tol + 2)
            cpw, spw = base, (base + delta) % mod
            if rng.random() < 0.5:
                cpw, spw = spw, cpw
        vectors.append((cpw, spw, bits, tol))
    # Hand-picked wrap cases.
    for bits in (1, 2, min(width, 8), width):
        top = (1 << bits) - 1
        vectors += [(0, top, bits, 1), (top, 0, bits, 1), (0, top, bits, 0), (top, 0, bits, 0),
                    (1, top, bits, 2), (top, 1, bits, 1), (top - 1 if top else 0, 1, bits, 2)]
    dut = SpwCheck(width)
    got = []

    async def tb(ctx):
        # Each vector is held two clocks; match is read two clocks after a vector is applied,
        # i.e. in the first clock of the next vector. (Holding it two clocks keeps this test
        # about the function; the latency of each input is tested separately below.)
        for cpw, spw, bits, tol in vectors + [(0, 0, 1, 0)]:
            ctx.set(dut.cpw_top, cpw)
            ctx.set(dut.spw, spw)
            ctx.set(dut.bits, bits)
            ctx.set(dut.tolerance, tol)
            got.append(ctx.get(dut.match))
            await ctx.tick().repeat(2)

    _simulate(dut, tb)
    expected = [_spw_ref(*v) for v in vectors]
    assert got[1:] == expected
    assert 0 < sum(expected) < len(expected)
    # The wrap is a distance of 1, not 2**bits - 1.
    assert _spw_ref(0, (1 << width) - 1, width, 1) == 1


def _spw_stream(seq, width=28):
    dut = SpwCheck(width)
    got = []

    async def tb(ctx):
        for cpw, spw, bits, tol in seq:
            ctx.set(dut.cpw_top, cpw)
            ctx.set(dut.spw, spw)
            ctx.set(dut.bits, bits)
            ctx.set(dut.tolerance, tol)
            got.append(ctx.get(dut.match))
            await ctx.tick()

    _simulate(dut, tb)
    return got


def test_spw_check_match_follows_positions_two_clocks_later():
    # Only cpw_top / spw / bits change, every clock; match(t) = reference(inputs(t - 2)).
    seq = [(100, 100, 28, 2), (100, 200, 28, 2), (100, 102, 28, 2), (5, 9, 28, 2),
           (0, (1 << 28) - 1, 28, 2), (0, 6, 2, 2), (0, 5, 3, 2), (7, 0, 3, 2), (7, 0, 4, 2)]
    got = _spw_stream(seq + [seq[-1]] * 2)
    expected = [_spw_ref(*v) for v in seq]
    assert expected == [1, 0, 1, 0, 1, 1, 0, 1, 0]
    assert got[2:] == expected


def test_spw_check_match_follows_tolerance_two_clocks_later():
    """RTL bug (low severity, see report): the docstring says ``match`` follows *the inputs* two
    clocks later, but ``tolerance`` goes straight into the second stage, one clock later.
    Harmless in the master today (cfg_spw_tolerance is latched for the whole cycle)."""
    # cpw/spw 4 apart throughout; only the tolerance changes.
    tols = [3, 4, 3, 4, 4, 3, 3]
    got = _spw_stream([(5, 9, 28, t) for t in tols] + [(5, 9, 28, 3)] * 2)
    assert got[2:] == [int(t >= 4) for t in tols]


# =============================================================================================
# 6. SaturatingCounter
# =============================================================================================

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

    _simulate(dut, tb)
    count, expected = 0, []
    for inc, clear in ops:
        count = 0 if clear else min(count + inc, (1 << width) - 1)
        expected.append(count)
    assert got == expected
    # By hand: 1..5, 5, 5, 6, 7 x5 (saturated), clear with inc -> 0, 1, 2, 3, clear -> 0.
    assert got[:18] == [1, 2, 3, 4, 5, 5, 5, 6, 7, 7, 7, 7, 7, 0, 1, 2, 3, 0]
    assert got.count(7) > 10


# =============================================================================================
# 7. FrameDecoder
# =============================================================================================

def _cfg(wf):
    if wf is None:
        return {"data_bits": 0, "nenw": 0, "lc": 0, "crc": 0}
    return {"data_bits": wf.data_bits, "nenw": int(wf.nenw), "lc": int(wf.lc),
            "crc": int(CRC_CODE[wf.crc])}


def _random_values(fmt, rng):
    values = []
    cpw = rng.randrange(1 << fmt.words[0].data_bits)
    for i, w in enumerate(fmt.words):
        pos = cpw if i == 0 else (cpw >> fmt.spw_shift)
        values.append(WordValue(pos, rng.randrange(2), rng.randrange(2),
                                rng.randint(1, 63) if w.lc else None))
    return values


def _decode(params, fmt, values, *, acks, faults=None, hw_word1=None, seed=0):
    """Feed Ack zeros, the model frame and the stop bit, samples 1..4 clocks apart with junk on
    ``bit`` in between; then two more samples (SLO back high). Returns (trace, sample cycles)."""
    rng = random.Random(seed)
    frame = build_frame(fmt, values, faults)
    slots = [0] * acks + frame + [0] + [1, 1]
    dut = FrameDecoder(params)
    cfgs = [_cfg(w) for w in fmt.words]
    if params.words == 2 and len(cfgs) == 1:
        cfgs.append(_cfg(hw_word1))
    fields = ["done", "stopped", "started", "start_slot", "slots", "cds", "ne", "nw", "lc",
              "cpw_top", "crc_ok", "frame_bits"] + [f"data{w}" for w in range(params.words)]
    trace, sample_cycles = [], []

    async def tb(ctx):
        ctx.set(dut.words, cfgs)
        ctx.set(dut.word_count, len(fmt.words))
        cycle = 0

        def record():
            trace.append({f: ctx.get(getattr(dut, f)) for f in fields})

        for bit in slots + [None] * 2:
            for _ in range(rng.randrange(4)):
                ctx.set(dut.sample, 0)
                ctx.set(dut.bit, rng.randrange(2))
                record()
                await ctx.tick()
                cycle += 1
            if bit is None:
                continue
            ctx.set(dut.sample, 1)
            ctx.set(dut.bit, bit)
            sample_cycles.append(cycle)
            record()
            await ctx.tick()
            cycle += 1
        ctx.set(dut.sample, 0)
        record()

    _simulate(dut, tb)
    return trace, sample_cycles, frame


DECODER_CASES = {
    # name: (params, format, acks, faults, hw word 1 config when the frame has one word)
    "resolute_fs_rsh": (MasterParams(), PRESETS["resolute_fs_rsh"], 1, None, None),
    "resolute_fs_rsh_cds1_acks3": (MasterParams(), PRESETS["resolute_fs_rsh"], 3,
                                   FrameFaults(cds=1), None),
    "evolute_36_word1_off": (MasterParams(), PRESETS["evolute_36"], 2, None,
                             WordFormat(28, lc=True, crc=CRC16)),
    "bp3_1": (MasterParams(), PRESETS["bp3_1"], 1, None, None),
    "bp3_55": (MasterParams(), bp3(55), 4, None, None),
    "bp3_55_one_word_hw": (MasterParams(max_data_bits=(55,), word_crcs=((Crc.CRC6,),)), bp3(55),
                           2, FrameFaults(cds=1), None),
    "evolute_36_one_word_hw": (MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)),
                               PRESETS["evolute_36"], 1, None, None),
}


@pytest.mark.parametrize("case", list(DECODER_CASES))
def test_frame_decoder_fields_and_strobes(case):
    params, fmt, acks, faults, hw_word1 = DECODER_CASES[case]
    rng = random.Random(case)
    for rep in range(2):
        values = _random_values(fmt, rng)
        if rep == 0:        # fixed extremes: all-ones / errors asserted / LC 63
            values = [WordValue((1 << w.data_bits) - 1, 0, 1, 63 if w.lc else None)
                      for w in fmt.words]
            if fmt.is_safety:
                values[1].position = values[0].position >> fmt.spw_shift
        trace, samples, frame = _decode(params, fmt, values, acks=acks, faults=faults,
                                        hw_word1=hw_word1, seed=rep)
        n_words = len(fmt.words)
        last_bit_sample = samples[acks + len(frame) - 1]
        stop_sample = samples[acks + len(frame)]
        assert [c for c, x in enumerate(trace) if x["done"]] == [last_bit_sample + 1]
        assert [c for c, x in enumerate(trace) if x["stopped"]] == [stop_sample + 1]
        # started in the cycle after the Start sample, not before.
        start_sample = samples[acks]
        assert [x["started"] for x in trace] == \
            [0] * (start_sample + 1) + [1] * (len(trace) - start_sample - 1)

        for when in (last_bit_sample + 1, len(trace) - 1):    # at done, and held afterwards
            x = trace[when]
            assert x["start_slot"] == acks
            assert x["cds"] == (faults.cds if faults else 0)
            assert x["frame_bits"] == fmt.total_bits
            for w, (wf, v) in enumerate(zip(fmt.words, values)):
                assert x[f"data{w}"] == v.position, (when, w)
                assert (x["ne"] >> w) & 1 == v.ne and (x["nw"] >> w) & 1 == v.nw
                if wf.lc:
                    assert x["lc"] == v.lc
            if not any(wf.lc for wf in fmt.words):
                assert x["lc"] == 0
            assert x["crc_ok"] & ((1 << n_words) - 1) == (1 << n_words) - 1
            if params.words == 2:
                if n_words == 2:
                    d1 = fmt.words[1].data_bits
                else:
                    d1 = hw_word1.data_bits if hw_word1 else 0
                expected_top = values[0].position >> max(0, fmt.words[0].data_bits - d1)
                assert x["cpw_top"] == expected_top
        assert trace[-1]["slots"] == acks + len(frame) + 3
        # Nothing that ends the frame happens before its last bit.
        assert not any(x["done"] or x["stopped"] for x in trace[:last_bit_sample + 1])


def test_frame_decoder_frame_bits_and_word_count():
    # frame_bits is combinational from the configuration: word 1 only counts when enabled.
    dut = FrameDecoder(MasterParams())
    got = []

    async def tb(ctx):
        rsh = PRESETS["resolute_fs_rsh"]
        for count, words in ((2, rsh.words), (1, rsh.words),
                             (2, (WordFormat(55), WordFormat(40, lc=True, crc=CRC16))),
                             (1, (WordFormat(7, nenw=False, crc=CRC_NONE), rsh.words[1]))):
            ctx.set(dut.words, [_cfg(w) for w in words])
            ctx.set(dut.word_count, count)
            got.append(ctx.get(dut.frame_bits))
            await ctx.tick()

    _simulate(dut, tb)
    assert got == [96, 44, 63 + 64, 7]


@pytest.mark.parametrize("word", (0, 1))
def test_frame_decoder_flipped_bit_fails_only_that_words_crc(word):
    fmt = PRESETS["resolute_fs_rsh"]
    rng = random.Random(7000 + word)
    values = _random_values(fmt, rng)
    first = 2 + (0 if word == 0 else fmt.words[0].total_bits)
    flip = first + rng.randrange(fmt.words[word].total_bits)
    trace, samples, frame = _decode(MasterParams(), fmt, values, acks=1,
                                    faults=FrameFaults(flip_bits=(flip,)), seed=3)
    done = [c for c, x in enumerate(trace) if x["done"]]
    assert done == [samples[1 + len(frame) - 1] + 1]
    assert trace[done[0]]["crc_ok"] == (0b10 if word == 0 else 0b01)
