"""The cycle's time limits: break, Ack, NO_START, SLO-low timeout, and the delay limit."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import QUIET_WIDTH
from .const_compare import above, at_most


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
    - ``timeout_over`` (SSI builds): elapsed >= ``timeout_limit`` (latched), cleared with
      ``break_over``: in SSI, BREAK lasts this long too (the encoder's monoflop time after an
      interrupted train).
    - ``ack_expired``: elapsed >= ``ack_limit``; ``no_start_expired``: elapsed >=
      ``no_start_limit``. Right only in CLOCK, after a clock that stays in CLOCK without
      ``restart`` (the controller clears the timer on ``restart``) or after WAIT_READY (timer
      cleared). The limits are constant from the latch on.

    **The SLO-low timer** counts how long the synchronized SLO has been low, plus one,
    saturating at ``2**width``, and only while MA is idle: it restarts with MA running and with
    SLO high for the quiet time (below), and runs on through shorter high pulses (noise is not
    the end of the encoder's timeout). The encoder's timeout starts when MA stops, and the trailing zero bits of a frame (up to 6 CRC bits and the stop bit, 90 us at
    80 kHz) must not count. ``slo_stuck`` (latched ``timeout_limit``) and ``slo_stuck_live``
    (live ``timeout_live``, 0 -> ``timeout_default``; for the cycle's first clock, before the
    latched limit is valid) flag SLO-low time >= the limit, registered one clock ahead like the
    cycle timer's flags.

    **The SLO-high timer** counts how long the synchronized SLO has been high, saturating at
    ``2**12``. ``quiet`` (latched ``quiet_limit``) and ``quiet_live`` (live ``quiet_time_live``,
    0 -> ``quiet_default``; for the cycle's first clock) flag that SLO has been high for at
    least the quiet time, this clock included, registered one clock ahead: read in a clock in
    which SLO is high, each is exact for that clock. Both are 1 after reset (the line idles
    high), until the first clock's inputs are in.

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
            "quiet_time_live": In(QUIET_WIDTH),
            "quiet_limit": In(QUIET_WIDTH),
            "break_over": Out(1),
            **({"timeout_over": Out(1)} if p.ssi else {}),
            "ack_expired": Out(1),
            "no_start_expired": Out(1),
            "slo_stuck": Out(1),
            "slo_stuck_live": Out(1),
            "delay_over": Out(1),
            "quiet": Out(1, init=1),
            "quiet_live": Out(1, init=1),
        })

    def elaborate(self, platform):
        m = Module()
        p = self._params
        tw = p.timer_width

        # The SLO-low timer and its two flags.
        # It restarts when MA runs, or when SLO has been high for the quiet time: a shorter high
        # pulse (noise) does not restart it, so a line that toggles without ever being quiet
        # still ends in SLO_STUCK_LOW, and WAIT_READY, which waits for a quiet high, never hangs.
        slo_low_time_p1 = Signal(tw + 1, init=1)
        restart_low = self.slo & self.quiet | self.ma_busy
        with m.If(restart_low):
            m.d.sync += slo_low_time_p1.eq(1)
        with m.Elif(~slo_low_time_p1[tw]):
            m.d.sync += slo_low_time_p1.eq(slo_low_time_p1 + 1)
        low_idle = ~restart_low
        m.d.sync += [
            self.slo_stuck.eq(low_idle & (slo_low_time_p1 >= self.timeout_limit)),
            self.slo_stuck_live.eq(low_idle & Mux(self.timeout_live == 0,
                                                  above(slo_low_time_p1,
                                                        p.timeout_limit_default - 1),
                                                  slo_low_time_p1 >= self.timeout_live)),
        ]

        # The SLO-high timer, plus two: ``high_p2`` is one more than the clocks SLO will have
        # been high in the next clock if it stays high, so each flag compares it with the quiet
        # time directly (every quiet time is >= 1: a clock in which SLO was low leaves only the
        # quiet time 1 met).
        high_p2 = Signal(QUIET_WIDTH + 1, init=2)
        with m.If(~self.slo):
            m.d.sync += high_p2.eq(2)
        with m.Elif(~high_p2[QUIET_WIDTH]):
            m.d.sync += high_p2.eq(high_p2 + 1)
        quiet_live = Mux(self.quiet_time_live == 0, p.quiet_default, self.quiet_time_live)
        m.d.sync += [
            self.quiet.eq(Mux(self.slo, high_p2 >= self.quiet_limit, at_most(self.quiet_limit, 1))),
            self.quiet_live.eq(Mux(self.slo, high_p2 >= quiet_live, at_most(quiet_live, 1))),
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
            if p.ssi:
                m.d.sync += self.timeout_over.eq(0)
        with m.Else():
            m.d.sync += self.break_over.eq(Mux(self.break_time == 0,
                                               above(timer, p.break_default - 1),
                                               timer >= self.break_time))
            if p.ssi:
                m.d.sync += self.timeout_over.eq(timer >= self.timeout_limit)
        m.d.sync += [
            self.ack_expired.eq(counting & (timer >= self.ack_limit)),
            self.no_start_expired.eq(counting & (timer >= self.no_start_limit)),
        ]

        m.d.sync += self.delay_over.eq(self.delay > self.delay_limit)
        return m
