"""LimitTimers on Amaranth's simulator: every flag at limit - 1, limit and limit + 1, the live
break time and its default, the gates of the Ack / NO_START flags, the SLO-low timer, saturation.

Cycle conventions and where expected values come from: ``block_sim.py``. The timing contract
(the block's docstring, docs/ports.md "Limits to the clock"): after the last clock ``c`` with
``clear`` high, the elapsed time is 0 in clock ``c + 1`` and one more in every clock after; a flag
read in clock ``t`` is exact for the elapsed time of clock ``t``, with the live inputs (break time,
gates) of clock ``t - 1``. The SLO-high time in clock ``t`` is the number of clocks up to
``t`` with SLO high; ``quiet`` in a clock with SLO high is that time >= the quiet time (of the
clock before; 0 -> 1 us for ``quiet_live``), and 1 in the first clock after reset. The SLO-low
time in clock ``t`` is the number of clocks right before ``t`` in which neither MA was busy nor
SLO high and quiet (a high pulse shorter than the quiet time does not restart it); a flag is up
when it is >= the limit. Defaults: 40 us break, 80 us timeout (twice the slave's longest static
timeout), 1 us quiet time.
"""

import random

import pytest

from bissmaster.core.limit_timers import LimitTimers
from bissmaster.params import MasterParams

from testkit.block_sim import protocol_clocks, run_clocks, simulate

#: A slow system clock keeps the defaults short: 40 and 80 clocks at 1 MHz.
PARAMS = MasterParams(sys_clk_hz=1_000_000, timer_width=16, max_line_delay=100)
BREAK_DEFAULT = protocol_clocks(40, PARAMS.sys_clk_hz)
TIMEOUT_DEFAULT = protocol_clocks(80, PARAMS.sys_clk_hz)
QUIET_DEFAULT = protocol_clocks(1, PARAMS.sys_clk_hz)
FLAGS = ["break_over", "ack_expired", "no_start_expired", "slo_stuck", "slo_stuck_live",
         "delay_over", "quiet", "quiet_live", "timeout_over"]
QUIET = {"slo": 1, "ma_busy": 0, "clear": 0, "in_clock": 0, "restart": 0, "break_time": 1000,
         "timeout_live": 1000, "ack_limit": 1000, "timeout_limit": 1000, "no_start_limit": 1000,
         "delay": 0, "delay_limit": 50, "quiet_limit": 0, "quiet_time_live": 0}


def reference(steps):
    """Every flag per clock, from the contract in the module docstring."""
    out = []
    elapsed = None              # unknown until the first clear
    low = 0                     # SLO-low time
    high = 0                    # SLO-high time up to the clock before
    prev = None
    for s in ({**QUIET, **s} for s in steps):
        row = dict.fromkeys(FLAGS, 0)
        if prev is not None and elapsed is not None:
            row["break_over"] = int(not prev["clear"]
                                    and elapsed >= (prev["break_time"] or BREAK_DEFAULT))
            # SSI builds: the cycle timer against the (latched) timeout limit, as break_over.
            row["timeout_over"] = int(not prev["clear"] and elapsed >= prev["timeout_limit"])
            counting = prev["in_clock"] and not prev["restart"]
            row["ack_expired"] = int(counting and elapsed >= prev["ack_limit"])
            row["no_start_expired"] = int(counting and elapsed >= prev["no_start_limit"])
        # The quiet flags: exact in a clock with SLO high (registered from the clock before, and
        # written in every clock: in a low clock, what they would be had SLO gone high).
        if prev is None:
            row["quiet"] = row["quiet_live"] = 1
        else:
            run = high + 1 if prev["slo"] else 1
            row["quiet"] = int(run >= prev["quiet_limit"])
            row["quiet_live"] = int(run >= (prev["quiet_time_live"] or QUIET_DEFAULT))
        if prev is not None:
            row["slo_stuck"] = int(low >= prev["timeout_limit"])
            row["slo_stuck_live"] = int(low >= (prev["timeout_live"] or TIMEOUT_DEFAULT))
            row["delay_over"] = int(prev["delay"] > prev["delay_limit"])
        out.append(row)
        elapsed = 0 if s["clear"] else (None if elapsed is None else elapsed + 1)
        restart = (s["slo"] and row["quiet"]) or s["ma_busy"]
        low = 0 if restart else low + 1
        high = high + 1 if s["slo"] else 0
        prev = s
    return out


def _run(steps):
    return run_clocks(LimitTimers(PARAMS), steps, FLAGS, defaults=QUIET)


def _after_clear(n, **inputs):
    """Three clocks of ``clear``, then ``n`` clocks without: elapsed time k in step 3 + k.

    The clears come as the controller's do before CLOCK: in WAIT_READY, ``in_clock`` low (the
    Ack and NO_START flags are exact only after such a clock, or after a clock in CLOCK without
    ``restart``)."""
    return [{**inputs, "clear": 1, "in_clock": 0}] * 3 + [dict(inputs)] * n


@pytest.mark.parametrize("setting, limit", [(1, 1), (2, 2), (5, 5), (37, 37),
                                            (0, BREAK_DEFAULT)],
                         ids=["1", "2", "5", "37", "0_default"])
def test_limit_timers_break_over_at_the_limit(setting, limit):
    steps = _after_clear(limit + 4, break_time=setting)
    trace = _run(steps)
    assert [trace[3 + k]["break_over"] for k in (limit - 1, limit, limit + 1)] == [0, 1, 1]
    assert [x["break_over"] for x in trace] == [x["break_over"] for x in reference(steps)]


@pytest.mark.parametrize("limit", (1, 2, 37, 80))
def test_limit_timers_timeout_over_at_the_limit(limit):
    """SSI builds: BREAK lasts the timeout limit too (docs/ports.md, "SSI mode")."""
    steps = _after_clear(limit + 4, timeout_limit=limit)
    trace = _run(steps)
    assert [trace[3 + k]["timeout_over"] for k in (limit - 1, limit, limit + 1)] == [0, 1, 1]
    assert [x["timeout_over"] for x in trace] == [x["timeout_over"] for x in reference(steps)]


def test_limit_timers_break_time_read_live_and_restarted_by_clear():
    # A long count, then the break time drops below it: over one clock later; then a clear
    # in the middle of an expired break: 0 right after it, whatever the old count.
    steps = (_after_clear(20, break_time=30) + [{"break_time": 10}] * 3 + [{"clear": 1}]
             + [{"break_time": 3}] * 6 + [{"break_time": 0}] * 45)
    trace = _run(steps)
    assert [x["break_over"] for x in trace] == [x["break_over"] for x in reference(steps)]
    assert [x["break_over"] for x in trace[22:34]] == [0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1]


@pytest.mark.parametrize("flag, limit_input",
                         [("ack_expired", "ack_limit"), ("no_start_expired", "no_start_limit")])
@pytest.mark.parametrize("limit", (1, 2, 9, 300))
def test_limit_timers_cycle_flag_at_the_limit(flag, limit_input, limit):
    steps = _after_clear(limit + 4, in_clock=1, **{limit_input: limit})
    trace = _run(steps)
    assert [trace[3 + k][flag] for k in (limit - 1, limit, limit + 1)] == [0, 1, 1]
    assert [x[flag] for x in trace] == [x[flag] for x in reference(steps)]


@pytest.mark.parametrize("gate", ("not_in_clock", "restart"))
def test_limit_timers_cycle_flags_only_in_clock_without_restart(gate):
    # Past both limits; the gate is removed for one clock in the middle.
    limits = {"ack_limit": 4, "no_start_limit": 6, "in_clock": 1}
    off = {"in_clock": 0} if gate == "not_in_clock" else {"restart": 1}
    steps = _after_clear(12, **limits) + [{**limits, **off}] + [limits] * 2
    trace = _run(steps)
    for flag in ("ack_expired", "no_start_expired"):
        assert [x[flag] for x in trace[-3:]] == [1, 0, 1], flag
        assert [x[flag] for x in trace] == [x[flag] for x in reference(steps)], flag
    # Never up outside CLOCK, however long.
    trace = _run(_after_clear(20, ack_limit=2, no_start_limit=2))
    assert not any(x["ack_expired"] or x["no_start_expired"] for x in trace)


@pytest.mark.parametrize("flag, setting, limit",
                         [("slo_stuck", 1, 1), ("slo_stuck", 3, 3), ("slo_stuck", 10, 10),
                          ("slo_stuck_live", 1, 1), ("slo_stuck_live", 7, 7),
                          ("slo_stuck_live", 0, TIMEOUT_DEFAULT)])
def test_limit_timers_slo_low_flag_at_the_limit(flag, setting, limit):
    # SLO low for limit - 1, limit and limit + 1 clocks (MA idle), high in between.
    limit_input = "timeout_limit" if flag == "slo_stuck" else "timeout_live"
    steps = []
    for low in (limit - 1, limit, limit + 1):
        steps += [{"slo": 1}] * 2 + [{"slo": 0}] * low + [{"slo": 1}]
    steps = [{**s, limit_input: setting} for s in steps]
    trace = _run(steps)
    assert [x[flag] for x in trace] == [x[flag] for x in reference(steps)]
    # Up exactly in the clock after the limit-th low clock, and only in the two longer runs.
    ups = [t for t, x in enumerate(trace) if x[flag]]
    first = 2 + (limit - 1) + 1 + 2 + limit
    assert ups[0] == first and len(ups) == 1 + 2


def test_limit_timers_slo_low_time_counts_only_while_ma_idle_and_restarts_on_slo_high():
    t = {"timeout_limit": 5, "timeout_live": 5}
    steps = ([{**t, "slo": 0, "ma_busy": 1}] * 20          # the frame's trailing zeros: no count
             + [{**t, "slo": 0}] * 4 + [{**t, "slo": 1}]   # 4 low, one high: restart
             + [{**t, "slo": 0}] * 4 + [{**t, "slo": 0, "ma_busy": 1}]   # MA busy: restart
             + [{**t, "slo": 0}] * 7)
    trace = _run(steps)
    assert [x["slo_stuck"] for x in trace] == [x["slo_stuck"] for x in reference(steps)]
    assert [t for t, x in enumerate(trace) if x["slo_stuck"]] == [35, 36]
    assert [x["slo_stuck_live"] for x in trace] == [x["slo_stuck"] for x in trace]


@pytest.mark.parametrize("limit", (0, 1, 50, 100))
def test_limit_timers_delay_over_above_the_limit(limit):
    delays = [d for d in (limit - 1, limit, limit + 1, 2**PARAMS.delay_width - 1, 0) if d >= 0]
    steps = [{"delay": d, "delay_limit": limit} for d in delays] + [{}]
    trace = _run(steps)
    assert [x["delay_over"] for x in trace[1:]] == [int(d > limit) for d in delays]


def test_limit_timers_random_sweep():
    rng = random.Random(7400)
    s = dict(QUIET)
    steps = [{**s, "clear": 1}]             # the elapsed time is defined from a clear on
    for _ in range(3000):
        s = dict(s)
        for name, values in (("break_time", (0, 1, 3, 8, 45)), ("timeout_live", (0, 1, 4, 9, 90)),
                             ("ack_limit", (1, 3, 12)), ("timeout_limit", (1, 5, 11)),
                             ("no_start_limit", (1, 7, 20))):
            if rng.random() < 0.01:
                s[name] = rng.choice(values)
        # As the controller drives it: in CLOCK the timer is cleared with ``restart`` (and
        # on an abort, which ends CLOCK); outside CLOCK at any time.
        s["in_clock"] = s["in_clock"] ^ int(rng.random() < 0.05)
        s["restart"] = int(s["in_clock"] and rng.random() < 0.03)
        s["clear"] = s["restart"] if s["in_clock"] else int(rng.random() < 0.03)
        s["slo"] = s["slo"] ^ int(rng.random() < 0.05)
        s["ma_busy"] = s["ma_busy"] ^ int(rng.random() < 0.02)
        s["delay"] = rng.randrange(2**PARAMS.delay_width)
        s["delay_limit"] = rng.choice((s["delay"], s["delay"] - 1, rng.randrange(101)))
        s["delay_limit"] = max(0, s["delay_limit"])
        steps.append(s)
    assert _run(steps) == reference(steps)


def test_limit_timers_saturate_instead_of_wrapping():
    # timer_width 16: the cycle timer holds 17 bits, the SLO-low timer counts to 2**16. Held
    # past both ends, every flag at its largest limit stays up.
    tw = PARAMS.timer_width
    dut = LimitTimers(PARAMS)
    seen = []

    async def tb(ctx):
        for name, value in {**QUIET, "slo": 0, "in_clock": 1, "clear": 1,
                            "break_time": 2**tw - 1, "ack_limit": 2**tw - 1,
                            "no_start_limit": 2**(tw + 1) - 1, "timeout_limit": 2**tw - 1,
                            "timeout_live": 2**tw - 1}.items():
            ctx.set(getattr(dut, name), value)
        await ctx.tick()
        ctx.set(dut.clear, 0)
        elapsed = 0
        for checkpoint in (2**tw - 3, 2**tw + 3, 2**(tw + 1) - 2, 2**(tw + 1) + 3):
            await ctx.tick().repeat(checkpoint - elapsed)
            elapsed = checkpoint
            seen.append((elapsed, {f: ctx.get(getattr(dut, f)) for f in FLAGS}))

    simulate(dut, tb)
    # Elapsed time e; SLO-low time e + 1 (SLO low from the clear's clock on).
    for elapsed, flags in seen:
        cycle_up, low_up = int(elapsed >= 2**tw - 1), int(elapsed + 1 >= 2**tw - 1)
        expected = {"break_over": cycle_up, "timeout_over": cycle_up, "ack_expired": cycle_up,
                    "slo_stuck": low_up,
                    "slo_stuck_live": low_up, "delay_over": 0,
                    "no_start_expired": int(elapsed >= 2**(tw + 1) - 1),
                    # SLO low, a quiet time of 0 (latched) and 1 us = 1 clock (live): a high
                    # clock now would already be quiet.
                    "quiet": 1, "quiet_live": int(QUIET_DEFAULT <= 1)}
        assert flags == expected, elapsed


def test_limit_timers_no_start_limit_above_17_bits_on_a_16_bit_build():
    # The longest NO_START limit of a 16-bit timer build, Ack limit 2**16 - 1 plus one MA period
    # of 2 x (2**16 - 1) clocks, needs 18 bits: the flag rises exactly there, not at a wrapped
    # or saturated value.
    limit = (2**16 - 1) + 2 * (2**16 - 1)
    dut = LimitTimers(PARAMS)
    seen = {}

    async def tb(ctx):
        for name, value in {**QUIET, "in_clock": 1, "clear": 1, "no_start_limit": limit}.items():
            ctx.set(getattr(dut, name), value)
        await ctx.tick()
        ctx.set(dut.clear, 0)
        elapsed = 0
        for checkpoint in (2**17 - 1, limit - 1, limit, limit + 1):
            await ctx.tick().repeat(checkpoint - elapsed)
            elapsed = checkpoint
            seen[elapsed] = ctx.get(dut.no_start_expired)

    simulate(dut, tb)
    assert seen == {2**17 - 1: 0, limit - 1: 0, limit: 1, limit + 1: 1}


@pytest.mark.parametrize("flag, setting, quiet",
                         [("quiet", 1, 1), ("quiet", 4, 4), ("quiet", 30, 30),
                          ("quiet_live", 3, 3), ("quiet_live", 0, QUIET_DEFAULT)])
def test_limit_timers_quiet_flag_after_the_quiet_time(flag, setting, quiet):
    """SLO high for quiet - 1, quiet and quiet + 1 clocks, low in between: the flag reads 1 in a
    high clock exactly from the quiet-th high clock on."""
    limit_input = "quiet_limit" if flag == "quiet" else "quiet_time_live"
    steps = []
    for high in (quiet - 1, quiet, quiet + 1):
        steps += [{"slo": 0}] * 3 + [{"slo": 1}] * high
    steps = [{**s, limit_input: setting} for s in steps] + [{"slo": 0, limit_input: setting}]
    trace = _run(steps)
    assert [x[flag] for x in trace] == [x[flag] for x in reference(steps)]
    quiet_high = [t for t, (s, x) in enumerate(zip(steps, trace)) if s["slo"] and x[flag]]
    start = 3 + (quiet - 1) + 3
    assert quiet_high[0] == start + quiet - 1 if quiet > 1 else quiet_high


def test_limit_timers_slo_low_time_runs_through_high_pulses_shorter_than_the_quiet_time():
    """A toggling line (noise) never restarts the SLO-low timer unless SLO stays high for the
    quiet time: SLO_STUCK_LOW comes although SLO is never low for the limit in one piece, so
    WAIT_READY cannot wait forever."""
    t = {"timeout_limit": 12, "timeout_live": 12, "quiet_limit": 4, "quiet_time_live": 4}
    steps = [{**t, "slo": 1}] * 6 + ([{**t, "slo": 0}] * 2 + [{**t, "slo": 1}] * 3) * 6
    trace = _run(steps)
    for flag in ("slo_stuck", "slo_stuck_live", "quiet"):
        assert [x[flag] for x in trace] == [x[flag] for x in reference(steps)], flag
    assert any(x["slo_stuck"] for x in trace)
    # High for the quiet time restarts it.
    steps = [{**t, "slo": 1}] * 6 + ([{**t, "slo": 0}] * 2 + [{**t, "slo": 1}] * 4) * 6
    trace = _run(steps)
    assert [x["slo_stuck"] for x in trace] == [x["slo_stuck"] for x in reference(steps)]
    assert not any(x["slo_stuck"] for x in trace)


def test_limit_timers_slo_high_time_saturates():
    """SLO high far longer than the widest quiet time (2**12 - 1 clocks): still quiet."""
    steps = [{"slo": 0, "quiet_limit": 4095}] + [{"slo": 1, "quiet_limit": 4095}] * 4200
    trace = _run(steps)
    ups = [t for t, x in enumerate(trace) if x["quiet"]]
    assert ups[1:] == list(range(4095, 4201))
