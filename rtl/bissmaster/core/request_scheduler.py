"""Request scheduling: single shot, periodic, as fast as possible, and overrun."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .const_compare import at_most


class RequestScheduler(wiring.Component):
    """Turns ``start``, ``periodic`` and the request period into requests for the controller.

    With ``periodic`` high a tick comes every ``period`` clocks (the first in the clock
    ``periodic`` rises, then ``period`` clocks apart, start to start); ``period`` = 0 asks for a
    cycle in every clock (as fast as the encoder allows: the controller takes the next one as
    soon as it is idle again). Each of those requests counts as a tick: when the period becomes
    non-zero again, the next tick comes a period after the last of them (and never in the clock
    right after it: at least two clocks later). ``period`` is read live, with a lag: whether a
    tick comes in a clock is decided on the ``period`` of two clocks before, whether requests
    come in every clock on the one of the clock before. Both decisions are registered, so that
    neither the period compare nor the zero test sits in front of the period counter (with
    several cores behind a bus that loop was the critical path, docs/performance.md).

    A ``start`` or a tick that the controller cannot take (it is not idle, or an abort is being
    handled) is an ``overrun``; the request is dropped, never queued. A continuous request
    (``period`` = 0) is never an overrun.

    ``trigger`` is the seam for starting several channels in the same clock (a bus top drives
    it from one register write or an external pulse); it acts exactly like ``start``.

    With ``hold`` (built for ``config_hold`` cores): while ``hold`` is high no request reaches
    the controller (its configuration is being written). A ``start`` or a tick that comes in
    an idle clock with ``hold`` high is deferred, not dropped: it is a request from the next
    clock on until the controller takes it (an abort drops it, as an ``overrun``). Another
    ``start`` or tick while one waits and ``hold`` is still high is an ``overrun``, as one
    during a cycle is; one in the clock the waiting request is taken is the same cycle, as a
    ``start`` and a tick in one clock are.

    Attributes
    ----------
    start, trigger : In(1)
        Single-shot request.
    periodic : In(1)
    period : In(timer_width)
        ``cfg_request_period``, live.
    abort : In(1)
    idle : In(1)
        The controller is in IDLE.
    hold : In(1)
        Only with ``hold=True``: keep every request from the controller in this clock.
    request : Out(1)
        Start a cycle (the controller takes it when idle).
    overrun : Out(1)
    """

    def __init__(self, timer_width, hold=False):
        self._hold = hold
        super().__init__({
            "start": In(1),
            "trigger": In(1),
            "periodic": In(1),
            "period": In(timer_width),
            "abort": In(1),
            "idle": In(1),
            **({"hold": In(1)} if hold else {}),
            "request": Out(1),
            "overrun": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        start = self.start | self.trigger

        # Clocks since the last tick, plus two. The period restarts in a clock whose ``wrap``
        # is set: ``wrap`` is "clocks since the last tick + 1 >= period", registered from the
        # clock before (count_p2 there), so the compare ends in one flip-flop and only that
        # flip-flop fans out to the counter. The count only goes on while below a period, so
        # count_p2 never exceeds 2**width (one bit wider than the period).
        count_p2 = Signal(len(self.period) + 1, init=2)
        wrap = Signal()
        # ``count_p2 == 2``, kept as a register (written with it; the count never wraps to 2):
        # no wide compare in front of the request decode.
        period_start = Signal(init=1)
        # ``period == 0``, registered: continuous requests from the clock after the period
        # becomes 0.
        period_zero = Signal()
        m.d.sync += period_zero.eq(self.period == 0)
        as_fast_as_possible = self.periodic & period_zero
        tick = self.periodic & ~as_fast_as_possible & period_start
        with m.If(~self.periodic | (wrap & ~as_fast_as_possible)):
            # The period restarts: a tick in the next clock.
            m.d.sync += [count_p2.eq(2), period_start.eq(1), wrap.eq(at_most(self.period, 1))]
        with m.Elif(as_fast_as_possible):
            # A continuous request is a tick: the next clock is the one after a tick.
            m.d.sync += [count_p2.eq(3), period_start.eq(0), wrap.eq(at_most(self.period, 2))]
        with m.Else():
            m.d.sync += [count_p2.eq(count_p2 + 1), period_start.eq(0),
                         wrap.eq(count_p2 >= self.period)]

        takeable = self.idle & ~self.abort
        hold, deferred = C(0, 1), C(0, 1)
        if self._hold:
            # A request the hold keeps from an idle controller waits here (one: the bank
            # holds the core for two idle clocks per configuration write; a second request
            # while one waits is an overrun, as a request during a cycle is).
            hold, deferred = self.hold, Signal()
            with m.If(self.abort | (self.idle & ~hold)):
                m.d.sync += deferred.eq(0)
            with m.Elif(takeable & (start | tick)):
                m.d.sync += deferred.eq(1)
        m.d.comb += [
            self.request.eq((start | tick | as_fast_as_possible | deferred) & ~hold),
            self.overrun.eq(((start | tick) & (~takeable | (deferred & hold)))
                            | (deferred & self.abort)),
        ]
        return m
        # A request the hold keeps from an idle controller waits here (one: the bank holds
        # the core for two idle clocks per configuration write; a second request while one
        # waits is an overrun, as a request during a cycle is).
        deferred = Signal()
        with m.If(self.abort | (self.idle & ~self.hold)):
            m.d.sync += deferred.eq(0)
        with m.Elif(takeable & (start | tick)):
            m.d.sync += deferred.eq(1)
        m.d.comb += [
            self.request.eq((start | tick | as_fast_as_possible | deferred) & ~self.hold),
            self.overrun.eq(((start | tick) & (~takeable | (deferred & self.hold)))
                            | (deferred & self.abort)),
        ]
        return m
