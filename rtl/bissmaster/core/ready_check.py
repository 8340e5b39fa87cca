"""Whether a request cycle may begin clocking MA: the decision of WAIT_READY."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class ReadyCheck(wiring.Component):
    """Decides, clock by clock while the controller waits in WAIT_READY, how the wait ends.

    Exactly one of the four outputs is high, or none (wait on), in this priority:

    1. ``bad_config``: in the wait's first clock (``first_clock``) the configuration latched at
       the request is refused (``config_ok`` low): the request ends with BAD_CONFIG, nothing
       reaches the line;
    2. ``aborted``: ``abort`` is high;
    3. ``ready``: SLO is high and has been for the quiet time (the encoder's timeout has ended,
       and no noise pulse is taken for its end): MA may start. In the first clock the flag
       computed from the live setting (``quiet_live``) is used, ``quiet`` afterwards;
    4. ``stuck_low``: SLO has been low for the timeout limit: SLO_STUCK_LOW. In the first clock
       the latched limit is not valid yet, so the flag computed from the live setting
       (``slo_stuck_live``) is used there, ``slo_stuck`` afterwards.

    Combinational: the outputs follow the inputs in the same clock.

    Attributes
    ----------
    first_clock : In(1)
        The previous clock was IDLE: the wait's first clock.
    config_ok : In(1)
        The configuration check (of the latched configuration, valid in the first clock).
    abort : In(1)
        ``abort_cycle``.
    slo : In(1)
        Synchronized SLO.
    quiet, quiet_live : In(1)
        From the limit timers: SLO high for the latched / the live quiet time.
    slo_stuck, slo_stuck_live : In(1)
        From the limit timers: SLO low for the latched / the live timeout limit.
    bad_config, aborted, ready, stuck_low : Out(1)
        How the wait ends in this clock (at most one high).
    """

    def __init__(self):
        super().__init__({
            "first_clock": In(1),
            "config_ok": In(1),
            "abort": In(1),
            "slo": In(1),
            "quiet": In(1),
            "quiet_live": In(1),
            "slo_stuck": In(1),
            "slo_stuck_live": In(1),
            "bad_config": Out(1),
            "aborted": Out(1),
            "ready": Out(1),
            "stuck_low": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        slo_stuck = Mux(self.first_clock, self.slo_stuck_live, self.slo_stuck)
        with m.If(self.first_clock & ~self.config_ok):
            m.d.comb += self.bad_config.eq(1)
        with m.Elif(self.abort):
            m.d.comb += self.aborted.eq(1)
        with m.Elif(self.slo):
            # High but not yet for the quiet time: wait on (never stuck: SLO is high).
            m.d.comb += self.ready.eq(Mux(self.first_clock, self.quiet_live, self.quiet))
        with m.Elif(slo_stuck):
            m.d.comb += self.stuck_low.eq(1)
        return m
