"""The verdict on a cycle: status priority, ``valid``, and the checks' flags for the results."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..layouts import config_enables, config_layout, config_words
from ..params import Status


class FrameVerdict(wiring.Component):
    """Judges the decoded frame when the controller reports it, and forwards a fault otherwise.

    All combinational, from flip-flops: the CRC checkers', the sign-of-life tracker's and the
    SPW check's outputs are registered in their blocks, so the verdict is one small decode.

    A frame's status is the lowest-numbered that applies (docs/ports.md): a CRC error makes the
    LC meaningless, an LC error makes the plausibility check moot. A word that is not in the
    frame (word ``N`` with ``cfg_wN_enable`` = 0) counts as CRC-good. In a frame of more than two
    words (a chain) CRC_ERROR_WORD1 stands for "a word after word 0", CRC_ERROR_BOTH for "word
    0 and a word after it"; ``word_crc_ok`` says which.

    The sign of life is judged (``lc_check``, which also stores the new LC in the tracker) only
    for a reported frame whose LC-carrying word passed its CRC.

    Parameters
    ----------
    params : MasterParams

    Attributes
    ----------
    cfg : In(config_layout)
        The cycle's configuration.
    report_frame : In(1)
        From the controller: report the decoded frame now.
    fault : In(1)
    fault_status : In(Status)
        From the controller: the cycle ended without a frame, with this status.
    crc_ok : In(words)
        Each word's CRC checker.
    lc_repeat_seen, lc_skip_seen, lc_zero_seen : In(1)
        The sign-of-life tracker's flags for the frame's LC.
    spw_match : In(1)
        The SPW check (two-word builds).
    copy_mismatch : In(1)
        SSI builds: the two copies of an SSI double transmission differ (the decoder's
        ``mismatch``; read only with ``cfg.ssi``): SPW_MISMATCH, as a plausibility fault.
    noisy : In(1)
        The line-noise judgement of the frame (:class:`~bissmaster.core.line_noise.LineNoise`),
        final from the decoder's ``done`` on.
    delay_jump : In(1)
        The round trip left the settled one (:class:`~bissmaster.core.delay_check.DelayCheck`),
        final long before ``done``.
    unconfirmed : In(1)
        A frame that passes every check is UNCONFIRMED, not OK
        (:class:`~bissmaster.core.confirmation.Confirmation`, registered).
    lc_check : Out(1)
        Judge and store the LC (to the tracker).
    clean : Out(1)
        Every check but the round trip's passes (to the delay check, with ``report_frame``).
    report : Out(1)
        A cycle ends in this clock (``done`` one clock later).
    status : Out(Status)
        The status to report (valid with ``report``).
    valid : Out(1)
        ``report_frame`` with status OK.
    passed : Out(1)
        ``report_frame`` with status OK or UNCONFIRMED: the frame passed every check (what the
        control channel's CDS bit needs; it has its own CRC-4).
    doubtful : Out(1)
        The frame's status will not be OK (a CRC, sign-of-life, plausibility or line fault): the frame
        may have been misread, and the controller pauses before the next cycle. Not gated by
        ``report_frame``: final from the decoder's ``done`` on, so the controller can register
        it there (no verdict logic in front of its transitions).
    word_crc_ok : Out(words)
        Per word, the CRC verdict as reported (a word not in the frame is good).
    lc_repeat, lc_skip, lc_zero, spw_mismatch : Out(1)
        The flags as reported with the frame (``spw_mismatch``: the SPW check, or an SSI
        double transmission's copies).
    crc_error : Out(words)
        Event strobes: a reported frame's word failed its CRC.
    """

    def __init__(self, params):
        self._params = p = params
        super().__init__({
            "cfg": In(config_layout(p)),
            "report_frame": In(1),
            "fault": In(1),
            "fault_status": In(Status),
            "crc_ok": In(p.words),
            "lc_repeat_seen": In(1),
            "lc_skip_seen": In(1),
            "lc_zero_seen": In(1),
            "spw_match": In(1),
            "copy_mismatch": In(1),
            "noisy": In(1),
            "delay_jump": In(1),
            "unconfirmed": In(1),
            "lc_check": Out(1),
            "clean": Out(1),
            "report": Out(1),
            "status": Out(Status),
            "valid": Out(1),
            "passed": Out(1),
            "doubtful": Out(1),
            "word_crc_ok": Out(p.words),
            "lc_repeat": Out(1),
            "lc_skip": Out(1),
            "lc_zero": Out(1),
            "spw_mismatch": Out(1),
            "crc_error": Out(p.words),
        })

    def elaborate(self, platform):
        m = Module()
        p = self._params
        cfg = self.cfg
        two = p.words >= 2
        words, on = config_words(cfg, p), config_enables(cfg, p)

        # CRCs: a word not in the frame is good.
        m.d.comb += self.word_crc_ok.eq(Cat(self.crc_ok[0], *(self.crc_ok[w] | ~on[w]
                                                              for w in range(1, p.words))))
        ok = self.word_crc_ok
        crcs_ok = ok.all()
        later_ok = ok[1:].all() if two else C(1)        # every word after word 0

        # Sign of life: judged for the word that carries it (one per frame: Configuration),
        # when its CRC is good.
        carries = [on[w] & words[w].lc for w in range(p.words)]
        lc_on = Cat(*carries).any()
        lc_word_crc_ok = ok[-1]
        for w in reversed(range(p.words - 1)):
            lc_word_crc_ok = Mux(carries[w], ok[w], lc_word_crc_ok)
        m.d.comb += [
            self.lc_check.eq(self.report_frame & lc_on & lc_word_crc_ok),
            self.lc_repeat.eq(self.lc_check & self.lc_repeat_seen),
            self.lc_skip.eq(self.lc_check & self.lc_skip_seen),
            self.lc_zero.eq(self.lc_check & self.lc_zero_seen),
        ]

        # Plausibility: only between two CRC-good words (or copies).
        implausible = C(0)
        if two:
            implausible |= cfg.spw_check & on[1] & ~self.spw_match
        if p.ssi:
            implausible |= cfg.ssi & self.copy_mismatch
        m.d.comb += self.spw_mismatch.eq(crcs_ok & implausible)

        # Status priority: the first condition that holds (a one-word build has one CRC).
        # CRC_ERROR_WORD1 stands for any word after word 0 (a chain's: ``word_crc_ok`` tells
        # which).
        if two:
            crc_order = [(~ok[0] & ~later_ok, Status.CRC_ERROR_BOTH),
                         (~ok[0], Status.CRC_ERROR_WORD0), (~later_ok, Status.CRC_ERROR_WORD1)]
        else:
            crc_order = [(~ok[0], Status.CRC_ERROR_WORD0)]
        order = crc_order + [
            (self.lc_repeat | self.lc_skip | self.lc_zero, Status.SIGN_OF_LIFE),
            (self.spw_mismatch, Status.SPW_MISMATCH),
            (self.noisy, Status.NOISY_LINE),
            (self.delay_jump, Status.DELAY_JUMP),
            (self.unconfirmed, Status.UNCONFIRMED),     # a frame that passed every check
        ]
        frame_status = Signal(Status)
        m.d.comb += frame_status.eq(Status.OK)
        for condition, status in reversed(order):      # the last assignment wins
            with m.If(condition):
                m.d.comb += frame_status.eq(status)

        m.d.comb += [
            self.report.eq(self.report_frame | self.fault),
            self.status.eq(Mux(self.report_frame, frame_status, self.fault_status)),
            self.valid.eq(self.report_frame & (frame_status == Status.OK)),   # faults never OK
            self.passed.eq(self.report_frame & ((frame_status == Status.OK)
                                                | (frame_status == Status.UNCONFIRMED))),
            # The same verdict without the report gate: final from the decoder's ``done`` on
            # (CRCs, LC flags and the SPW check are registered and settled by then).
            self.doubtful.eq(~crcs_ok | self.spw_mismatch | lc_on & lc_word_crc_ok
                             & (self.lc_repeat_seen | self.lc_skip_seen | self.lc_zero_seen)
                             | self.noisy | self.delay_jump),
            self.clean.eq(crcs_ok & ~self.spw_mismatch & ~self.noisy
                          & ~(self.lc_repeat | self.lc_skip | self.lc_zero)),
            self.crc_error.eq(Mux(self.report_frame, ~ok, 0)),
        ]
        return m
