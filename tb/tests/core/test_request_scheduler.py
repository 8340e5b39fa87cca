"""RequestScheduler on Amaranth's simulator: single shot, periodic ticks, as fast as possible,
overrun, the period read live (with a lag of one and two clocks).

Cycle conventions and where expected values come from: ``block_sim.py``. The periodic timing is
docs/ports.md (``periodic``, ``cfg_request_period``, "Request period" and "Overrun" rows): the
first tick in the clock ``periodic`` rises, then every period clocks; period 0 = a request in
every clock, never an overrun; a start or tick while not idle, or with an abort, is an overrun.
"""

import itertools
import random

import pytest

from bissmaster.core.request_scheduler import RequestScheduler

from testkit.block_sim import run_clocks

TIMER_WIDTH = 16
OUTPUTS = ["request", "overrun"]
QUIET = {"start": 0, "trigger": 0, "periodic": 0, "period": 0, "abort": 0, "idle": 1}


def _decisions(steps):
    """Per clock: (a start, trigger or tick came, a request of "every clock"). A tick comes in
    the first clock of ``periodic`` (with a period), then in the first clock at least
    ``period`` clocks after the last tick. The period is read live with a lag
    (docs/ports.md): the tick is decided on the period of two clocks before, "a request in
    every clock" (period 0) on the one of the clock before; none is known before reset (no
    tick in the first clock after a tick there, no period 0). Each request of "every clock"
    counts as a tick, and the clock after it has none."""
    out, last = [], None
    period = lambda t: {**QUIET, **steps[t]}["period"] if t >= 0 else None
    for t, s in enumerate(steps):
        s = {**QUIET, **s}
        tick = 0
        continuous = s["periodic"] and period(t - 1) == 0
        if not s["periodic"]:
            last = None
        elif continuous:
            last = t
        elif last is None or period(t - 2) not in (None, 0) and t - last >= period(t - 2):
            # (A period of 0 two clocks before: the clock before was the last request of
            # "every clock", and the period counts from there.)
            tick, last = 1, t
        out.append((bool(s["start"] or s["trigger"] or tick), bool(continuous)))
    return out


def reference(steps):
    """(request, overrun) per clock (``_decisions``): a start, trigger or tick that the
    controller cannot take (not idle, or an abort) is an overrun."""
    out = []
    for s, (new, continuous) in zip(steps, _decisions(steps)):
        s = {**QUIET, **s}
        taken = s["idle"] and not s["abort"]
        out.append({"request": int(new or continuous),
                    "overrun": int(new and not taken)})
    return out


def held_reference(steps):
    """The same for a scheduler built with ``hold`` (a ``config_hold`` core; docs/bus.md,
    "Configuration writes"): no request reaches the controller in a clock with ``hold``; a
    start, trigger or tick that comes while the controller is idle and held waits (deferred)
    and is a request from the next clock until the controller, idle and not held, takes it;
    an abort drops it, as an overrun; another one while it waits and the hold lasts is an
    overrun too (one in the clock it is taken joins it)."""
    out, deferred = [], False
    for s, (new, continuous) in zip(steps, _decisions(steps)):
        s = {**QUIET, "hold": 0, **s}
        taken = s["idle"] and not s["abort"]
        out.append({"request": int((new or continuous or deferred) and not s["hold"]),
                    "overrun": int((new and (not taken or (deferred and s["hold"])))
                                   or (deferred and s["abort"]))})
        if s["abort"] or (s["idle"] and not s["hold"]):
            deferred = False
        elif taken and new:
            deferred = True
    return out


def _run(steps, hold=False):
    return run_clocks(RequestScheduler(TIMER_WIDTH, hold=hold), steps, OUTPUTS,
                      defaults={**QUIET, "hold": 0} if hold else QUIET)


@pytest.mark.parametrize("start, trigger, idle, abort",
                         list(itertools.product((0, 1), repeat=4)))
def test_request_scheduler_single_shot(start, trigger, idle, abort):
    step = {"start": start, "trigger": trigger, "idle": idle, "abort": abort}
    trace = _run([{}, step, {}])
    shot = int(bool(start or trigger))
    assert trace[1] == {"request": shot, "overrun": int(shot and not (idle and not abort))}
    assert trace[0] == trace[2] == {"request": 0, "overrun": 0}


@pytest.mark.parametrize("period", (1, 2, 3, 7, 50))
def test_request_scheduler_periodic_ticks_exactly_period_apart(period):
    rise = 5
    n = rise + 6 * period + 3
    steps = [{"periodic": int(t >= rise), "period": period} for t in range(n)]
    trace = _run(steps)
    ticks = [t for t, x in enumerate(trace) if x["request"]]
    assert ticks == list(range(rise, n, period))
    assert not any(x["overrun"] for x in trace)


@pytest.mark.parametrize("period", (1, 4, 9))
def test_request_scheduler_tick_while_busy_is_an_overrun_and_is_dropped(period):
    # Busy (not idle) around the second tick, aborting around the fourth: those ticks are
    # overruns; the schedule goes on, the next tick a period later.
    rise = 2
    n = rise + 6 * period + 1
    busy = {rise + period, rise + period - 1 if period > 1 else rise + period}
    abort = {rise + 3 * period}
    steps = [{"periodic": int(t >= rise), "period": period, "idle": int(t not in busy),
              "abort": int(t in abort)} for t in range(n)]
    trace = _run(steps)
    assert [t for t, x in enumerate(trace) if x["request"]] == list(range(rise, n, period))
    assert [t for t, x in enumerate(trace) if x["overrun"]] == [rise + period, rise + 3 * period]


def test_request_scheduler_period_zero_requests_every_clock_never_overrun():
    rng = random.Random(7300)
    steps = [{"periodic": int(3 <= t < 40), "period": 0, "idle": rng.randrange(2),
              "abort": int(rng.random() < 0.2)} for t in range(45)]
    trace = _run(steps)
    assert [x["request"] for x in trace] == [int(3 <= t < 40) for t in range(45)]
    assert not any(x["overrun"] for x in trace)
    # A start while busy is still an overrun in that mode.
    trace = _run([{"periodic": 1, "period": 0, "idle": 0, "start": 1}])
    assert trace == [{"request": 1, "overrun": 1}]


# (case id, [(clock, period)] changes, periodic rises at clock 2, expected ticks)
LIVE = [
    ("shorter_already_elapsed", [(0, 10), (15, 5)], [2, 12, 17, 22, 27, 32, 37, 42]),
    ("longer_mid_interval", [(0, 10), (19, 20)], [2, 12, 32]),
    ("longer_in_the_tick_clock", [(0, 10), (12, 15)], [2, 12, 27, 42]),
    ("shorter_in_the_tick_clock", [(0, 10), (12, 3)], [2, 12, 15, 18, 21, 24, 27, 30, 33, 36, 39, 42]),
    # Period 0 from clock 14 on: a request in every clock from 15 (the clock after) up to 20
    # (the period is 6 again from 20, seen in 21); the last of them, in 20, counts as a tick,
    # so the next comes 6 clocks later.
    ("to_zero_and_back", [(0, 10), (14, 0), (20, 6)], [2, 12, 20, 26, 32, 38, 44]),
    # Periodic rises in the clock the period leaves 0 (seen as 0 there): one request of
    # "every clock", then the period counts from it, no extra tick in the clock after.
    ("from_zero_as_periodic_rises", [(0, 0), (2, 7)], [2, 9, 16, 23, 30, 37, 44]),
]


@pytest.mark.parametrize("changes, expected", [c[1:] for c in LIVE], ids=[c[0] for c in LIVE])
def test_request_scheduler_period_changed_live(changes, expected):
    n = 45
    period, steps = 0, []
    for t in range(n):
        period = dict(changes).get(t, period)
        steps.append({"periodic": int(t >= 2), "period": period})
    trace = _run(steps)
    assert [x["request"] for x in trace] == [x["request"] for x in reference(steps)]
    ticks = [t for t, x in enumerate(trace) if x["request"] and steps[t]["period"]]
    assert ticks == expected


def test_request_scheduler_periodic_dropped_and_raised_again_ticks_at_once():
    steps = [{"periodic": int(t in range(2, 9) or t >= 11), "period": 4} for t in range(20)]
    trace = _run(steps)
    assert [t for t, x in enumerate(trace) if x["request"]] == [2, 6, 11, 15, 19]


def _random_steps(seed, hold=False, clocks=2000):
    """Random inputs: starts, triggers, aborts and idle clocks, ``periodic`` toggled and the
    period changed now and then; with ``hold``, a held clock in five."""
    rng = random.Random(seed)
    steps, periodic, period = [], 0, 5
    for _ in range(clocks):
        if rng.random() < 0.03:
            periodic ^= 1
        if rng.random() < 0.02:
            period = rng.choice((0, 1, 2, 3, 5, 8, 13))
        steps.append({"start": int(rng.random() < 0.05), "trigger": int(rng.random() < 0.05),
                      "periodic": periodic, "period": period, "idle": int(rng.random() < 0.6),
                      "abort": int(rng.random() < 0.1),
                      **({"hold": int(rng.random() < 0.2)} if hold else {})})
    return steps


def test_request_scheduler_random_sweep():
    steps = _random_steps(7301)
    assert _run(steps) == reference(steps)


def test_request_scheduler_held_start_is_deferred_not_dropped():
    """A start in an idle clock with ``hold`` (a configuration write acting) is no request
    then, no overrun, and a request in the next clock; an abort drops a deferred one with an
    overrun; a continuous request is kept off the controller only while held."""
    trace = _run([{}, {"start": 1, "hold": 1}, {}, {}], hold=True)
    assert [(x["request"], x["overrun"]) for x in trace] == [(0, 0), (0, 0), (1, 0), (0, 0)]
    trace = _run([{"start": 1, "hold": 1}, {"abort": 1}, {}], hold=True)
    assert [(x["request"], x["overrun"]) for x in trace] == [(0, 0), (1, 1), (0, 0)]
    # Held for three clocks: the start waits through all of them; a second start while it
    # waits is an overrun.
    trace = _run([{"start": 1, "hold": 1}, {"start": 1, "hold": 1}, {"hold": 1}, {}, {}],
                 hold=True)
    assert [(x["request"], x["overrun"]) for x in trace] == [(0, 0), (0, 1), (0, 0), (1, 0),
                                                             (0, 0)]
    steps = [{"periodic": 1, "period": 0, "hold": int(t == 4)} for t in range(7)]
    assert [x["request"] for x in _run(steps, hold=True)] == [1, 1, 1, 1, 0, 1, 1]


def test_request_scheduler_held_random_sweep():
    steps = _random_steps(7302, hold=True)
    assert _run(steps, hold=True) == held_reference(steps)
    # Without hold, the held build is the plain one.
    for step in steps:
        step["hold"] = 0
    assert _run(steps, hold=True) == reference([{k: v for k, v in s.items() if k != "hold"}
                                                for s in steps])
