"""When MA has clocked out enough rising edges for the whole frame."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .field_ends import word_length
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
    rising edges. The sum comes from the cycle's configuration in two register stages (valid two
    clocks after the latch; first read when Start has been sampled) and the compare is
    registered (a wide compare is too slow in front of the MA generator). The lag is harmless:
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

        word_len = [Signal(width, name=f"word{w}_len") for w in range(n_words)]
        frame_len = Signal(width + 1)          # every word's bits + RISES_BEYOND_WORDS
        target_rises = Signal(SLOT_WIDTH + 1)
        started = Signal()
        if self._ssi:
            # One register stage more: the word's length, then the frame's by mode (one stage
            # of both was the SSI build's critical path).
            n = Signal(width)
            m.d.sync += n.eq(word_length(self.words[0], self.crc_widths[0], width=width,
                                         error_bit=self.ssi & self.ssi_error))
            ssi_len = Mux(self.ssi_double, Cat(C(0, 1), n + SSI_RISES_BEYOND_WORD),
                          n + SSI_RISES_BEYOND_WORD)
            m.d.sync += word_len[0].eq(Mux(self.ssi, ssi_len, n + RISES_BEYOND_WORDS))
        else:
            m.d.sync += word_len[0].eq(word_length(self.words[0], self.crc_widths[0],
                                                   extra=RISES_BEYOND_WORDS,
                                                   width=width))
        # SSI: the frame starts with MA (the first rise), not when Start comes back: MA stops
        # after exactly its rises, however long the round trip. Every cycle has at least one
        # clock in WAIT_READY and a low phase of at least 2 clocks before its first rise: the
        # four stages above have settled by then (one clock to spare).
        started_now = Mux(self.ssi, self.rises != 0, self.started) if self._ssi else self.started
        m.d.sync += [
            # Words not in the frame add nothing (bit w of ``enables``; word 0 always counts).
            frame_len.eq(sum([word_len[0]] + [Mux(self.enables[w], word_len[w], 0)
                                              for w in range(1, n_words)])),
            target_rises.eq(self.start_slot + frame_len),
            started.eq(started_now),
            self.enough.eq(started & (self.rises >= target_rises) & ~self.clear),
        ]
        for w in range(1, n_words):
            m.d.sync += word_len[w].eq(word_length(self.words[w], self.crc_widths[w], width=width))
        return m
