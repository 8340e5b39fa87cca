"""Runtime configuration: checked live, latched for the cycle, zero replaced by the defaults."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from ..layouts import config_custom_crcs, config_enables, config_layout, config_words
from ..params import CRC_MAX_WIDTH, CRC_SETTINGS, QUIET_WIDTH, Crc
from .const_compare import above, at_most
from .crc_engine import crc_settings, crc_width


class Configuration(wiring.Component):
    """The configuration a request cycle runs with.

    The check is registered from the live inputs in every clock (``ok``, shown on the
    ``config_error`` port inverted). While ``idle`` is high, ``cycle`` copies the live inputs in
    every clock, so the last copy is the one of the accepted request (the clock the controller
    leaves IDLE). In the cycle's first clock ``ok`` is therefore the verdict on exactly the
    configuration the cycle latched: the controller refuses it there. Nothing reads ``cycle`` while
    idle (MA stopped, receiver held in reset, no frame reported), so copying in every idle clock
    is the same as latching on acceptance, without the request decode in the enable.

    A ``config_hold`` build (the bus tops) copies nothing: its ``live`` inputs change only in
    the clock after one with the controller in IDLE and held there (``MasterParams``), so
    ``cycle`` is ``live`` itself, the same values through the cycle as a copy would hold.

    The time limits are resolved (0 -> protocol default) in the same latch, so that no default
    mux sits in front of a comparator. Every default is >= 1, so each limit is >= 1.

    Parameters
    ----------
    params : MasterParams

    Attributes
    ----------
    live : In(config_layout)
        The ``cfg_*`` ports.
    idle : In(1)
        The controller is in IDLE: copy ``live`` into ``cycle``.
    ok : Out(1)
        ``live`` of the previous clock is within what this hardware can do (registered).
    cycle : Out(config_layout)
        The cycle's configuration.
    ack_limit, timeout_limit : Out(timer_width)
        ``cfg_ack_limit`` and ``cfg_timeout_limit`` of the cycle, 0 replaced by the default.
    delay_limit : Out(delay_limit_width)
        ``cfg_delay_limit`` of the cycle, 0 replaced by ``max_line_delay``.
    quiet_time : Out(12)
        ``cfg_quiet_time`` of the cycle, 0 replaced by ``quiet_default``.
    delay_tolerance : Out(params.delay_tolerance_width)
        The round-trip check's tolerance for the cycle: its half period plus
        ``cfg_delay_tolerance`` (0 replaced by the default, 2 clocks): a jittered Ack edge moves
        by up to a quarter MA period each way (docs/ports.md, "Noise: the line checks").
    no_start_limit : Out(cycle_timer_width)
        The Ack limit plus one MA period plus one clock (NO_START; the clock is the register
        between sampler and decoder), registered from the latched values: valid
        one clock after the latch (the controller reads it in CLOCK, after at least one clock in
        WAIT_READY).
    word_count : Out(range(1, words + 1))
        Words in the cycle's frame.
    crc_widths : Out(ArrayLayout(range(CRC_MAX_WIDTH + 1), words))
        Each word's CRC width for the cycle, its code resolved: a named CRC's width, a custom
        CRC's ``cfg_wN_crc_width``, 0 for none. Builds of 2+ words resolve it from ``cycle``
        (combinational; its readers, the field ends and the frame length, register what they
        compute from it, and the CRC engine resolves the rest of a word's CRC as the word
        begins); one-word builds take it from ``crc``.
    crc : Out(CRC_SETTINGS)
        One-word builds: the word's CRC resolved (width, polynomial, start, inversion), latched
        with ``cycle``: the CRC engine reads flip-flops, and the copy of the raw custom
        settings in ``cycle`` goes unread.
    """

    def __init__(self, params):
        self._params = p = params
        tw = p.timer_width
        super().__init__({
            "live": In(config_layout(p)),
            "idle": In(1),
            "ok": Out(1),
            "cycle": Out(config_layout(p)),
            "ack_limit": Out(tw),
            "timeout_limit": Out(tw),
            "delay_limit": Out(p.delay_limit_width),
            "quiet_time": Out(QUIET_WIDTH),
            "delay_tolerance": Out(p.delay_tolerance_width),
            "no_start_limit": Out(p.cycle_timer_width),
            "word_count": Out(range(1, p.words + 1)),
            "crc_widths": Out(data.ArrayLayout(range(CRC_MAX_WIDTH + 1), p.words)),
            **({"crc": Out(CRC_SETTINGS)} if p.words == 1 else {}),
        })

    def valid(self, cfg):
        """Combinational: is ``cfg`` within what this hardware can do?"""
        p = self._params

        customs = config_custom_crcs(cfg, p)

        def word_ok(word, w):
            crc_ok = word.crc == Crc.NONE
            for kind in p.word_crcs[w]:
                crc_ok |= word.crc == kind
            if p.custom_crc:
                width = customs[w].width
                crc_ok |= (word.crc == Crc.CUSTOM) & (width != 0) & at_most(width, CRC_MAX_WIDTH)
            # Compares with constants as logic (const_compare: no carry chain each).
            return (word.data_bits.any() & at_most(word.data_bits, p.max_data_bits[w])
                    & crc_ok)

        words = config_words(cfg, p)
        assert protocol.MA_HALF_PERIOD_MIN == 2
        ok = cfg.ma_half_period[1:].any() & word_ok(words[0], 0)        # half period >= 2
        if p.max_line_delay < 2**p.delay_limit_width - 1:
            ok &= at_most(cfg.delay_limit, p.max_line_delay)
        enables = config_enables(cfg, p)
        for w in range(1, p.words):
            ok &= ~enables[w] | word_ok(words[w], w)
            if w >= 2:
                ok &= ~enables[w] | enables[w - 1]          # the frame's words come in order
        if p.words >= 2:
            # One LC per frame (one sign-of-life tracker).
            lc_words = [enables[w] & words[w].lc for w in range(p.words)]
            for a in range(p.words):
                for b in range(a + 1, p.words):
                    ok &= ~(lc_words[a] & lc_words[b])
            w1 = cfg.w1_enable
            # The SPW check needs an SPW no longer than the CPW, and its CRC (the check is
            # read after the CRC bits; see SpwCheck).
            ok &= ~cfg.spw_check | (w1 & (cfg.w1.data_bits <= cfg.w0.data_bits)
                                    & (cfg.w1.crc != Crc.NONE))
        if p.ssi:
            # SSI: one word, no sign of life, nE/nW or the error bit (not both), no SPW check
            # (docs/ports.md, "SSI mode"); a round trip the sampler can count to.
            ssi_bad = cfg.w0.lc | (cfg.ssi_error & cfg.w0.nenw)
            if p.words >= 2:
                ssi_bad |= cfg.spw_check
            for w in range(1, p.words):
                ssi_bad |= enables[w]
            if p.max_line_delay < 2**p.delay_limit_width - 1:
                ssi_bad |= above(cfg.ssi_delay, p.max_line_delay)
            ok &= ~(cfg.ssi & ssi_bad)
        return ok

    def elaborate(self, platform):
        m = Module()
        p = self._params
        live, cycle = self.live, self.cycle

        def or_default(value, default):
            return Mux(value == 0, default, value)

        # Check every clock; latch and resolve the limits while idle.
        m.d.sync += self.ok.eq(self.valid(live))
        if p.config_hold:
            m.d.comb += cycle.eq(live)
        else:
            with m.If(self.idle):
                m.d.sync += cycle.eq(live)
        with m.If(self.idle):
            m.d.sync += [
                self.ack_limit.eq(or_default(live.ack_limit, p.ack_limit_default)),
                self.timeout_limit.eq(or_default(live.timeout_limit, p.timeout_limit_default)),
                self.delay_limit.eq(or_default(live.delay_limit, p.max_line_delay)),
                self.quiet_time.eq(or_default(live.quiet_time, p.quiet_default)),
                self.delay_tolerance.eq(live.ma_half_period
                                        + or_default(live.delay_tolerance,
                                                     protocol.DELAY_TOLERANCE_DEFAULT)),
            ]
        # NO_START: the Ack limit plus one MA period (two half periods) plus one clock: the
        # controller sees Start one clock later after its decision than the Ack's (the register
        # between sampler and decoder), so the same decisions pass as with the Ack limit alone.
        m.d.sync += self.no_start_limit.eq(self.ack_limit + Cat(C(1, 1), cycle.ma_half_period))
        if p.words == 1:
            customs = config_custom_crcs(live, p) or [None]
            with m.If(self.idle):
                m.d.sync += self.crc.eq(crc_settings(live.w0.crc, customs[0], p.word_crcs[0]))
            m.d.comb += self.crc_widths[0].eq(self.crc.width)
        else:
            customs = config_custom_crcs(cycle, p) or [None] * p.words
            for w, word in enumerate(config_words(cycle, p)):
                m.d.comb += self.crc_widths[w].eq(crc_width(word.crc, customs[w],
                                                            p.word_crcs[w]))
        # The words in the frame: word 0 and the enabled ones after it (in order: a gap is
        # refused above).
        m.d.comb += self.word_count.eq(sum(config_enables(cycle, p)))
        return m
