"""Frame decoder: Ack, Start, CDS, then one or two single-cycle data words."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import CRC_SETTINGS, SLOT_WIDTH, WORD_CONFIG, WORD_INDEX_WIDTH
from .crc_engine import CrcEngine
from .. import protocol


def _table(index, values, width):
    """``values[index]`` modulo ``2**width`` as a small lookup: one LUT level per result bit
    instead of an adder chain."""
    return Array(C(v % 2**width, width) for v in values)[index]


def tail_bits(word, crc, extra=0, width=WORD_INDEX_WIDTH):
    """Bits after a word's data field (nE/nW, LC, CRC), plus ``extra``, modulo ``2**width``:
    a table on the two flag bits plus the CRC's width (a WORD_CONFIG and a CRC_SETTINGS
    view)."""
    values = [nenw * protocol.NE_NW_BITS + lc * protocol.LC_BITS + extra
              for lc in (0, 1) for nenw in (0, 1)]
    return (_table(Cat(word.nenw, word.lc), values, width) + crc.width)[:width]


def word_length(word, crc, extra=0, width=WORD_INDEX_WIDTH):
    """Bits of one word on the line (plus ``extra``), from its runtime configuration (a
    WORD_CONFIG view and its resolved CRC_SETTINGS view)."""
    return (word.data_bits + tail_bits(word, crc, extra, width))[:width]


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
            "stop_bit": Out(1),             # the stop slot's level (0 from a good encoder)
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
        for w in range(p.words):
            wcfg = self.words[w]
            e = {name: Signal(WORD_INDEX_WIDTH, name=f"w{w}_{name}", reset_less=True)
                 for name in ("data_end_p1", "data_end_m1", "nenw_end_m1", "lc_end_m1",
                              "word_end_m1")}
            wcrc = self.crcs[w]
            # The fields at bit 0 of the word (only with an invalid data_bits = 0).
            e["data_at0"] = Signal(name=f"w{w}_data_at0", reset_less=True)
            e["lc_at0"] = Signal(name=f"w{w}_lc_at0", reset_less=True)
            nenw_bits = Mux(wcfg.nenw, protocol.NE_NW_BITS, 0)
            nenw_lc_bits = _table(Cat(wcfg.nenw, wcfg.lc),
                                  [0, protocol.NE_NW_BITS, protocol.LC_BITS,
                                   protocol.NE_NW_BITS + protocol.LC_BITS], 4)
            # "- 1" folded into the tables, modulo 2**iw: a field end of 0 (only with
            # data_bits = 0) becomes 2**iw - 1, which ``idx`` never reaches inside a word.
            nenw_m1 = _table(wcfg.nenw, [-1, protocol.NE_NW_BITS - 1], iw)
            nenw_lc_m1 = _table(Cat(wcfg.nenw, wcfg.lc),
                                [-1, protocol.NE_NW_BITS - 1, protocol.LC_BITS - 1,
                                 protocol.NE_NW_BITS + protocol.LC_BITS - 1], iw)
            m.d.sync += [
                e["data_end_p1"].eq(wcfg.data_bits + 1),
                e["data_end_m1"].eq((wcfg.data_bits + C(2**iw - 1, iw))[:iw]),
                e["nenw_end_m1"].eq((wcfg.data_bits + nenw_m1)[:iw]),
                e["lc_end_m1"].eq((wcfg.data_bits + nenw_lc_m1)[:iw]),
                # data_bits >= 1, so "- 1" folded into the table (modulo 2**iw) never wraps.
                e["word_end_m1"].eq((wcfg.data_bits + tail_bits(wcfg, wcrc, extra=-1))[:iw]),
                e["data_at0"].eq(wcfg.data_bits != 0),
                e["lc_at0"].eq((wcfg.data_bits + nenw_bits == 0)
                               & (wcfg.data_bits + nenw_lc_bits != 0)),
            ]
            ends.append(e)

        def end(name):
            return ends[0][name] if p.words == 1 else Mux(word, ends[1][name], ends[0][name])

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

        with m.FSM(name="decoder_fsm"):
            with m.State("ACK"):
                with m.If(self.sample & self.bit):
                    m.d.sync += [self.started.eq(1), self.start_slot.eq(self.slots)]
                    m.next = "CDS"
            with m.State("CDS"):
                m.d.comb += at_cds.eq(self.sample)
                with m.If(self.sample):
                    m.d.sync += [self.cds.eq(self.bit), idx.eq(0),
                                 in_data.eq(ends[0]["data_at0"]), in_lc.eq(ends[0]["lc_at0"]),
                                 in_crc.eq(0)]
                    if p.words > 1:
                        m.d.sync += in_top.eq(self.words[1].data_bits != 0)
                    if p.words > 1:
                        m.d.sync += word.eq(0)
                    m.next = "WORD"
            with m.State("WORD"):
                m.d.comb += in_word.eq(self.sample)
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
                        # The next word (word 1) starts; after it nothing is read.
                        m.d.sync += [in_data.eq(ends[-1]["data_at0"]),
                                     in_lc.eq(ends[-1]["lc_at0"]), in_top.eq(0)]
                        with m.If(word == last_word):
                            m.d.sync += self.done.eq(1)
                            m.next = "STOP"
                        if p.words > 1:
                            with m.Else():
                                m.d.sync += word.eq(word + 1)
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
            # A word without nE/nW reads as "no error, no warning" (both high).
            with m.If(~self.words[w].nenw):
                m.d.sync += [self.ne[w].eq(1), self.nw[w].eq(1)]
            with m.Elif(this_word & (idx == self.words[w].data_bits)):
                m.d.sync += self.ne[w].eq(self.bit)
            with m.Elif(this_word & (idx == ends[w]["data_end_p1"])):
                m.d.sync += self.nw[w].eq(self.bit)
        m.d.comb += [
            self.lc_load.eq(in_word & in_lc),
            self.lc_next.eq(Cat(self.bit, self.lc)),
        ]
        with m.If(self.lc_load):
            m.d.sync += self.lc.eq(self.lc_next)
        if p.words == 2:
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
