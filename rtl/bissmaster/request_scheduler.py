"""Request scheduling: single shot, periodic, as fast as possible, and overrun."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class RequestScheduler(wiring.Component):
    """Turns ``start``, ``periodic`` and the request period into requests for the controller.

    With ``periodic`` high a tick comes every ``period`` clocks (the first in the clock
    ``periodic`` rises, then ``period`` clocks apart, start to start); ``period`` = 0 asks for a
    cycle in every clock (as fast as the encoder allows: the controller takes the next one as
    soon as it is idle again). ``period`` is read live.

    A ``start`` or a tick that the controller cannot take (it is not idle, or an abort is being
    handled) is an ``overrun``; the request is dropped, never queued. A continuous request
    (``period`` = 0) is never an overrun.

    ``trigger`` is the seam for starting several channels in the same clock (a bus top drives
    it from one register write or an external pulse); it acts exactly like ``start``.

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
    request : Out(1)
        Start a cycle (the controller takes it when idle).
    overrun : Out(1)
    """

    def __init__(self, timer_width):
        super().__init__({
            "start": In(1),
            "trigger": In(1),
            "periodic": In(1),
            "period": In(timer_width),
            "abort": In(1),
            "idle": In(1),
            "request": Out(1),
            "overrun": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        start = self.start | self.trigger

        # Clocks since the last tick, plus one: the period restarts when it reaches the live
        # period (one compare, no "- 1" in front of it). It never exceeds 2**width - 1: it only
        # counts up while below the period.
        count_p1 = Signal(len(self.period), init=1)
        # ``count_p1 == 1``, kept as a register (written with it; the count never wraps to 1):
        # no wide compare in front of the request decode.
        period_start = Signal(init=1)
        as_fast_as_possible = self.periodic & (self.period == 0)
        tick = self.periodic & ~as_fast_as_possible & period_start
        with m.If(~self.periodic | as_fast_as_possible | (count_p1 >= self.period)):
            m.d.sync += [count_p1.eq(1), period_start.eq(1)]
        with m.Else():
            m.d.sync += [count_p1.eq(count_p1 + 1), period_start.eq(0)]

        m.d.comb += [
            self.request.eq(start | tick | as_fast_as_possible),
            self.overrun.eq((start | tick) & ~(self.idle & ~self.abort)),
        ]
        return m
