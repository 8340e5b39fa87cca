"""The request cycle's state machine."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .cdm_hold import CdmHold
from .cycle_report import CycleReport
from ..layouts import fault_layout
from .line_faults import LineFaults
from ..params import Status
from .ready_check import ReadyCheck


class CycleController(wiring.Component):
    """Runs one request cycle: BREAK -> IDLE -> WAIT_READY -> CLOCK -> TAIL -> END / CONFIRM
    (-> PAUSE after a doubtful frame).

    ``docs/timing.md`` draws a cycle; ``docs/ports.md`` states every limit to the clock. The
    controller decides, the other blocks measure: the timers and their flags come from
    :class:`~bissmaster.core.limit_timers.LimitTimers`, the frame from the sampler and decoder, the
    frame's verdict is made by :class:`~bissmaster.core.frame_verdict.FrameVerdict` when the
    controller says ``report_frame``.

    The controller keeps the state machine (with ``idle``, ``first_clock``, ``receiver_clear``
    and the doubtful frame's ``pause``) and connects four blocks that own the rest:
    :class:`~bissmaster.core.ready_check.ReadyCheck` (how WAIT_READY ends),
    :class:`~bissmaster.core.line_faults.LineFaults` (the frame's Ack and Start: the timer restart
    and the line faults of CLOCK), :class:`~bissmaster.core.cdm_hold.CdmHold` (``cdm`` builds: the
    cycle's CDM bit and the hold of MA) and :class:`~bissmaster.core.cycle_report.CycleReport` (the
    report: ``report_frame``, ``report_delay``, ``fault``, ``fault_status``, ``faults``).

    States:

    - BREAK: MA high for the break time (power-up, after an abort or a line fault). The
      receiver is cleared and the sign of life resynchronised.
    - IDLE: wait for a request; the configuration is copied (``idle``).
    - WAIT_READY: one clock or more. A configuration refused by the check ends the request with
      BAD_CONFIG (nothing reaches the line); never start while the encoder holds SLO low (its
      timeout is still running), nor before SLO has been high for the quiet time (a noise
      pulse is not the end of the timeout); SLO low past the timeout limit is SLO_STUCK_LOW.
    - CLOCK: MA runs; the sampler and decoder follow SLO, the line delay behind. Line faults:
      NO_ACK, DELAY_RANGE, NO_START.
    - TAIL: clock out the stop bit and let the sampler see it. Without the end check the frame
      was reported at its last word bit; with it, NO_STOP if the stop bit is high.
    - END: the last half period of MA, then IDLE.
    - CONFIRM (end check): the frame counts once SLO is back high with MA stopped (the
      encoder's timeout ended); SLO low past the timeout limit is SLO_STUCK_LOW.
    - PAUSE: after a frame whose verdict is not OK (``frame_doubtful`` when it is reported: a CRC
      error, a sign-of-life or plausibility fault), MA high for the break time, as in BREAK but
      the sign of life stays synchronised. Such a frame may have been misread (a glitch taken
      for Start slips the frame): the encoder may still be sending the rest of it, and a cycle
      started at once would read that tail as a new frame. The pause lets the encoder's
      timeout run out first (protocol: the master pauses after an error).

    A fault reports its status (``fault``, ``fault_status`` and its own strobe in ``faults``) and
    goes to BREAK, except BAD_CONFIG (back to IDLE). A fault does not clear the timer itself:
    every state a fault can come from clears it (IDLE, WAIT_READY: always; CLOCK: on ``abort``),
    or MA is still running when BREAK begins (the line faults of CLOCK come before Start, so MA
    runs on), and BREAK clears it until MA has stopped; TAIL and CONFIRM clear it with their
    faults and on the way to PAUSE (MA may have stopped already). That keeps the fault decode out of the timer's enable.

    **CDM** (``cdm=True`` builds, the control channel): ``cdm`` is copied in every IDLE clock
    like the configuration, so a cycle carries the bit of its accepted request
    (``cdm_cycle``). With ``cdm_cycle`` = 1 the controller asks
    :class:`~bissmaster.core.ma_clock.MaClock` to hold MA low after the frame (``ma_hold`` in CLOCK
    and TAIL: MaClock reads it only at the end of the last high phase, so only a frame that
    clocked out every rise is followed by a hold; a fault or an abort goes to BREAK, which never
    holds). MA then stays low through the encoder's timeout, and END, CONFIRM and PAUSE release
    it (``ma_hold`` low) in the first clock in which SLO is seen high (the timeout ended), SLO
    has been low for the timeout limit since MA stopped (SLO_STUCK_LOW is then reported by the
    next cycle, or by CONFIRM with the end check), or ``abort`` is high (END then goes to
    BREAK). END and CONFIRM wait for MaClock to be idle (its release phase of one half period
    high) before IDLE: the master is never idle with MA low. CONFIRM accepts SLO high while MA
    is held (``ma_held``), as it does with MA stopped.

    Attributes
    ----------
    request, abort : In(1)
        From the request scheduler, and ``abort_cycle``.
    config_ok, end_check : In(1)
        The configuration check (of the latched configuration, in the cycle's first clock) and
        the cycle's ``cfg_end_check``.
    slo : In(1)
        Synchronized SLO.
    ma_busy, ma_arm, ma_enough : In(1)
        MA is in a period; the cycle's second MA rise; MA made every rise the frame needs.
    locked, early : In(1)
        The sampler found the Ack edge; SLO was low when armed.
    frame_done, started, slots_full, stopped, stop_bit : In(1)
        From the decoder.
    frame_doubtful : In(1)
        From the verdict: the frame's status will not be OK (registered with ``frame_done``).
    ssi : In(1)
        The cycle is an SSI frame (docs/ports.md, "SSI mode"): no line faults of Ack and
        Start; ``frame_done`` is the stop bit's strobe (the decoder's ``stopped``), and a stop
        bit of 1 there is NO_STOP whatever ``end_check`` says (an SSI line stuck high sends
        nothing else to tell it by); TAIL does not wait for the stop bit again; BREAK also
        waits for ``timeout_over`` (an aborted train may leave the encoder's line high within
        its monoflop time: nothing shows when it ends).
    timeout_over : In(1)
        From the limit timers: BREAK has lasted the timeout limit (SSI).
    break_over, ack_expired, no_start_expired, slo_stuck, slo_stuck_live, delay_over : In(1)
        From the limit timers.
    quiet, quiet_live : In(1)
        From the limit timers: SLO high for the quiet time (WAIT_READY).
    idle : Out(1)
    waiting : Out(1)
        IDLE or WAIT_READY: MA stopped, the encoder's SLO may only rise (for the noise watch).
    first_clock : Out(1)
        The previous clock was IDLE: in WAIT_READY, its first clock.
    receiver_clear, resync : Out(1)
        Hold the sampler and decoder in reset; forget the stored sign of life.
    timer_clear, in_clock, restart_timer : Out(1)
        To the limit timers.
    ma_run : Out(1)
    report_frame : Out(1)
        Report the decoded frame (its verdict, fields and line delay) in this clock.
    report_delay : Out(1)
        Report the measured line delay (with the frame, or with its DELAY_RANGE fault).
    fault : Out(1)
        Report ``fault_status`` in this clock, without a frame.
    fault_status : Out(Status)
    faults : Out(fault_layout())
        One strobe per fault status.
    cdm : In(1)
        ``cdm`` builds: the CDM bit for the next cycle (from the register-access engine).
    ma_held : In(1)
        ``cdm`` builds: MaClock holds MA low (its ``held``).
    ma_hold : Out(1)
        ``cdm`` builds: to MaClock's ``hold``.
    cdm_cycle : Out(1)
        ``cdm`` builds: the CDM bit this cycle carries (copied while idle).

    Parameters
    ----------
    cdm : bool
        Build the CDM hold.
    """

    def __init__(self, cdm=False):
        self._cdm = bool(cdm)
        members = {
            "request": In(1),
            "abort": In(1),
            "config_ok": In(1),
            "end_check": In(1),
            "slo": In(1),
            "ma_busy": In(1),
            "ma_arm": In(1),
            "ma_enough": In(1),
            "locked": In(1),
            "early": In(1),
            "frame_done": In(1),
            "started": In(1),
            "slots_full": In(1),
            "stopped": In(1),
            "stop_bit": In(1),
            "frame_doubtful": In(1),
            "ssi": In(1),
            "timeout_over": In(1),
            "break_over": In(1),
            "ack_expired": In(1),
            "no_start_expired": In(1),
            "slo_stuck": In(1),
            "slo_stuck_live": In(1),
            "delay_over": In(1),
            "quiet": In(1),
            "quiet_live": In(1),
            "idle": Out(1),
            "waiting": Out(1),
            "first_clock": Out(1),
            "receiver_clear": Out(1, init=1),
            "resync": Out(1),
            "timer_clear": Out(1),
            "in_clock": Out(1),
            "restart_timer": Out(1),
            "ma_run": Out(1),
            "report_frame": Out(1),
            "report_delay": Out(1),
            "fault": Out(1),
            "fault_status": Out(Status),
            "faults": Out(fault_layout()),
        }
        if self._cdm:
            members.update({"cdm": In(1), "ma_held": In(1), "ma_hold": Out(1),
                            "cdm_cycle": Out(1)})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        cdm = self._cdm
        m.submodules.ready_check = ready = ReadyCheck()
        m.submodules.line_faults = line = LineFaults()
        m.submodules.report = report = CycleReport()
        if cdm:
            m.submodules.cdm_hold = hold = CdmHold()

        # The blocks' inputs from the ports of the same name, and their outputs to the ports.
        def inputs(block, *names):
            return [getattr(block, name).eq(getattr(self, name)) for name in names]

        m.d.comb += inputs(ready, "first_clock", "config_ok", "abort", "slo", "slo_stuck",
                           "slo_stuck_live", "quiet", "quiet_live")
        m.d.comb += inputs(line, "ma_arm", "locked", "early", "started", "slots_full",
                           "ack_expired", "no_start_expired", "delay_over")
        m.d.comb += [self.restart_timer.eq(line.restart_timer),
                     self.report_frame.eq(report.report_frame),
                     self.report_delay.eq(report.report_delay),
                     self.fault.eq(report.fault), self.fault_status.eq(report.fault_status),
                     self.faults.eq(report.faults)]
        if cdm:
            m.d.comb += inputs(hold, "idle", "cdm", "slo", "slo_stuck", "abort")
            m.d.comb += [self.cdm_cycle.eq(hold.cdm_cycle), self.ma_hold.eq(hold.ma_hold)]
        m.d.sync += self.first_clock.eq(self.idle)

        # ``idle`` and ``receiver_clear`` are decodes of the state, kept as registers: written
        # with every transition from the state it goes to (no decode in front of the resets of
        # the receiver, the configuration latch and the request logic).
        cleared_states = ("BREAK", "PAUSE", "IDLE", "WAIT_READY")

        def goto(state):
            m.next = state
            m.d.sync += [self.idle.eq(state == "IDLE"),
                         self.receiver_clear.eq(state in cleared_states)]

        def fault(status, next_state="BREAK"):
            m.d.comb += [report.fail.eq(1), report.status.eq(status)]
            goto(next_state)

        # The frame is doubtful (taken when it ends): after it, PAUSE instead of END / IDLE.
        pause = Signal()

        with m.FSM(init="BREAK", name="cycle_fsm"):
            with m.State("BREAK"):
                m.d.comb += self.resync.eq(1)
                with m.If(self.ma_busy | self.abort):
                    m.d.comb += self.timer_clear.eq(1)
                with m.Elif(self.break_over & (~self.ssi | self.timeout_over)):
                    goto("IDLE")

            with m.State("IDLE"):
                m.d.comb += self.waiting.eq(1)
                # The timer is not read in IDLE, and every way out of it (BREAK, WAIT_READY)
                # starts from 0: hold it at 0 here, whatever the request decode says.
                m.d.comb += self.timer_clear.eq(1)
                with m.If(self.abort):
                    goto("BREAK")
                with m.Elif(self.request):
                    goto("WAIT_READY")

            with m.State("WAIT_READY"):
                m.d.comb += [self.timer_clear.eq(1), line.clear.eq(1), self.waiting.eq(1)]
                with m.If(ready.bad_config):
                    # Nothing has reached the line. An abort now is handled as IDLE would have.
                    fault(Status.BAD_CONFIG, "IDLE")
                    with m.If(self.abort):
                        goto("BREAK")
                with m.Elif(ready.aborted):
                    fault(Status.ABORTED)
                with m.Elif(ready.ready):
                    goto("CLOCK")
                with m.Elif(ready.stuck_low):
                    fault(Status.SLO_STUCK_LOW)

            with m.State("CLOCK"):
                m.d.comb += [self.ma_run.eq(~self.ma_enough), self.in_clock.eq(1),
                             line.watch.eq(1)]
                if cdm:
                    m.d.comb += hold.framing.eq(1)
                with m.If(self.restart_timer | self.abort):
                    m.d.comb += self.timer_clear.eq(1)
                # The end of the frame comes right after the abort: it excludes every line
                # fault below (those all come before the first sample, or before Start), so
                # this order reports the same as theirs, with fewer gates in front of the
                # frame's verdict.
                with m.If(self.abort):
                    fault(Status.ABORTED)
                with m.Elif(self.frame_done & self.ssi & self.stop_bit):
                    # SSI: the bit after the word is high: the line is stuck high (an unplugged
                    # encoder behind a fail-safe receiver) or the word is longer than set.
                    m.d.comb += self.timer_clear.eq(1)
                    fault(Status.NO_STOP)
                with m.Elif(self.frame_done):
                    m.d.sync += pause.eq(self.frame_doubtful)
                    # With the end check the verdict waits for the end of the frame (CONFIRM).
                    with m.If(~self.end_check):
                        m.d.comb += report.frame.eq(1)
                    goto("TAIL")
                with m.Elif(line.fault & ~self.ssi):
                    m.d.comb += report.delay.eq(line.delay)
                    fault(line.status)

            with m.State("TAIL"):
                m.d.comb += self.ma_run.eq(~self.ma_enough)
                if cdm:
                    m.d.comb += hold.framing.eq(1)
                with m.If(self.abort):
                    m.d.comb += self.timer_clear.eq(1)
                    with m.If(self.end_check):
                        fault(Status.ABORTED)
                    with m.Else():
                        goto("BREAK")
                with m.Elif(self.stopped | self.ssi):      # SSI: stop bit checked in CLOCK
                    with m.If(~self.end_check):
                        with m.If(pause):
                            # MA may have stopped already: the pause starts from 0.
                            m.d.comb += self.timer_clear.eq(1)
                            goto("PAUSE")
                        with m.Else():
                            goto("END")
                    with m.Elif(self.stop_bit):
                        # A good encoder holds SLO low from the stop bit through its timeout.
                        # High here: the line went (or is stuck) high, or the frame is longer
                        # than configured. Either way the bits before it are not trusted: a
                        # stuck tail can be a CRC codeword.
                        m.d.comb += self.timer_clear.eq(1)
                        fault(Status.NO_STOP)
                    with m.Else():
                        goto("CONFIRM")

            with m.State("PAUSE"):
                if cdm:
                    m.d.comb += hold.holding.eq(1)
                with m.If(self.ma_busy | self.abort):
                    m.d.comb += self.timer_clear.eq(1)
                with m.Elif(self.break_over):
                    goto("IDLE")

            with m.State("END"):
                if cdm:
                    m.d.comb += hold.holding.eq(1)
                    # An abort releases a CDM hold at once, and pauses as after any abort.
                    with m.If(self.cdm_cycle & self.abort):
                        goto("BREAK")
                    with m.Elif(~self.ma_busy):
                        goto("IDLE")
                else:
                    with m.If(~self.ma_busy):
                        goto("IDLE")

            with m.State("CONFIRM"):
                if cdm:
                    m.d.comb += hold.holding.eq(1)
                    ma_stopped = ~self.ma_busy | self.ma_held
                else:
                    ma_stopped = ~self.ma_busy
                with m.If(self.abort):
                    m.d.comb += self.timer_clear.eq(1)
                    fault(Status.ABORTED)
                with m.Elif(ma_stopped & self.slo):
                    m.d.comb += report.frame.eq(1)
                    with m.If(pause):
                        m.d.comb += self.timer_clear.eq(1)
                        goto("PAUSE")
                    if cdm:
                        # MA is released now: END waits for its half period high.
                        with m.Elif(self.cdm_cycle):
                            goto("END")
                    with m.Else():
                        goto("IDLE")
                with m.Elif(self.slo_stuck):
                    m.d.comb += self.timer_clear.eq(1)
                    fault(Status.SLO_STUCK_LOW)

        return m
