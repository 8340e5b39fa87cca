"""MaClock on Amaranth's simulator: MA phases, ``rise``/``rises``, stopping at any offset.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.ma_clock import MaClock

from testkit.block_sim import simulate


def _runs(values):
    """Run-length encoding: [(value, length), ...]."""
    out = []
    for v in values:
        if out and out[-1][0] == v:
            out[-1][1] += 1
        else:
            out.append([v, 1])
    return [tuple(r) for r in out]


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


def _ma_sim(hp, run, **options):
    """MaClock at half period ``hp`` with ``run`` one value per cycle: per cycle
    (ma, rise, rises, busy). ``options``: MaClock's (``half_period_width``)."""
    dut = MaClock(**options)
    trace = []

    async def tb(ctx):
        ctx.set(dut.half_period, hp)
        for value in run:
            ctx.set(dut.run, value)
            trace.append((ctx.get(dut.ma), ctx.get(dut.rise), ctx.get(dut.rises),
                          ctx.get(dut.busy)))
            await ctx.tick()

    simulate(dut, tb)
    return trace


@pytest.mark.parametrize("hp", MA_HALF_PERIODS)
def test_ma_clock_phases_rise_and_stop_at_any_offset(hp):
    rng = random.Random(1000 + hp)
    run, designed_bursts = _ma_run_wave(hp, rng)
    trace = _ma_sim(hp, run)
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


@pytest.mark.parametrize("hp", (2, 255))
def test_ma_clock_of_an_8_bit_half_period_build(hp):
    """``half_period_width`` 8 (MasterParams): the setting holds up to 255 clocks, and MA's
    phases are exact at the shortest and the longest, cycle by cycle against the reference."""
    run = [0, 0, 0] + [1] * (2 * hp * 3) + [0] * (2 * hp + 3) + [1] * (hp + 1) + [0] * (2 * hp)
    trace = _ma_sim(hp, run, half_period_width=8)
    exp_ma, exp_rise, exp_rises, exp_busy, bursts = _ma_reference(hp, run)
    assert [b[1] for b in bursts] == [3, 1]
    for i, expected in enumerate((exp_ma, exp_rise, exp_rises, exp_busy)):
        assert [x[i] for x in trace] == expected, ("ma", "rise", "rises", "busy")[i]


def test_ma_clock_abort_mid_low_completes_period_then_idles():
    hp = 5
    # run: 2 full periods, then dropped 2 clocks into the third low phase.
    run = [0, 0] + [1] * (2 * 2 * hp + 2) + [0] * (4 * hp)
    trace = _ma_sim(hp, run)
    ma = [x[0] for x in trace]
    # Hand-written: idle(3) low5 high5 low5 high5 low5 high5, then idle high.
    assert _runs(ma) == [(1, 3), (0, 5), (1, 5), (0, 5), (1, 5), (0, 5), (1, len(run) - 28)]
    busy = [x[3] for x in trace]
    assert _runs(busy) == [(0, 3), (1, 30), (0, len(run) - 33)]
    assert trace[-1][2] == 3



# -- CDM hold (control channel): MA held low through the encoder's timeout -------------------------

def _hold_sim(hp, run, hold):
    """MaClock with the CDM hold: per cycle (ma, rise, rises, busy, held, clocking)."""
    dut = MaClock(cdm=True)
    trace = []

    async def tb(ctx):
        ctx.set(dut.half_period, hp)
        for r, h in zip(run, hold):
            ctx.set(dut.run, r)
            ctx.set(dut.hold, h)
            trace.append(tuple(ctx.get(x) for x in (dut.ma, dut.rise, dut.rises, dut.busy,
                                                     dut.held, dut.clocking)))
            await ctx.tick()

    simulate(dut, tb)
    return trace


@pytest.mark.parametrize("hp", (2, 3, 5))
@pytest.mark.parametrize("release", (-3, 0, 1, 2, 7), ids=lambda r: f"release{r:+d}")
def test_ma_clock_cdm_hold_low_through_timeout_then_one_half_period_high(hp, release):
    """Spec section 10: CDM = 1 is MA held low through the encoder's timeout. Expected from the
    period rule alone: ``run`` for P periods; ``hold`` high when the last high phase ends (its
    last clock, 2*hp*P) makes MA fall in the next clock, m = 2*hp*P + 1, exactly when a next
    period would have begun. ``hold`` drops in clock m + ``release`` (negative: before m, where
    MaClock does not look at it): MA rises at max(m + release + 1, m + hp) (no low phase shorter
    than hp), stays high exactly hp busy clocks, then idles high. No ``rise`` strobe, ``rises``
    kept."""
    periods = 3
    n = 2 * hp * periods + 4 * hp + 30
    last_high = 2 * hp * periods
    m = last_high + 1
    run = [1] * (2 * hp * (periods - 1) + 1) + [0] * n
    run = run[:n]
    drop = m + release
    hold = [int(t < drop or t < last_high + 1 and t >= last_high) for t in range(n)]
    if release < 0:
        hold = [int(t == last_high) for t in range(n)]       # high only where it is read
    trace = _hold_sim(hp, run, hold)
    ma = [x[0] for x in trace]
    rise_at = max(m + max(release, -1) + 1, m + hp) if release >= 0 else m + hp
    exp = [1] * n
    for t in range(1, last_high + 1):
        k, phase = divmod(t - 1, 2 * hp)
        exp[t] = 0 if phase < hp else 1
    for t in range(m, rise_at):
        exp[t] = 0
    assert ma == exp, (f"got {_runs(ma)}, expected {_runs(exp)}")
    busy = [x[3] for x in trace]
    assert busy == [int(1 <= t < rise_at + hp) for t in range(n)]
    assert [x[4] for x in trace] == [int(m <= t < rise_at) for t in range(n)], "held"
    assert [x[5] for x in trace] == [int(1 <= t < m) for t in range(n)], "clocking"
    assert sum(x[1] for x in trace) == periods and trace[-1][2] == periods


def test_ma_clock_cdm_release_is_remembered():
    """``hold`` low for one clock inside the minimum low phase releases MA at its end, even
    when ``hold`` comes back high."""
    hp = 5
    run = [1] + [0] * 40
    hold = [1] * 41
    m = 2 * hp + 1
    hold[m + 1] = 0
    trace = _hold_sim(hp, run, hold)
    ma = [x[0] for x in trace]
    assert _runs(ma) == [(1, 1), (0, hp), (1, hp), (0, hp), (1, 41 - 1 - 3 * hp)]


def test_ma_clock_without_hold_is_unchanged():
    """``hold`` low: the waveform of the build without the hold (the reference above)."""
    hp = 3
    rng = random.Random(7)
    run, _ = _ma_run_wave(hp, rng)
    trace = _hold_sim(hp, run, [0] * len(run))
    exp_ma, exp_rise, exp_rises, exp_busy, _ = _ma_reference(hp, run)
    assert [x[0] for x in trace] == exp_ma and [x[3] for x in trace] == exp_busy
    assert [x[3] for x in trace] == [x[5] for x in trace]          # clocking == busy
