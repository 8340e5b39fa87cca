"""BiSS C / BiSS Safety master: the top level."""

from amaranth.hdl import *
from amaranth.lib import cdc, data, wiring
from amaranth.lib.wiring import In, Out

from . import protocol
from .counters import SaturatingCounter
from .frame_decoder import FrameDecoder, word_length
from .ma_clock import MaClock
from .params import STATUS_WIDTH, WORD_CONFIG, Crc, MasterParams, Status
from .sign_of_life import SignOfLife
from .slo_sampler import SloSampler
from .spw_check import SpwCheck


#: Saturating error counters, each with a ``count_<name>`` output port.
COUNTERS = (
    "crc_word0", "crc_word1", "no_ack", "no_start", "delay_range", "slo_stuck_low",
    "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch", "overrun", "aborted",
    "no_stop",
)


def _word_fields(w):
    """The flat ``cfg_w<w>_*`` ports of one word, from WORD_CONFIG."""
    return {f"cfg_w{w}_{name}": In(shape) for name, shape in WORD_CONFIG.members.items()}


class BissMaster(wiring.Component):
    """BiSS C / BiSS Safety master for one encoder.

    See ``docs/ports.md`` for the port table and ``docs/timing.md`` for one request cycle.
    Runtime settings (``cfg_*``) are checked when a request arrives and latched for the
    cycle: changing them mid-cycle never mixes two configurations in one frame.

    Parameters
    ----------
    params : MasterParams
    """

    def __init__(self, params=None):
        if params is None:
            params = MasterParams()
        if not isinstance(params, MasterParams):
            raise TypeError(f"params must be a MasterParams, not {params!r}")
        self.params = p = params
        tw = p.timer_width
        two = p.words == 2

        ports = {
            # Line
            "ma": Out(1, init=1),
            "slo": In(1, init=1),
            # Control
            "start": In(1),
            "periodic": In(1),
            "abort_cycle": In(1),
            **({"clear_counters": In(1)} if p.counters else {}),
            # Runtime configuration
            "cfg_ma_half_period": In(16),
            "cfg_request_period": In(tw),
            "cfg_break_time": In(tw),
            "cfg_ack_limit": In(tw),
            "cfg_timeout_limit": In(tw),
            "cfg_delay_limit": In(p.delay_limit_width),
            "cfg_end_check": In(1),
            **_word_fields(0),
        }
        if two:
            ports.update({"cfg_w1_enable": In(1), **_word_fields(1),
                          "cfg_spw_check": In(1), "cfg_spw_tolerance": In(8)})
        ports.update({
            # State
            "busy": Out(1),
            "config_error": Out(1),
            "overrun": Out(1),
            # Result of the last cycle
            "done": Out(1),
            "valid": Out(1),
            "status": Out(STATUS_WIDTH),
            **({"timestamp": Out(p.timestamp_width)} if p.timestamped else {}),
            "line_delay": Out(p.delay_width),
            "cds": Out(1),
        })
        for w in range(p.words):
            ports.update({
                f"word{w}_position": Out(p.max_data_bits[w]),
                f"word{w}_ne": Out(1),
                f"word{w}_nw": Out(1),
                f"word{w}_crc_ok": Out(1),
            })
        ports.update({
            "lc": Out(protocol.LC_BITS),
            "lc_repeat": Out(1),
            "lc_skip": Out(1),
            "lc_zero": Out(1),
        })
        if two:
            ports["spw_mismatch"] = Out(1)
        for name in self.counter_names:
            ports[f"count_{name}"] = Out(p.counter_width)
        super().__init__(ports)

    @property
    def counter_names(self):
        """The COUNTERS this build has: none without counters, no word-1 ones for one word."""
        p = self.params
        if not p.counters:
            return ()
        return tuple(name for name in COUNTERS
                     if p.words == 2 or name not in ("crc_word1", "spw_mismatch"))

    def _config_layout(self):
        fields = {name: len(getattr(self, name)) for name in self.signature.members
                  if name.startswith("cfg_")}
        return data.StructLayout(fields)

    def _config_valid(self, cfg):
        """Combinational: is the configuration within what this hardware can do?"""
        p = self.params

        def word_ok(w):
            bits = cfg[f"cfg_w{w}_data_bits"]
            crc = cfg[f"cfg_w{w}_crc"]
            crc_ok = crc == Crc.NONE
            for kind in p.word_crcs[w]:
                crc_ok |= crc == kind
            return bits.any() & (bits <= p.max_data_bits[w]) & crc_ok

        assert protocol.MA_HALF_PERIOD_MIN == 2
        ok = cfg.cfg_ma_half_period[1:].any() & word_ok(0)        # half period >= 2
        if p.max_line_delay < 2**p.delay_limit_width - 1:
            ok &= cfg.cfg_delay_limit <= p.max_line_delay
        if p.words == 2:
            w1 = cfg.cfg_w1_enable
            ok &= ~w1 | word_ok(1)
            ok &= ~(w1 & cfg.cfg_w0_lc & cfg.cfg_w1_lc)            # one LC per frame
            # The SPW check needs an SPW no longer than the CPW, and its CRC (the check is
            # read after the CRC bits; see SpwCheck).
            ok &= ~cfg.cfg_spw_check | (w1 & (cfg.cfg_w1_data_bits <= cfg.cfg_w0_data_bits)
                                        & (cfg.cfg_w1_crc != Crc.NONE))
        return ok

    def elaborate(self, platform):
        m = Module()
        p = self.params
        two = p.words == 2
        tw = p.timer_width

        # -- Blocks -------------------------------------------------------------------------
        m.submodules.ma_clock = ma_clock = MaClock()
        # The receiver is held in reset between cycles: every cycle starts from scratch.
        receiver_clear = Signal()
        sampler = SloSampler(p.delay_width)
        decoder = FrameDecoder(p)
        m.submodules.sampler = ResetInserter(receiver_clear)(sampler)
        m.submodules.decoder = ResetInserter(receiver_clear)(decoder)
        m.submodules.sign_of_life = sol = SignOfLife(early=True)
        if two:
            m.submodules.spw_check = spw_check = SpwCheck(p.max_data_bits[1])

        # SLO is asynchronous: two flops; the sampler compensates their latency.
        slo = Signal(init=1)
        m.submodules.slo_sync = cdc.FFSynchronizer(self.slo, slo, init=1, stages=2)

        # -- Configuration: checked live, latched when a cycle is accepted ---------------------
        layout = self._config_layout()
        live = Signal(layout)
        m.d.comb += [live[name].eq(getattr(self, name)) for name in layout.members]
        cfg = Signal(layout)        # the cycle's configuration
        # The check is registered from the live inputs in every clock. In IDLE ``cfg`` below
        # copies the same inputs in the same clocks, so in a cycle's first clock (WAIT_READY)
        # ``cfg_ok`` is the verdict on exactly the configuration the cycle latched: WAIT_READY
        # refuses it there. IDLE accepts every request, with no check in front of it.
        cfg_ok = Signal()
        m.d.sync += cfg_ok.eq(self._config_valid(live))
        m.d.comb += self.config_error.eq(~cfg_ok)

        def or_default(value, default):
            return Mux(value == 0, default, value)

        # The limits of a cycle are resolved (0 -> default) when the configuration is latched,
        # so that no default mux sits in front of a comparator. Every default is >= 1, so each
        # limit is >= 1.
        ack_limit = Signal(tw)
        timeout_limit = Signal(tw)
        delay_limit = Signal(p.delay_limit_width)
        # The configuration is copied in every clock in IDLE, so the last copy is the one of
        # the accepted request (IDLE -> WAIT_READY). Nothing reads ``cfg`` in IDLE (the MA clock
        # is stopped, the receiver held in reset, no frame is reported), so this is the same as
        # latching it on acceptance only, without the request decode in the enable.
        idle = Signal()
        with m.If(idle):
            m.d.sync += [
                cfg.eq(live),
                ack_limit.eq(or_default(live.cfg_ack_limit, p.ack_limit_default)),
                timeout_limit.eq(or_default(live.cfg_timeout_limit, p.timeout_limit_default)),
                delay_limit.eq(or_default(live.cfg_delay_limit, p.max_line_delay)),
            ]
        # NO_START limit: the Ack limit plus one MA period. Computed every clock from the
        # latched values; valid one clock after the latch, first read in CLOCK (WAIT_READY
        # lasts at least one clock).
        no_start_limit = Signal(tw + 1)
        m.d.sync += no_start_limit.eq(ack_limit + Cat(C(0, 1), cfg.cfg_ma_half_period))
        word_count = (1 + cfg.cfg_w1_enable) if two else 1

        m.d.comb += [
            ma_clock.half_period.eq(cfg.cfg_ma_half_period),
            sampler.slo.eq(slo),
            sampler.half_period.eq(cfg.cfg_ma_half_period),
            decoder.sample.eq(sampler.sample),
            decoder.bit.eq(sampler.bit),
            decoder.word_count.eq(word_count),
            self.ma.eq(ma_clock.ma),
        ]
        for w in range(p.words):
            word = decoder.words[w]
            m.d.comb += [
                word.data_bits.eq(cfg[f"cfg_w{w}_data_bits"]),
                word.nenw.eq(cfg[f"cfg_w{w}_nenw"]),
                word.lc.eq(cfg[f"cfg_w{w}_lc"]),
                word.crc.eq(cfg[f"cfg_w{w}_crc"]),
            ]

        # -- Free-running time base and the SLO-low timer -----------------------------------
        if p.timestamped:
            now = Signal(p.timestamp_width)
            m.d.sync += now.eq(now + 1)
            first_rise_time = Signal(p.timestamp_width)
            with m.If(ma_clock.first_rise):
                m.d.sync += first_rise_time.eq(now)

        # How long SLO has been low, plus one (saturating at 2**tw: SLO low for 2**tw - 1
        # clocks or more). The "+ 1" turns the one-clock-ahead compare below into a plain one.
        # Counted only while MA is idle: the encoder's timeout starts when MA stops, and the
        # trailing zero bits of a frame (up to 6 CRC bits and the stop bit, 90 us at 80 kHz)
        # must not count towards SLO_STUCK_LOW.
        slo_low_time_p1 = Signal(tw + 1, init=1)
        with m.If(slo | ma_clock.busy):
            m.d.sync += slo_low_time_p1.eq(1)
        with m.Elif(~slo_low_time_p1[tw]):
            m.d.sync += slo_low_time_p1.eq(slo_low_time_p1 + 1)
        # ``SLO-low time >= timeout limit``, registered one clock ahead: the next SLO-low time
        # is 0 (never >= a limit >= 1) or, saturating, this one + 1. WAIT_READY reads it. In
        # its first clock the limit was latched only at the clock edge that began it, so that
        # clock uses the flag computed from the live setting.
        stuck_latched = Signal()
        stuck_live = Signal()
        latched = Signal()      # the previous clock was IDLE: in WAIT_READY, its first clock
        m.d.sync += [
            stuck_latched.eq(~slo & ~ma_clock.busy & (slo_low_time_p1 >= timeout_limit)),
            stuck_live.eq(~slo & ~ma_clock.busy & Mux(live.cfg_timeout_limit == 0,
                                     slo_low_time_p1 >= p.timeout_limit_default,
                                     slo_low_time_p1 >= live.cfg_timeout_limit)),
            latched.eq(idle),
        ]
        slo_stuck = Mux(latched, stuck_live, stuck_latched)

        # Clocks since the timer was cleared, *plus one*: a clear loads 1. So ``timer`` is
        # already the value the elapsed time will have in the next clock, and the flags below,
        # registered one clock ahead, compare it with a limit directly (no "+ 1" or "- 1"
        # adder in series with the comparator). One bit more than the limits: Ack limit + 2
        # half periods. Saturates (far above every limit).
        timer = Signal(tw + 1, init=1)
        timer_clear = Signal()
        m.d.sync += timer.eq(Mux(timer_clear, 1, Mux(timer.all(), timer, timer + 1)))
        # ``timer >= limit`` for the Ack and NO_START limits: see the cycle controller.
        ack_expired = Signal()
        no_start_expired = Signal()
        # BREAK reads cfg_break_time live: ``elapsed >= break time``, registered one clock
        # ahead like the limits below (the next elapsed time is 0 after a clear, never >= a
        # time >= 1, or else ``timer``), from the setting of the clock before. Both compares
        # in parallel, then the default mux.
        break_over = Signal()
        m.d.sync += break_over.eq(~timer_clear & Mux(live.cfg_break_time == 0,
                                                     timer >= p.break_default,
                                                     timer >= live.cfg_break_time))

        # -- Requests ---------------------------------------------------------------------
        # Clocks since the last tick, plus one: the period restarts when it reaches the live
        # cfg_request_period (one compare, no "- 1" in front of it). It never exceeds
        # 2**tw - 1: it only counts up while below the period.
        period_count_p1 = Signal(tw, init=1)
        # ``period_count_p1 == 1``, kept as a register (written with it; the count never
        # wraps to 1): no wide compare in front of the request decode.
        period_start = Signal(init=1)
        as_fast_as_possible = self.periodic & (self.cfg_request_period == 0)
        tick = self.periodic & ~as_fast_as_possible & period_start
        with m.If(~self.periodic | as_fast_as_possible
                  | (period_count_p1 >= self.cfg_request_period)):
            m.d.sync += [period_count_p1.eq(1), period_start.eq(1)]
        with m.Else():
            m.d.sync += [period_count_p1.eq(period_count_p1 + 1), period_start.eq(0)]
        request = self.start | tick | as_fast_as_possible
        m.d.comb += self.overrun.eq((self.start | tick) & ~(idle & ~self.abort_cycle))

        # -- Frame verdict ----------------------------------------------------------------
        report_frame = Signal()         # the cycle controller reports the decoded frame
        crc_ok = [decoder.crc_ok[w] for w in range(p.words)]
        word1_on = cfg.cfg_w1_enable if two else C(0)
        word_crc_ok = [crc_ok[0], crc_ok[1] | ~word1_on] if two else [crc_ok[0]]
        crcs_ok = word_crc_ok[0] & word_crc_ok[-1]
        lc_on = cfg.cfg_w0_lc | (word1_on & cfg.cfg_w1_lc) if two else cfg.cfg_w0_lc
        lc_word_crc_ok = Mux(cfg.cfg_w0_lc, word_crc_ok[0], word_crc_ok[-1])
        m.d.comb += [
            sol.lc.eq(decoder.lc),
            sol.lc_next.eq(decoder.lc_next),
            sol.load.eq(decoder.lc_load),
            sol.check.eq(report_frame & lc_on & lc_word_crc_ok),
        ]
        lc_repeat = sol.check & sol.repeat
        lc_skip = sol.check & sol.skip
        lc_zero = sol.check & sol.zero
        if two:
            m.d.comb += [
                spw_check.cpw_top.eq(decoder.cpw_top),
                spw_check.spw.eq(decoder.data1),
                spw_check.bits.eq(cfg.cfg_w1_data_bits),
                spw_check.tolerance.eq(cfg.cfg_spw_tolerance),
            ]
            mismatch = cfg.cfg_spw_check & word1_on & crcs_ok & ~spw_check.match
        else:
            mismatch = C(0)

        frame_status = Signal(Status)
        with m.If(~word_crc_ok[0] & ~word_crc_ok[-1]):
            m.d.comb += frame_status.eq(Status.CRC_ERROR_BOTH if two else Status.CRC_ERROR_WORD0)
        with m.Elif(~word_crc_ok[0]):
            m.d.comb += frame_status.eq(Status.CRC_ERROR_WORD0)
        with m.Elif(~word_crc_ok[-1]):
            m.d.comb += frame_status.eq(Status.CRC_ERROR_WORD1)
        with m.Elif(lc_repeat | lc_skip | lc_zero):
            m.d.comb += frame_status.eq(Status.SIGN_OF_LIFE)
        with m.Elif(mismatch):
            m.d.comb += frame_status.eq(Status.SPW_MISMATCH)
        with m.Else():
            m.d.comb += frame_status.eq(Status.OK)

        # -- Cycle controller ---------------------------------------------------------------
        report = Signal()               # end of a request cycle: strobe done, set status
        report_status = Signal(Status)
        report_delay = Signal()         # ... with a measured delay
        resync = Signal()               # encoder reset: the next LC is accepted as it is
        target_rises = Signal(17)       # MA rising edges the frame needs, once Start is seen
        started = Signal()
        # ``decoder.frame_bits + 4``, from the cycle's configuration in two register stages
        # (valid two clocks after the latch; first read when Start has been sampled).
        word_len = [Signal(8, name=f"word{w}_len") for w in range(p.words)]
        frame_len_p4 = Signal(9)
        m.d.sync += [
            word_len[0].eq(word_length(decoder.words[0], extra=4, width=8)),
            frame_len_p4.eq(word_len[0] + (Mux(cfg.cfg_w1_enable, word_len[1], 0) if two else 0)),
        ]
        if two:
            m.d.sync += word_len[1].eq(word_length(decoder.words[1], width=8))
        m.d.sync += [
            target_rises.eq(decoder.start_slot + frame_len_p4),
            started.eq(decoder.started),
        ]
        # Enough MA rising edges for the frame, registered (a 17-bit compare is too slow in
        # front of the MA generator). The lag is harmless for ``rises``: it changes at a rising
        # edge and the MA generator reads ``run`` only at the end of the high phase, >= 2
        # clocks later. ``started`` and ``target_rises`` change together (both registered from
        # the decoder), so the flag sees them consistently, one clock late: when the round
        # trip is longer than the frame, MA may stop one clock (rarely one period) later. The
        # receiver is cleared before every cycle, so the flag is 0 in a cycle's first clock.
        ma_enough = Signal()
        m.d.sync += ma_enough.eq(started & (ma_clock.rises >= target_rises) & ~receiver_clear)
        locked_seen = Signal()
        armed = Signal()
        arm = ma_clock.second_rise
        in_clock = Signal()                 # the controller is in CLOCK
        restart_timer = arm | (sampler.locked & ~locked_seen)      # in CLOCK
        # CLOCK compares the elapsed time with the Ack and NO_START limits. Both flags are
        # registered one clock ahead: the next elapsed time is 0 (cleared; never >= a limit
        # >= 1) or ``timer`` (see above). They need to be right only in CLOCK: after a clock
        # in CLOCK that stays there (it clears the timer on ``restart_timer`` and on an abort,
        # which leaves CLOCK), or after WAIT_READY (timer cleared). The limits are constant
        # from the latch on.
        m.d.sync += [
            ack_expired.eq(in_clock & ~restart_timer & (timer >= ack_limit)),
            no_start_expired.eq(in_clock & ~restart_timer & (timer >= no_start_limit)),
        ]
        m.d.comb += sampler.arm.eq(arm)
        # The measured delay is final at least two clocks before ``sampler.locked`` rises (the
        # first sample comes half an MA period, >= 2 clocks, after the Ack edge), and the
        # check below reads it only then: compare it a clock early, registered.
        delay_over = Signal()
        m.d.sync += delay_over.eq(sampler.delay > delay_limit)

        # One strobe per fault status, set only where that fault is reported: the counters
        # decode these directly, not the status mux.
        fault_event = {status: Signal(name=f"fault_{status.name.lower()}") for status in Status}

        # A fault does not clear the timer itself: every state a fault can come from clears
        # it (IDLE, WAIT_READY: always; CLOCK: on ``abort_cycle``), or MA is still running
        # when BREAK begins (the line faults of CLOCK come before Start, so MA runs on), and
        # BREAK clears it until MA has stopped. That keeps the fault decode out of the
        # timer's enable.
        def fault(status, next_state="BREAK"):
            m.d.comb += [report.eq(1), report_status.eq(status), fault_event[status].eq(1)]
            m.next = next_state

        def report_verdict():
            """Report the decoded frame: its verdict, fields and line delay."""
            m.d.comb += [report.eq(1), report_status.eq(frame_status), report_frame.eq(1),
                         report_delay.eq(1)]

        with m.FSM(init="BREAK", name="cycle_fsm"):
            # MA high for the break time: power-up, after an abort, after a line fault.
            with m.State("BREAK"):
                m.d.comb += [receiver_clear.eq(1), resync.eq(1)]
                with m.If(ma_clock.busy | self.abort_cycle):
                    m.d.comb += timer_clear.eq(1)
                with m.Elif(break_over):
                    m.next = "IDLE"

            with m.State("IDLE"):
                # The timer is not read in IDLE, and every way out of it (BREAK, WAIT_READY)
                # starts from 0: hold it at 0 here, whatever the request decode says.
                m.d.comb += [idle.eq(1), receiver_clear.eq(1), timer_clear.eq(1)]
                with m.If(self.abort_cycle):
                    m.next = "BREAK"
                with m.Elif(request):
                    m.next = "WAIT_READY"

            # Never start while the encoder holds SLO low (its timeout is still running).
            with m.State("WAIT_READY"):
                m.d.comb += receiver_clear.eq(1)
                m.d.comb += timer_clear.eq(1)
                m.d.sync += [armed.eq(0), locked_seen.eq(0)]
                with m.If(latched & ~cfg_ok):
                    # The configuration latched at the request is invalid: no cycle. Nothing
                    # has reached the line. An abort now is handled as IDLE would have.
                    fault(Status.BAD_CONFIG, "IDLE")
                    with m.If(self.abort_cycle):
                        m.next = "BREAK"
                with m.Elif(self.abort_cycle):
                    fault(Status.ABORTED)
                with m.Elif(slo):
                    m.next = "CLOCK"
                with m.Elif(slo_stuck):
                    fault(Status.SLO_STUCK_LOW)

            # MA runs; the sampler and decoder follow SLO, the line delay behind.
            with m.State("CLOCK"):
                m.d.comb += [ma_clock.run.eq(~ma_enough), in_clock.eq(1)]
                with m.If(restart_timer | self.abort_cycle):
                    m.d.comb += timer_clear.eq(1)
                with m.If(arm):
                    m.d.sync += armed.eq(1)
                with m.If(sampler.locked & ~locked_seen):
                    m.d.sync += locked_seen.eq(1)
                # The end of the frame comes right after the abort: it excludes every line
                # fault below (those all come before the first sample, or before Start), so
                # this order reports the same as theirs, with fewer gates in front of the
                # frame's verdict.
                with m.If(self.abort_cycle):
                    fault(Status.ABORTED)
                with m.Elif(decoder.done):
                    # With the end check the verdict waits for the end of the frame (CONFIRM).
                    with m.If(~cfg.cfg_end_check):
                        report_verdict()
                    m.next = "TAIL"
                with m.Elif(armed & sampler.early):
                    fault(Status.DELAY_RANGE)
                with m.Elif(armed & ~locked_seen & ~sampler.locked & ack_expired):
                    fault(Status.NO_ACK)
                with m.Elif(sampler.locked & ~locked_seen & delay_over):
                    m.d.comb += report_delay.eq(1)
                    fault(Status.DELAY_RANGE)
                with m.Elif(locked_seen & ~decoder.started
                            & (no_start_expired | decoder.slots_full)):
                    fault(Status.NO_START)

            # Clock out the stop bit and let the sampler see it. Without the end check the
            # frame is reported already; with it, nothing is, and the faults below (and an
            # abort) replace the frame's verdict. They clear the timer themselves: MA may
            # have stopped already, and the break must then start from 0.
            with m.State("TAIL"):
                m.d.comb += ma_clock.run.eq(~ma_enough)
                with m.If(self.abort_cycle):
                    m.d.comb += timer_clear.eq(1)
                    with m.If(cfg.cfg_end_check):
                        fault(Status.ABORTED)
                    with m.Else():
                        m.next = "BREAK"
                with m.Elif(decoder.stopped):
                    with m.If(~cfg.cfg_end_check):
                        m.next = "END"
                    with m.Elif(decoder.stop_bit):
                        # A good encoder holds SLO low from the stop bit through its timeout.
                        # High here: the line went (or is stuck) high, or the frame is longer
                        # than configured. Either way the bits before it are not trusted: a
                        # stuck tail can be a CRC codeword.
                        m.d.comb += timer_clear.eq(1)
                        fault(Status.NO_STOP)
                    with m.Else():
                        m.next = "CONFIRM"
            with m.State("END"):
                with m.If(~ma_clock.busy):
                    m.next = "IDLE"
            # End check: the frame counts only once the encoder's timeout has ended (SLO back
            # high with MA stopped). SLO held low past the timeout limit is a line stuck low,
            # whose tail can also be a CRC codeword.
            with m.State("CONFIRM"):
                with m.If(self.abort_cycle):
                    m.d.comb += timer_clear.eq(1)
                    fault(Status.ABORTED)
                with m.Elif(~ma_clock.busy & slo):
                    report_verdict()
                    m.next = "IDLE"
                with m.Elif(stuck_latched):
                    m.d.comb += timer_clear.eq(1)
                    fault(Status.SLO_STUCK_LOW)

        m.d.comb += [
            self.busy.eq(~idle),
            sol.resync.eq(resync),
        ]

        # -- Results ------------------------------------------------------------------------
        m.d.sync += [
            self.done.eq(report),
            self.valid.eq(report_frame & (frame_status == Status.OK)),  # faults are never OK
        ]
        with m.If(report):
            m.d.sync += self.status.eq(report_status)
        with m.If(report_delay):
            m.d.sync += self.line_delay.eq(sampler.delay)
        with m.If(report_frame):
            if p.timestamped:
                m.d.sync += self.timestamp.eq(first_rise_time)
            m.d.sync += [
                self.cds.eq(decoder.cds),
                self.lc.eq(decoder.lc),
                self.lc_repeat.eq(lc_repeat),
                self.lc_skip.eq(lc_skip),
                self.lc_zero.eq(lc_zero),
            ]
            for w in range(p.words):
                m.d.sync += [
                    getattr(self, f"word{w}_position").eq(getattr(decoder, f"data{w}")),
                    getattr(self, f"word{w}_ne").eq(decoder.ne[w]),
                    getattr(self, f"word{w}_nw").eq(decoder.nw[w]),
                    getattr(self, f"word{w}_crc_ok").eq(word_crc_ok[w]),
                ]
            if two:
                m.d.sync += self.spw_mismatch.eq(mismatch)

        # -- Error counters -----------------------------------------------------------------
        events = {
            "crc_word0": report_frame & ~word_crc_ok[0],
            "no_ack": fault_event[Status.NO_ACK],
            "no_start": fault_event[Status.NO_START],
            "delay_range": fault_event[Status.DELAY_RANGE],
            "slo_stuck_low": fault_event[Status.SLO_STUCK_LOW],
            "lc_repeat": report_frame & lc_repeat,
            "lc_skip": report_frame & lc_skip,
            "lc_zero": report_frame & lc_zero,
            "overrun": self.overrun,
            "aborted": fault_event[Status.ABORTED],
            "no_stop": fault_event[Status.NO_STOP],
        }
        if two:
            events["crc_word1"] = report_frame & ~word_crc_ok[1]
            events["spw_mismatch"] = report_frame & mismatch
        for name in self.counter_names:
            m.submodules[f"count_{name}"] = counter = SaturatingCounter(p.counter_width)
            m.d.comb += [
                counter.inc.eq(events[name]),
                counter.clear.eq(self.clear_counters),
                getattr(self, f"count_{name}").eq(counter.count),
            ]

        return m
