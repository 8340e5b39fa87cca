"""Frame decoder: Ack, Start, CDS, then the frame's data words (one slave's, a Safety
encoder's CPW and SPW, or a chain's words back to back)."""

from types import SimpleNamespace

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import (CHAIN_FIRST_WORD, CRC_MAX_WIDTH, CRC_SETTINGS, CRC_TABLE, SLOT_WIDTH,
                      WORD_INDEX_WIDTH, word_config)
from .chain_results import CHAIN_INDEX_BITS
from .crc_engine import CrcEngine
from .field_ends import FieldEnds, field_ends as field_ends_of
from .ssi_copy import SsiCopyCompare
from .. import protocol


class FrameDecoder(wiring.Component):
    """Turns the sampled slots of one cycle into fields.

    Slots arrive from :class:`~bissmaster.core.slo_sampler.SloSampler`, slot 0 being the first Ack
    slot. Low slots are Ack; the first high slot is Start; then CDS; then each word's data
    (MSB first, right-justified in ``data``; a word set ``gray`` is Gray-decoded as it
    arrives, one set ``signed`` is sign-extended to the width of ``data``), nE, nW, LC and
    CRC. One more slot, the stop bit, ends the frame: the encoder's timeout has begun, so the
    master may look for SLO high again.

    One :class:`~bissmaster.core.crc_engine.CrcEngine` checks every word's CRC in turn, each
    with its own settings (its code in ``words``, ``customs``, ``crc_widths``; a one-word
    build's resolved ``word0_crc``). ``crc_ok`` comes from the engine's flip-flops: valid in the
    clock after the word's last bit was sampled, and held until the next frame.

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

    **Chain memory** (``params.chain_words_in_memory``): words 2.. have no ``data<N>``; they
    share ``chain_data`` (as wide as the longest of them), which holds each word's data as
    its own register would (Gray-decoded, sign-extended to that word's longest field, 0
    above), from its last data bit until the next word's first. ``chain_end`` strobes in the
    clock a chain word's last bit is sampled, with ``chain_index`` = N - 2:
    :class:`~bissmaster.core.chain_results.ChainResults` writes the word from the next clock.
    """

    def __init__(self, params):
        self._params = params
        words = params.words
        # Words with a data register of their own: every word, or with the chain memory
        # words 0 and 1 (the chain's words share one register, ``chain_data``).
        self._own_words = range(CHAIN_FIRST_WORD if params.chain_words_in_memory else words)
        self._chain_bits = max(params.max_data_bits[CHAIN_FIRST_WORD:], default=0)
        super().__init__({
            "sample": In(1),
            "bit": In(1),
            "words": In(data.ArrayLayout(word_config(params), words)),
            # Each word's resolved CRC width (Configuration.crc_widths); in builds of 2+ words
            # with custom CRCs, each word's ``cfg_wN_crc_*`` settings, or with ``crc_table``
            # the CRC engine's table port (CrcEngine); in one-word builds, the word's CRC
            # resolved (Configuration.crc).
            "crc_widths": In(data.ArrayLayout(range(CRC_MAX_WIDTH + 1), words)),
            **({"word0_crc": In(CRC_SETTINGS)} if words == 1 else
               {"crc_table_addr": Out(range(words)), "crc_table_data": In(CRC_TABLE)}
               if params.crc_table_built else
               {"customs": In(data.ArrayLayout(CRC_SETTINGS, words))} if params.custom_crc
               else {}),
            "word_count": In(range(1, words + 1)),
            "started": Out(1),
            "start_slot": Out(SLOT_WIDTH),
            "slots": Out(SLOT_WIDTH),                # slots sampled so far (saturating)
            "slots_full": Out(1),            # slots saturated (registered)
            "cds": Out(1),
            **{f"data{w}": Out(params.max_data_bits[w]) for w in self._own_words},
            **({"chain_data": Out(self._chain_bits), "chain_end": Out(1),
                "chain_index": Out(CHAIN_INDEX_BITS)}
               if params.chain_words_in_memory else {}),
            "ne": Out(words),
            "nw": Out(words),
            "lc": Out(protocol.LC_BITS),
            "lc_next": Out(protocol.LC_BITS),   # what ``lc`` holds after a clock with lc_load
            "lc_load": Out(1),                  # an LC bit is shifted in in this clock
            "cpw_top": Out(params.max_data_bits[min(1, words - 1)]),   # word 0's first SPW-length bits
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
        # What the parts below share: where the current bit sits and which fields it is in.
        s = SimpleNamespace()
        # Where the current bit sits: word ``word``, bit ``idx`` of that word.
        s.word = Signal(range(p.words), name="word") if p.words > 1 else C(0, 1)   # none in one-word builds
        s.idx = Signal(WORD_INDEX_WIDTH, name="idx")
        self._field_ends(m, s)
        # Which fields the current bit (``idx``) belongs to, as flip-flops: set for the
        # word's first bit, then updated with each sample from ``idx`` and the registered
        # field ends (``idx`` only ever counts up by one inside a word). No magnitude compare
        # sits in front of the shift enables.
        s.in_data = Signal(name="in_data")      # idx < data_bits of this word
        s.in_lc = Signal(name="in_lc")          # nenw_end <= idx < lc_end of this word
        s.in_top = Signal(name="in_top")        # word 0 and idx < data_bits of word 1 (cpw_top)
        s.in_crc = Signal(name="in_crc")        # lc_end <= idx: the word's received CRC bits
        s.at_cds = Signal(name="at_cds")        # the CDS bit is sampled: word 0 begins next
        s.in_word = Signal(name="in_word")
        m.d.sync += [self.done.eq(0), self.stopped.eq(0)]

        with m.If(self.sample & ~self.slots_full):
            m.d.sync += [self.slots.eq(self.slots + 1), self.slots_full.eq(self.slots == 2**SLOT_WIDTH - 2)]

        s.ssi = self.ssi if p.ssi else C(0)
        m.d.comb += self.frame_end.eq(Mux(s.ssi, self.stopped, self.done))
        # SSI double transmission: the second copy compared with the first as it arrives.
        if p.ssi:
            m.submodules.copy = s.copy = SsiCopyCompare(
                p.max_data_bits[0] + protocol.NE_NW_BITS + CRC_MAX_WIDTH)
            m.d.comb += [s.copy.bit.eq(self.bit), s.copy.index.eq(s.current.word_end_m1),
                         self.mismatch.eq(s.copy.mismatch)]
        self._word_fsm(m, s)
        self._route_bits(m, s)
        self._crc_engine(m, s)
        return m

    def _field_ends(self, m, s):
        """The field ends of the current word and the next (``s.field_ends``, ``s.current``),
        word 0's first-bit flags (``s.first``) and the SSI error bit (``s.error_bit``)."""
        p = self._params
        # Field boundaries of the current word and the next, as registers (no adders in front
        # of the ``idx`` compares): loaded as word 0 begins and as each word ends (one-word
        # builds: registered from the configuration in every clock, valid one clock after
        # ``words`` settles; the first word bit comes at least three samples (Ack, Start, CDS)
        # after that; SSI: see above).
        m.submodules.field_ends = field_ends = FieldEnds(p.words, error_bit=p.ssi,
                                                         word_layout=word_config(p))
        m.d.comb += [field_ends.words.eq(self.words), field_ends.crc_widths.eq(self.crc_widths)]
        s.error_bit = None
        if p.ssi:
            # Word 0's SSI error bit: a flag bit after the data, like nE.
            s.error_bit = self.ssi & self.ssi_error
            m.d.comb += field_ends.error_bit.eq(s.error_bit)
        s.field_ends, s.current = field_ends, field_ends.current
        # Word 0's first-bit flags as ``begin_words`` reads them: a one-word build's registers
        # hold them already; with more words they are loaded with the ends themselves.
        if p.words == 1:
            s.first = s.current
        else:
            s.first = field_ends_of(self.words[0], self.crc_widths[0], s.error_bit)

    def _word_fsm(self, m, s):
        """Ack, Start, CDS, the words bit by bit (the field flags updated with each sample),
        an SSI double transmission's separator and copy, the stop bit."""
        p = self._params
        idx, word, current, field_ends = s.idx, s.word, s.current, s.field_ends
        in_data, in_lc, in_top, in_crc = s.in_data, s.in_lc, s.in_top, s.in_crc
        word_end_m1 = current.word_end_m1
        last_word = self.word_count - 1

        def begin_words():
            """Word 0 begins with the next sample (the CRC engine loads its start value)."""
            m.d.comb += s.at_cds.eq(1)
            m.d.sync += [idx.eq(0), in_data.eq(s.first["data_at0"]),
                         in_lc.eq(s.first["lc_at0"]), in_crc.eq(0)]
            if p.words > 1:
                m.d.comb += field_ends.begin.eq(1)
                m.d.sync += [in_top.eq(self.words[1].data_bits != 0), word.eq(0)]
            m.next = "WORD"

        def end_words():
            """The last word bit is in: ``done``, then the stop bit."""
            m.d.sync += self.done.eq(1)
            m.next = "STOP"

        with m.FSM(name="decoder_fsm"):
            with m.State("ACK"):
                with m.If(s.ssi):
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
                m.d.comb += s.in_word.eq(self.sample)
                if p.ssi:
                    with m.If(self.sample):
                        m.d.sync += self.started.eq(1)      # SSI: slot 0 (BiSS: set already)
                with m.If(self.sample):
                    m.d.sync += [
                        idx.eq(idx + 1),
                        in_data.eq(in_data & (idx != current.data_end_m1)),
                        in_lc.eq((in_lc | (idx == current.nenw_end_m1))
                                 & (idx != current.lc_end_m1)),
                        in_crc.eq((in_crc | (idx == current.lc_end_m1)) & (idx != word_end_m1)),
                    ]
                    if p.words > 1:
                        # In word 0: word 1's ends are the following ones.
                        m.d.sync += in_top.eq(in_top & (idx != field_ends.following.data_end_m1))
                    with m.If(idx == word_end_m1):
                        m.d.sync += idx.eq(0)
                        # The next word starts (after the last one nothing is read).
                        following = field_ends.following if p.words > 1 else current
                        m.d.sync += [in_data.eq(following.data_at0),
                                     in_lc.eq(following.lc_at0), in_top.eq(0)]
                        with m.If(word == last_word):
                            if p.ssi:
                                with m.If(s.ssi & self.ssi_double):
                                    m.next = "SEPARATOR"
                                with m.Else():
                                    end_words()
                            else:
                                end_words()
                        if p.words > 1:
                            with m.Else():
                                m.d.sync += word.eq(word + 1)
                                m.d.comb += field_ends.advance.eq(1)
            if p.ssi:
                with m.State("SEPARATOR"):
                    m.d.comb += s.copy.separator.eq(self.sample)
                    with m.If(self.sample):
                        m.next = "COPY"
                with m.State("COPY"):
                    m.d.comb += s.copy.second.eq(self.sample)
                    with m.If(self.sample):
                        m.d.sync += idx.eq(idx + 1)
                        with m.If(idx == word_end_m1):
                            end_words()
            with m.State("STOP"):
                with m.If(self.sample):
                    m.d.sync += [self.stopped.eq(1), self.stop_bit.eq(self.bit)]
                    m.next = "END"
            with m.State("END"):
                pass

    def _route_bits(self, m, s):
        """Each bit of a word to its field: the data registers, nE / nW, LC, ``cpw_top``, the
        chain register."""
        p = self._params
        idx, word, current, in_word = s.idx, s.word, s.current, s.in_word
        # Gray-coded data: each binary bit is the received bit xor the binary bit before it
        # (MSB first), which is the register's bit 0 (0 before the first: the decoder is reset
        # between cycles). The CRC engine gets the bits as sent.
        decoded = []
        for w in self._own_words:
            data_w = getattr(self, f"data{w}")
            decoded.append(self.bit ^ (self.words[w].gray & data_w[0]))
        # A signed word's first bit (its sign, the binary MSB) fills the whole register; each
        # further bit shifts in below it, so the sign stays copied above the field
        # (two's complement in the port's full width, with no decode of ``data_bits``).
        first_bit = idx == 0
        for w in range(p.words):
            this_word = in_word & (word == w)
            if w in self._own_words:
                data_w = getattr(self, f"data{w}")
                shifted = Cat(decoded[w], data_w)[:len(data_w)]
                if p.signed_words:
                    shifted |= (self.words[w].signed & first_bit
                                & decoded[w]).replicate(len(data_w))
                with m.If(this_word & s.in_data):
                    m.d.sync += data_w.eq(shifted)
            # A word without nE/nW reads as "no error, no warning" (both high); an SSI error
            # bit (word 0) is read as nE is: 0 when active (inverted when active high).
            nenw = self.words[w].nenw
            if w == 0 and p.ssi:
                with m.If(~nenw & ~s.error_bit):
                    m.d.sync += self.ne[w].eq(1)
                with m.Elif(this_word & (idx == self.words[w].data_bits)):
                    m.d.sync += self.ne[w].eq(self.bit ^ (s.error_bit & ~self.ssi_error_low))
                with m.If(~nenw):
                    m.d.sync += self.nw[w].eq(1)
                with m.Elif(this_word & (idx == current.data_end_p1)):
                    m.d.sync += self.nw[w].eq(self.bit)
            else:
                with m.If(~nenw):
                    m.d.sync += [self.ne[w].eq(1), self.nw[w].eq(1)]
                with m.Elif(this_word & (idx == self.words[w].data_bits)):
                    m.d.sync += self.ne[w].eq(self.bit)
                with m.Elif(this_word & (idx == current.data_end_p1)):
                    m.d.sync += self.nw[w].eq(self.bit)
        if p.chain_words_in_memory:
            self._chain_register(m, word, first_bit, in_word & s.in_data,
                                 in_word & (idx == current.word_end_m1))
        if p.ssi:
            # The first copy of an SSI double transmission, as sent (word 0 is the only word).
            m.d.comb += s.copy.first.eq(in_word & s.ssi)
        m.d.comb += [
            self.lc_load.eq(in_word & s.in_lc),
            self.lc_next.eq(Cat(self.bit, self.lc)),
        ]
        with m.If(self.lc_load):
            m.d.sync += self.lc.eq(self.lc_next)
        if p.words >= 2:
            # Word 0's leading bits, as many as word 1 has: the CPW with its extra low bits dropped.
            with m.If(in_word & s.in_top):
                m.d.sync += self.cpw_top.eq(Cat(decoded[0], self.cpw_top))

    def _crc_engine(self, m, s):
        """One CRC engine for every word in turn, fed each bit of the word (data and the
        CRC)."""
        p = self._params
        in_word, last_bit = s.in_word, s.idx == s.current.word_end_m1
        kinds = sorted({kind for crcs in p.word_crcs for kind in crcs})
        m.submodules.crc = engine = CrcEngine(p.words, kinds=kinds, custom=p.custom_crc,
                                              table=p.crc_table_built)
        if p.words == 1:
            m.d.comb += engine.word_crc.eq(self.word0_crc)
        else:
            m.d.comb += [engine.codes[w].eq(self.words[w].crc) for w in range(p.words)]
            if p.crc_table_built:
                m.d.comb += [engine.widths.eq(self.crc_widths),
                             self.crc_table_addr.eq(engine.table_index),
                             engine.table.eq(self.crc_table_data)]
            elif p.custom_crc:
                m.d.comb += engine.customs.eq(self.customs)
        m.d.comb += [
            engine.load.eq(s.at_cds | (in_word & last_bit)),
            engine.cover.eq(in_word & ~s.in_crc),
            engine.check.eq(in_word & s.in_crc),
            engine.last.eq(in_word & last_bit),
            engine.bit.eq(self.bit),
            self.crc_ok.eq(engine.ok),
        ]
        if p.words > 1:
            # The word the engine loads next: word 0 at CDS, then the one after the current
            # word. A register counting the loads from 0 (the decoder is reset before every
            # frame), not the decoder's state: the word's CRC settings (its code, width and
            # the CRC table's asynchronous read) are then settled long before the load, and
            # only the load itself comes from the sampled bit.
            next_word = Signal(range(p.words), name="crc_next_word")
            with m.If(engine.load):
                m.d.sync += next_word.eq((next_word + 1)[:len(next_word)])
            m.d.comb += [engine.index.eq(s.word), engine.load_index.eq(next_word)]

    def _chain_register(self, m, word, first_bit, data_bit, word_last_bit):
        """Words 2..7 through one register (``chain_data``), for the chain memory: each
        word's data as its own register would hold it (Gray-decoded, sign-extended to that
        word's longest field, 0 above it), final from its last data bit until the next word's
        first; ``chain_end`` in the clock its last bit (the word's last) is sampled."""
        p = self._params
        chain = self.chain_data
        chain_ws = range(CHAIN_FIRST_WORD, p.words)
        is_word = {w: word == w for w in chain_ws}
        in_chain = Cat(is_word.values()).any()

        def either(flag):
            """``flag`` of the current chain word's settings."""
            return Cat(is_word[w] & self.words[w][flag] for w in chain_ws).any()

        # The word's first bit starts from 0 (the previous word's data stays until then).
        previous = Mux(first_bit, 0, chain)
        decoded = self.bit ^ (either("gray") & previous[0])
        fill = either("signed") & first_bit & decoded if p.signed_words else C(0)
        # Bit i exists in the current word's register when its longest field is above i.
        keep = [C(1) if all(p.max_data_bits[w] > i for w in chain_ws)
                else Cat(is_word[w] for w in chain_ws if p.max_data_bits[w] > i).any()
                for i in range(len(chain))]
        shifted = Cat(keep[i] & ((decoded if i == 0 else previous[i - 1]) | fill)
                      for i in range(len(chain)))
        with m.If(data_bit & in_chain):
            m.d.sync += chain.eq(shifted)
        m.d.comb += [self.chain_end.eq(word_last_bit & in_chain),
                     self.chain_index.eq(word - CHAIN_FIRST_WORD)]
