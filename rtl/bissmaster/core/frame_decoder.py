"""Frame decoder: Ack, Start, CDS, then the frame's data words (one slave's, a Safety
encoder's CPW and SPW, or a chain's words back to back)."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import CRC_MAX_WIDTH, CRC_SETTINGS, SLOT_WIDTH, WORD_CONFIG, WORD_INDEX_WIDTH
from .crc_engine import CrcEngine
from .. import protocol


def _table(index, values, width):
    """``values[index]`` modulo ``2**width`` as a small lookup: one LUT level per result bit
    instead of an adder chain."""
    return Array(C(v % 2**width, width) for v in values)[index]


def _flag_table(word, error_bit, width, value):
    """``value(nenw, lc, error)`` modulo ``2**width`` as a table on a word's flag settings (a
    WORD_CONFIG view) and, when ``error_bit`` is given, its SSI error bit (the word has one
    error bit after the data: SSI mode, ``cfg_ssi_error``)."""
    index = Cat(word.nenw, word.lc)
    errors = (0,)
    if error_bit is not None:
        index, errors = Cat(index, error_bit), (0, 1)
    return _table(index, [value(nenw, lc, error) for error in errors for lc in (0, 1)
                          for nenw in (0, 1)], width)


def flag_bits(nenw, lc, error):
    """Bits between a word's data and its CRC: nE/nW, LC, an SSI error bit."""
    return nenw * protocol.NE_NW_BITS + lc * protocol.LC_BITS + error


def tail_bits(word, crc, extra=0, width=WORD_INDEX_WIDTH, error_bit=None):
    """Bits after a word's data field (nE/nW, LC, the SSI error bit, CRC), plus ``extra``,
    modulo ``2**width``: a table on the flag bits plus the CRC's width (a WORD_CONFIG and a
    CRC_SETTINGS view; ``error_bit`` as in :func:`_flag_table`)."""
    flags = _flag_table(word, error_bit, width, lambda *f: flag_bits(*f) + extra)
    return (flags + crc.width)[:width]


def word_length(word, crc, extra=0, width=WORD_INDEX_WIDTH, error_bit=None):
    """Bits of one word on the line (plus ``extra``), from its runtime configuration (a
    WORD_CONFIG view and its resolved CRC_SETTINGS view; ``error_bit`` as in
    :func:`_flag_table`)."""
    return (word.data_bits + tail_bits(word, crc, extra, width, error_bit))[:width]


class FrameDecoder(wiring.Component):
    """Turns the sampled slots of one cycle into fields.

    Slots arrive from :class:`~bissmaster.core.slo_sampler.SloSampler`, slot 0 being the first Ack
    slot. Low slots are Ack; the first high slot is Start; then CDS; then each word's data
    (MSB first, right-justified in ``data``; a word set ``gray`` is Gray-decoded as it
    arrives, one set ``signed`` is sign-extended to the width of ``data``), nE, nW, LC and
    CRC. One more slot, the stop bit, ends the frame: the encoder's timeout has begun, so the
    master may look for SLO high again.

    One :class:`~bissmaster.core.crc_engine.CrcEngine` checks every word's CRC in turn, each
    with its own settings (``crcs``). ``crc_ok`` comes from the engine's flip-flops: valid in
    the clock after the word's last bit was sampled, and held until the next frame.

    The master holds it in reset between cycles (``ResetInserter``), which also clears the
    data registers, so data fields are right-justified (zeros above an unsigned field).

    ``done`` strobes one clock after the last bit of the last word was sampled, when every
    field and ``crc_ok`` is final.

    **SSI** (builds with ``params.ssi``, ``ssi`` high): no Ack, Start or CDS: slot 0 is word 0's
    first bit (``started`` is set with its decision, ``start_slot`` 0). Word 0 begins in the
    first clock with ``ssi`` high, from the field boundaries registered from ``words``: those
    must have been stable for a clock before (in the master the configuration is latched while
    idle, at least one clock before the decoder leaves its reset). With ``ssi_error``
    the word has one error bit right after its data, reported on ``ne[0]`` as an nE is (0: the
    error is active; active high unless ``ssi_error_low``), ``nw[0]`` 1. With ``ssi_double``
    the word comes twice, the copies separated by one bit that must be 0: every bit of the
    second copy is compared with the first as it arrives (a shift register of the first copy's
    bits as sent), and ``mismatch`` is set for any difference or a separator of 1; ``done``
    comes after the second copy. The stop bit (``stopped``, ``stop_bit``) is the bit after the
    word, or after the second copy.

    ``frame_end`` is where the frame's verdict and its noise count close: ``done`` in BiSS,
    ``stopped`` in SSI (whose verdict waits for the bit after the word: it must be 0).
    """

    def __init__(self, params):
        self._params = params
        words = params.words
        super().__init__({
            "sample": In(1),
            "bit": In(1),
            "words": In(data.ArrayLayout(WORD_CONFIG, words)),
            "crcs": In(data.ArrayLayout(CRC_SETTINGS, words)),
            "word_count": In(range(1, words + 1)),
            "started": Out(1),
            "start_slot": Out(SLOT_WIDTH),
            "slots": Out(SLOT_WIDTH),                # slots sampled so far (saturating)
            "slots_full": Out(1),            # slots saturated (registered)
            "cds": Out(1),
            **{f"data{w}": Out(params.max_data_bits[w]) for w in range(words)},
            "ne": Out(words),
            "nw": Out(words),
            "lc": Out(protocol.LC_BITS),
            "lc_next": Out(protocol.LC_BITS),   # what ``lc`` holds after a clock with lc_load
            "lc_load": Out(1),                  # an LC bit is shifted in in this clock
            "cpw_top": Out(params.max_data_bits[-1]),   # the first SPW-length bits of word 0
            "crc_ok": Out(words),
            "done": Out(1),
            "stopped": Out(1),
            "frame_end": Out(1),            # ``done`` in BiSS, ``stopped`` in SSI
            "stop_bit": Out(1),             # the stop slot's level (0 from a good encoder)
            **({"ssi": In(1), "ssi_error": In(1), "ssi_error_low": In(1), "ssi_double": In(1),
                "mismatch": Out(1)} if params.ssi else {}),
        })

    def elaborate(self, platform):
        m = Module()
        p = self._params
        last_word = self.word_count - 1

        # Where the current bit sits: word ``word``, bit ``idx`` of that word.
        word = Signal(range(p.words), name="word") if p.words > 1 else C(0, 1)   # none in one-word builds
        idx = Signal(WORD_INDEX_WIDTH)
        # Field boundaries of each word, registered from the configuration (no adders in front
        # of the ``idx`` compares). They are not reset (they follow ``words`` in every clock),
        # so they are valid one clock after ``words`` settles; the first word bit comes at
        # least three samples (Ack, Start, CDS) after that.
        ends = []
        iw = WORD_INDEX_WIDTH
        # Word 0's SSI error bit (SSI builds): a flag bit after the data, like nE.
        error_bit = (self.ssi & self.ssi_error) if p.ssi else None
        for w in range(p.words):
            err = error_bit if w == 0 else None
            wcfg = self.words[w]
            e = {name: Signal(WORD_INDEX_WIDTH, name=f"w{w}_{name}", reset_less=True)
                 for name in ("data_end_p1", "data_end_m1", "nenw_end_m1", "lc_end_m1",
                              "word_end_m1")}
            wcrc = self.crcs[w]
            # The fields at bit 0 of the word (only with an invalid data_bits = 0).
            e["data_at0"] = Signal(name=f"w{w}_data_at0", reset_less=True)
            e["lc_at0"] = Signal(name=f"w{w}_lc_at0", reset_less=True)
            # The flag fields' lengths: nE/nW (or the SSI error bit), and those plus LC.
            nenw_bits = _flag_table(wcfg, err, 2, lambda n, lc, e: flag_bits(n, 0, e))
            nenw_lc_bits = _flag_table(wcfg, err, 4, flag_bits)
            # "- 1" folded into the tables, modulo 2**iw: a field end of 0 (only with
            # data_bits = 0) becomes 2**iw - 1, which ``idx`` never reaches inside a word.
            nenw_m1 = _flag_table(wcfg, err, iw, lambda n, lc, e: flag_bits(n, 0, e) - 1)
            nenw_lc_m1 = _flag_table(wcfg, err, iw, lambda *f: flag_bits(*f) - 1)
            m.d.sync += [
                e["data_end_p1"].eq(wcfg.data_bits + 1),
                e["data_end_m1"].eq((wcfg.data_bits + C(2**iw - 1, iw))[:iw]),
                e["nenw_end_m1"].eq((wcfg.data_bits + nenw_m1)[:iw]),
                e["lc_end_m1"].eq((wcfg.data_bits + nenw_lc_m1)[:iw]),
                # data_bits >= 1, so "- 1" folded into the table (modulo 2**iw) never wraps.
                e["word_end_m1"].eq((wcfg.data_bits + tail_bits(wcfg, wcrc, extra=-1,
                                                                error_bit=err))[:iw]),
                e["data_at0"].eq(wcfg.data_bits != 0),
                e["lc_at0"].eq((wcfg.data_bits + nenw_bits == 0)
                               & (wcfg.data_bits + nenw_lc_bits != 0)),
            ]
            ends.append(e)

        def end(name, of=word):
            """A field end of word ``of`` (the current word by default)."""
            if p.words == 1:
                return ends[0][name]
            if p.words == 2:
                return Mux(of, ends[1][name], ends[0][name])
            return Array(e[name] for e in ends)[of]

        word_end_m1 = end("word_end_m1")

        # Which fields the current bit (``idx``) belongs to, as flip-flops: set for the
        # word's first bit, then updated with each sample from ``idx`` and the registered
        # field ends (``idx`` only ever counts up by one inside a word). No magnitude compare
        # sits in front of the shift enables.
        in_data = Signal()      # idx < data_bits of this word
        in_lc = Signal()        # nenw_end <= idx < lc_end of this word
        in_top = Signal()       # word 0 and idx < data_bits of word 1 (cpw_top)
        in_crc = Signal()       # lc_end <= idx: the word's received CRC bits
        at_cds = Signal()       # the CDS bit is sampled: word 0 begins next
        in_word = Signal()
        m.d.sync += [self.done.eq(0), self.stopped.eq(0)]

        with m.If(self.sample & ~self.slots_full):
            m.d.sync += [self.slots.eq(self.slots + 1), self.slots_full.eq(self.slots == 2**SLOT_WIDTH - 2)]

        def begin_words():
            """Word 0 begins with the next sample (the CRC engine loads its start value)."""
            m.d.comb += at_cds.eq(1)
            m.d.sync += [idx.eq(0), in_data.eq(ends[0]["data_at0"]),
                         in_lc.eq(ends[0]["lc_at0"]), in_crc.eq(0)]
            if p.words > 1:
                m.d.sync += [in_top.eq(self.words[1].data_bits != 0), word.eq(0)]
            m.next = "WORD"

        def end_words():
            """The last word bit is in: ``done``, then the stop bit."""
            m.d.sync += self.done.eq(1)
            m.next = "STOP"

        ssi = self.ssi if p.ssi else C(0)
        m.d.comb += self.frame_end.eq(Mux(ssi, self.stopped, self.done))
        # SSI double transmission: the first copy's bits as sent (the newest in bit 0), and
        # whether the copies differ so far.
        if p.ssi:
            ring = Signal(p.max_data_bits[0] + protocol.NE_NW_BITS + CRC_MAX_WIDTH)
            expected = ring.bit_select(word_end_m1, 1)     # the first copy's bit at this index

        with m.FSM(name="decoder_fsm"):
            with m.State("ACK"):
                with m.If(ssi):
                    # SSI: no Ack, Start or CDS; slot 0 is word 0's first bit (``started``
                    # with its decision, in WORD).
                    begin_words()
                with m.Elif(self.sample & self.bit):
                    m.d.sync += [self.started.eq(1), self.start_slot.eq(self.slots)]
                    m.next = "CDS"
            with m.State("CDS"):
                with m.If(self.sample):
                    m.d.sync += self.cds.eq(self.bit)
                    begin_words()
            with m.State("WORD"):
                m.d.comb += in_word.eq(self.sample)
                if p.ssi:
                    with m.If(self.sample):
                        m.d.sync += self.started.eq(1)      # SSI: slot 0 (BiSS: set already)
                with m.If(self.sample):
                    m.d.sync += [
                        idx.eq(idx + 1),
                        in_data.eq(in_data & (idx != end("data_end_m1"))),
                        in_lc.eq((in_lc | (idx == end("nenw_end_m1")))
                                 & (idx != end("lc_end_m1"))),
                        in_crc.eq((in_crc | (idx == end("lc_end_m1"))) & (idx != word_end_m1)),
                    ]
                    if p.words > 1:
                        m.d.sync += in_top.eq(in_top & (idx != ends[1]["data_end_m1"]))
                    with m.If(idx == word_end_m1):
                        m.d.sync += idx.eq(0)
                        # The next word starts (after the last one nothing is read).
                        if p.words <= 2:
                            next_word = C(p.words - 1, 1)
                        else:
                            next_word = (word + 1)[:len(word)]
                        m.d.sync += [in_data.eq(end("data_at0", next_word)),
                                     in_lc.eq(end("lc_at0", next_word)), in_top.eq(0)]
                        with m.If(word == last_word):
                            if p.ssi:
                                with m.If(ssi & self.ssi_double):
                                    m.next = "SEPARATOR"
                                with m.Else():
                                    end_words()
                            else:
                                end_words()
                        if p.words > 1:
                            with m.Else():
                                m.d.sync += word.eq(word + 1)
            if p.ssi:
                with m.State("SEPARATOR"):
                    with m.If(self.sample):
                        m.d.sync += self.mismatch.eq(self.bit)      # must be 0
                        m.next = "COPY"
                with m.State("COPY"):
                    with m.If(self.sample):
                        m.d.sync += [
                            idx.eq(idx + 1),
                            ring.eq(Cat(self.bit, ring)),
                            self.mismatch.eq(self.mismatch | (self.bit != expected)),
                        ]
                        with m.If(idx == word_end_m1):
                            end_words()
            with m.State("STOP"):
                with m.If(self.sample):
                    m.d.sync += [self.stopped.eq(1), self.stop_bit.eq(self.bit)]
                    m.next = "END"
            with m.State("END"):
                pass

        # Route each bit of a word to its field.
        # Gray-coded data: each binary bit is the received bit xor the binary bit before it
        # (MSB first), which is the register's bit 0 (0 before the first: the decoder is reset
        # between cycles). The CRC engine gets the bits as sent.
        decoded = []
        for w in range(p.words):
            data_w = getattr(self, f"data{w}")
            decoded.append(self.bit ^ (self.words[w].gray & data_w[0]))
        # A signed word's first bit (its sign, the binary MSB) fills the whole register; each
        # further bit shifts in below it, so the sign stays copied above the field
        # (two's complement in the port's full width, with no decode of ``data_bits``).
        first_bit = idx == 0
        for w in range(p.words):
            this_word = in_word & (word == w)
            data_w = getattr(self, f"data{w}")
            shifted = Cat(decoded[w], data_w)[:len(data_w)]
            if p.signed_words:
                shifted |= (self.words[w].signed & first_bit & decoded[w]).replicate(len(data_w))
            with m.If(this_word & in_data):
                m.d.sync += data_w.eq(shifted)
            # A word without nE/nW reads as "no error, no warning" (both high); an SSI error
            # bit (word 0) is read as nE is: 0 when active (inverted when active high).
            nenw = self.words[w].nenw
            if w == 0 and p.ssi:
                with m.If(~nenw & ~error_bit):
                    m.d.sync += self.ne[w].eq(1)
                with m.Elif(this_word & (idx == self.words[w].data_bits)):
                    m.d.sync += self.ne[w].eq(self.bit ^ (error_bit & ~self.ssi_error_low))
                with m.If(~nenw):
                    m.d.sync += self.nw[w].eq(1)
                with m.Elif(this_word & (idx == ends[w]["data_end_p1"])):
                    m.d.sync += self.nw[w].eq(self.bit)
            else:
                with m.If(~nenw):
                    m.d.sync += [self.ne[w].eq(1), self.nw[w].eq(1)]
                with m.Elif(this_word & (idx == self.words[w].data_bits)):
                    m.d.sync += self.ne[w].eq(self.bit)
                with m.Elif(this_word & (idx == ends[w]["data_end_p1"])):
                    m.d.sync += self.nw[w].eq(self.bit)
        if p.ssi:
            # The first copy of an SSI double transmission, as sent (word 0 is the only word).
            with m.If(in_word & ssi):
                m.d.sync += ring.eq(Cat(self.bit, ring))
        m.d.comb += [
            self.lc_load.eq(in_word & in_lc),
            self.lc_next.eq(Cat(self.bit, self.lc)),
        ]
        with m.If(self.lc_load):
            m.d.sync += self.lc.eq(self.lc_next)
        if p.words >= 2:
            # Word 0's leading bits, as many as word 1 has: the CPW with its extra low bits dropped.
            with m.If(in_word & in_top):
                m.d.sync += self.cpw_top.eq(Cat(decoded[0], self.cpw_top))

        # One CRC engine for every word in turn, fed each bit of the word (data and the CRC).
        m.submodules.crc = engine = CrcEngine(p.words)
        m.d.comb += [
            engine.crcs.eq(self.crcs),
            engine.load.eq(at_cds | (in_word & (idx == word_end_m1))),
            engine.cover.eq(in_word & ~in_crc),
            engine.check.eq(in_word & in_crc),
            engine.last.eq(in_word & (idx == word_end_m1)),
            engine.bit.eq(self.bit),
            self.crc_ok.eq(engine.ok),
        ]
        if p.words > 1:
            m.d.comb += [engine.index.eq(word), engine.load_index.eq(Mux(at_cds, 0, word + 1))]

        return m
