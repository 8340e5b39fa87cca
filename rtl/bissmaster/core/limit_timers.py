"""The cycle's time limits: break, Ack, NO_START, SLO-low timeout, and the delay limit."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class LimitTimers(wiring.Component):
    """Two timers and the compares the cycle controller decides on, all registered.

    **The cycle timer** counts clocks since ``clear``, *plus one*: a clear loads 1, so the timer
    already holds the value the elapsed time will have in the next clock, and each flag below,
    registered one clock ahead, compares it with a limit directly (no "+ 1" or "- 1" adder in
    series with a comparator). It is ``cycle_timer_width`` bits, one more than the longest limit
    (the Ack limit + 2 half periods, up to 17 bits of half periods on a 16-bit timer build) needs,
    and saturates, above every limit. The flags are exact for the elapsed time of the clock
    in which they are read:

    - ``break_over``: elapsed >= ``break_time`` (live; 0 -> ``break_default``). The next
      elapsed time after a clear is 0, never >= a time >= 1: a clear resets the flag.
    - ``ack_expired``: elapsed >= ``ack_limit``; ``no_start_expired``: elapsed >=
      ``no_start_limit``. Right only in CLOCK, after a clock that stays in CLOCK without
      ``restart`` (the controller clears the timer on ``restart``) or after WAIT_READY (timer
      cleared). The limits are constant from the latch on.

    **The SLO-low timer** counts how long the synchronized SLO has been low, plus one,
    saturating at ``2**width``, and only while MA is idle: the encoder's timeout starts when MA
    stops, and the trailing zero bits of a frame (up to 6 CRC bits and the stop bit, 90 us at
    80 kHz) must not count. ``slo_stuck`` (latched ``timeout_limit``) and ``slo_stuck_live``
    (live ``timeout_live``, 0 -> ``timeout_default``; for the cycle's first clock, before the
    latched limit is valid) flag SLO-low time >= the limit, registered one clock ahead like the
    cycle timer's flags.

    ``delay_over``: the measured round trip is above ``delay_limit``, registered (the delay is
    final at least two clocks before the controller reads this).

    Parameters
    ----------
    params : MasterParams
    """

    def __init__(self, params):
        self._params = p = params
        tw = p.timer_width
        super().__init__({
            "slo": In(1),
            "ma_busy": In(1),
            "clear": In(1),
            "in_clock": In(1),
            "restart": In(1),
            "break_time": In(tw),
            "timeout_live": In(tw),
            "ack_limit": In(tw),
            "timeout_limit": In(tw),
            "no_start_limit": In(p.cycle_timer_width),
            "delay": In(p.delay_width),
            "delay_limit": In(p.delay_limit_width),
            "break_over": Out(1),
            "ack_expired": Out(1),
            "no_start_expired": Out(1),
            "slo_stuck": Out(1),
            "slo_stuck_live": Out(1),
            "delay_over": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        p = self._params
        tw = p.timer_width

        # The SLO-low timer and its two flags.
        slo_low_time_p1 = Signal(tw + 1, init=1)
        with m.If(self.slo | self.ma_busy):
            m.d.sync += slo_low_time_p1.eq(1)
        with m.Elif(~slo_low_time_p1[tw]):
            m.d.sync += slo_low_time_p1.eq(slo_low_time_p1 + 1)
        low_idle = ~self.slo & ~self.ma_busy
        m.d.sync += [
            self.slo_stuck.eq(low_idle & (slo_low_time_p1 >= self.timeout_limit)),
            self.slo_stuck_live.eq(low_idle & Mux(self.timeout_live == 0,
                                                  slo_low_time_p1 >= p.timeout_limit_default,
                                                  slo_low_time_p1 >= self.timeout_live)),
        ]

        # The cycle timer and its flags. Both break compares in parallel, then the default mux.
        # The clear is written as the flag's synchronous reset, not as "~clear &" in front of
        # it (the same function): Yosys then puts it on the flip-flop's reset input, as it does
        # the timer's, and the controller's clear logic stays out of the compare's LUTs. The
        # bus tops' Fmax came closer to the core's by it (docs/performance.md, "Netlist
        # variants").
        timer = Signal(p.cycle_timer_width, init=1)
        m.d.sync += timer.eq(Mux(self.clear, 1, Mux(timer.all(), timer, timer + 1)))
        counting = self.in_clock & ~self.restart
        with m.If(self.clear):
            m.d.sync += self.break_over.eq(0)
        with m.Else():
            m.d.sync += self.break_over.eq(Mux(self.break_time == 0,
                                               timer >= p.break_default,
                                               timer >= self.break_time))
        m.d.sync += [
            self.ack_expired.eq(counting & (timer >= self.ack_limit)),
            self.no_start_expired.eq(counting & (timer >= self.no_start_limit)),
        ]

        m.d.sync += self.delay_over.eq(self.delay > self.delay_limit)
        return m
