"""When MA has clocked out enough rising edges for the whole frame."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .field_ends import word_length
from .word_select import select_word
from ..params import CRC_MAX_WIDTH, SLOT_WIDTH, WORD_CONFIG, frame_length_width


#: Slot ``k`` is the bit the encoder puts on SLO at MA rising edge ``k + 2`` (SloSampler). Start
#: in slot ``s`` comes at rise ``s + 2``, CDS at ``s + 3``, ``N`` word bits, and the stop bit at
#: rise ``s + N + 4``: the frame needs ``s + N + 4`` rising edges.
RISES_BEYOND_WORDS = 4
#: SSI (no Ack, Start or CDS): the word's ``N`` bits come at rises 1..N, the bit after it (0
#: from a good encoder) at rise ``N + 1``; a double transmission is ``N`` bits, one separator,
#: ``N`` bits and that last bit: ``2 N + 2`` rises.
SSI_RISES_BEYOND_WORD = 1


class MaStop(wiring.Component):
    """``enough``: MA has made every rising edge the frame needs; the controller stops MA.

    Once Start is seen in slot ``start_slot``, the frame needs ``start_slot + words' bits + 4``
    rising edges. A one-word build registers it from the cycle's configuration in two stages
    (valid two clocks after the latch; first read when Start has been sampled); a build of more
    words sums it one word per clock after the receiver's clear and reads it once whole
    (:meth:`_sum_words`: ``words + 2`` clocks after the clear). The compare is registered (a wide compare is too slow in front of the MA generator). The lag is harmless:
    ``rises`` changes at a rising edge and the MA generator reads ``run`` only at the end of the
    high phase, >= 2 clocks later. ``started`` and the target change together (both registered
    from the decoder), so the flag sees them consistently, one clock late: when the round trip
    is longer than the frame, MA may stop one clock (rarely one period) later. ``clear`` (the
    receiver's clear, high before every cycle) keeps the flag 0 in a cycle's first clock.

    In SSI (``ssi``) the frame needs the word's bits plus 1 rises, or twice that with
    ``ssi_double``, counted from the first rise (``start_slot`` is 0): MA stops after exactly
    those, whatever the round trip. The sum takes one register stage more (valid three clocks
    after the latch, before the first rise can come).

    Parameters
    ----------
    words : int
        Words the build can decode (1 .. :data:`~bissmaster.params.MAX_WORDS`).
    ssi : bool
        Build the SSI inputs.

    Attributes
    ----------
    words : In(ArrayLayout(WORD_CONFIG, words))
        The cycle's word settings.
    crc_widths : In(ArrayLayout(range(CRC_MAX_WIDTH + 1), words))
        Their CRCs' widths (Configuration.crc_widths).
    enables : In(words)
        Which words are in the frame (bit 0, word 0, is not read: it always is).
    started : In(1)
        The decoder has seen Start ...
    start_slot : In(16)
        ... in this slot.
    rises : In(16)
        MA rising edges so far (MaClock).
    clear : In(1)
    enough : Out(1)
    ssi, ssi_double, ssi_error : In(1)
        SSI builds: the cycle is an SSI frame; its word comes twice; its word has an error bit.
    """

    def __init__(self, words, ssi=False, word_layout=WORD_CONFIG):
        self._words = words
        self._ssi = ssi
        super().__init__({
            "words": In(data.ArrayLayout(word_layout, words)),
            "crc_widths": In(data.ArrayLayout(range(CRC_MAX_WIDTH + 1), words)),
            "enables": In(words),
            "started": In(1),
            "start_slot": In(SLOT_WIDTH),
            "rises": In(SLOT_WIDTH),
            "clear": In(1),
            "enough": Out(1),
            **({"ssi": In(1), "ssi_double": In(1), "ssi_error": In(1)} if ssi else {}),
        })

    def elaborate(self, platform):
        m = Module()
        n_words = self._words
        width = frame_length_width(n_words)

        frame_len = Signal(width + 1)          # every word's bits + RISES_BEYOND_WORDS
        target_rises = Signal(SLOT_WIDTH + 1)
        started = Signal()
        if n_words == 1 or self._ssi:
            word_len0 = self._word0_length(m, width)
        # SSI: the frame starts with MA (the first rise), not when Start comes back: MA stops
        # after exactly its rises, however long the round trip. Every cycle has at least one
        # clock in WAIT_READY and a low phase of at least 2 clocks before its first rise: the
        # stages of the word's length have settled by then (one clock to spare).
        started_now = Mux(self.ssi, self.rises != 0, self.started) if self._ssi else self.started
        if n_words == 1:
            summed = C(1)
            m.d.sync += frame_len.eq(word_len0)
            frame = frame_len
        else:
            summed, frame = self._sum_words(m, frame_len, width)
            if self._ssi:
                # SSI frames have word 0 only (Configuration refuses more): its length at once.
                summed = summed | self.ssi
                frame = Mux(self.ssi, word_len0, frame)
        m.d.sync += [
            target_rises.eq(self.start_slot + frame),
            started.eq(started_now),
            self.enough.eq(started & summed & (self.rises >= target_rises) & ~self.clear),
        ]
        return m

    def _word0_length(self, m, width):
        """Word 0's rises, registered: its bits plus RISES_BEYOND_WORDS, or in SSI builds
        (``ssi``) the SSI frame's rises (one register stage more: the word's length, then the
        frame's by mode; one stage of both was the SSI build's critical path)."""
        word_len0 = Signal(width, name="word0_len")
        if self._ssi:
            n = Signal(width)
            m.d.sync += n.eq(word_length(self.words[0], self.crc_widths[0], width=width,
                                         error_bit=self.ssi & self.ssi_error))
            ssi_len = Mux(self.ssi_double, Cat(C(0, 1), n + SSI_RISES_BEYOND_WORD),
                          n + SSI_RISES_BEYOND_WORD)
            m.d.sync += word_len0.eq(Mux(self.ssi, ssi_len, n + RISES_BEYOND_WORDS))
        else:
            m.d.sync += word_len0.eq(word_length(self.words[0], self.crc_widths[0],
                                                 extra=RISES_BEYOND_WORDS, width=width))
        return word_len0

    def _sum_words(self, m, frame_len, width):
        """The BiSS frame's rises summed one word per clock from the receiver's clear (issue
        27: one word length behind a multiplexer instead of one per word and an N-way sum),
        from the cycle's configuration (latched before the clear drops). Two stages: the
        picked word's length is registered (0 when the word is not enabled), then added (word
        0's with RISES_BEYOND_WORDS, starting the sum); each is one adder deep. Word ``k``'s
        length is picked in clock ``k`` after the clear and added in clock ``k + 1``. Returns
        ``(summed, frame_len)``: ``summed`` is high from the clock ``target_rises`` holds the
        whole frame's target (``words + 2`` clocks after the clear), so that ``enough`` never
        reads a partial sum. That is long before it matters: the frame needs at least
        ``RISES_BEYOND_WORDS + 1`` rises, the first at least 2 clocks after the clear and the
        others at least 4 apart (half period >= 2), so at least 18 clocks, against at most
        10."""
        n_words = self._words
        k = Signal(range(n_words), name="sum_word")
        feeding = Signal(name="sum_feeding")        # words still to pick
        picked = Signal(width + 1, name="sum_length")
        picked_first = Signal(name="sum_first")
        picked_last = Signal(name="sum_last")
        adding = Signal(name="sum_adding")          # ``picked`` holds a word to add
        done = Signal(name="sum_done")
        summed = Signal(name="summed")
        # Word ``k``'s settings (``k`` = 0 from reset reads settings written long before:
        # select_word, not an Array).
        pick = select_word(k, [self.words[w] for w in range(n_words)])
        pick_crc = select_word(k, [self.crc_widths[w] for w in range(n_words)])
        # Word 0 is always in the frame (its enable is the constant 1, as config_enables).
        pick_on = select_word(k, [C(1, 1)] + [self.enables[w] for w in range(1, n_words)])
        m.d.sync += [
            picked.eq(Mux(pick_on, word_length(pick, pick_crc, width=width + 1), 0)),
            picked_first.eq(k == 0),
            picked_last.eq(k == n_words - 1),
            adding.eq(feeding & ~self.clear),
            summed.eq(done & ~self.clear),
        ]
        with m.If(self.clear):
            m.d.sync += [k.eq(0), feeding.eq(1), done.eq(0)]
        with m.Elif(feeding):
            m.d.sync += k.eq(k + 1)
            with m.If(k == n_words - 1):
                m.d.sync += feeding.eq(0)
        with m.If(adding & ~self.clear):
            m.d.sync += frame_len.eq(Mux(picked_first, RISES_BEYOND_WORDS, frame_len) + picked)
            with m.If(picked_last):
                m.d.sync += done.eq(1)
        return summed, frame_len
