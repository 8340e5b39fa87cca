"""One programmable CRC checker per channel, shared by the words of a frame in turn."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from ..params import CRC_MAX_WIDTH, CRC_SETTINGS, CRC_TABLE, Crc
from .word_select import select_word


#: The named CRCs as the engine runs them: start 0, sent inverted (docs/protocol.md, section 6).
NAMED_CRCS = {
    Crc.CRC6: (protocol.CRC6_WIDTH, protocol.CRC6_POLY, protocol.CRC_INIT, 1),
    Crc.CRC16: (protocol.CRC16_WIDTH, protocol.CRC16_POLY, protocol.CRC_INIT, 1),
}
assert protocol.CRC6_XOR_OUT == 2**protocol.CRC6_WIDTH - 1
assert protocol.CRC16_XOR_OUT == 2**protocol.CRC16_WIDTH - 1


def crc_settings(code, custom, kinds):
    """A word's CRC code resolved (combinational), as a :data:`CRC_SETTINGS` view: a named CRC
    of ``kinds`` gives its settings, ``Crc.CUSTOM`` the word's ``custom`` settings (``None`` in
    builds without custom CRCs), anything else width 0 (no CRC; a code the build lacks is
    refused before a cycle: Configuration.ok)."""
    value = C(0, CRC_SETTINGS.size)
    for kind in kinds:
        width, poly, start, inverted = NAMED_CRCS[kind]
        named = CRC_SETTINGS.const({"width": width, "poly": poly, "start": start,
                                    "inverted": inverted}).as_value()
        value = Mux(code == kind, named, value)
    if custom is not None:
        value = Mux(code == Crc.CUSTOM, custom.as_value(), value)
    return CRC_SETTINGS(value)


def crc_width(code, custom, kinds):
    """A word's CRC width resolved from its code (combinational): a named CRC's, the custom
    CRC's ``custom.width`` (a :data:`CRC_SETTINGS` or :data:`CRC_WIDTH_ONLY` view; ``None``
    without custom CRCs), 0 for none."""
    width = C(0, range(CRC_MAX_WIDTH + 1))
    for kind in kinds:
        width = Mux(code == kind, NAMED_CRCS[kind][0], width)
    if custom is not None:
        width = Mux(code == Crc.CUSTOM, custom.width, width)
    return width


class CrcEngine(wiring.Component):
    """Checks each data word against the CRC that follows it, one received bit per clock.

    The words of a frame follow each other on the line, so one bit-serial engine serves them
    all: before a word's first bit (``load``) it starts again from that word's settings
    (:data:`~bissmaster.params.CRC_SETTINGS`: width 0..16, register polynomial, start value,
    inversion), which is what lets any word have any CRC at no cost per word. The settings are
    resolved here, for one word at a time: ``load`` takes word ``load_index``'s code
    (``codes``) and, for a custom CRC, its ``customs`` entry, loads the register with the start
    value and holds the width, polynomial and inversion in ``settings`` for the word's bits.
    So a word's CRC is read from the configuration once per word, through one multiplexer, and
    no resolved copy per word is kept (issue 27: that was a resolution per word). A one-word
    engine takes its word's CRC resolved instead (``word_crc``, held by the master's
    configuration for the cycle, as cheap as it gets with one word) and has no ``settings``.

    **Table** (``table=True``, builds of 2+ words with custom CRCs): the custom CRCs'
    polynomials, start values and inversions are not inputs per word but one table entry,
    read combinationally (an asynchronous memory read, outside the engine): ``table_index``
    names the word ``load`` prepares, ``table`` is that word's entry, and the width comes from
    the word's resolved ``widths``. So the engine has no multiplexer over the words'
    polynomials and start values at all (issue 27: 33 bits of an eight-way multiplexer become
    a memory's read port).

    Every bit of the word *before* its CRC field (``cover``: data, nE, nW, LC) goes through
    the textbook shift register (MSB first, not reflected): feedback = register MSB xor bit,
    then shift left and xor the polynomial when the feedback is 1. The received CRC bits
    (``check``) are then compared one by one with the register's MSB (complemented when the
    encoder sends the CRC inverted) while the register shifts on, so the engine needs no
    residue table and works for every polynomial and start value. The register is
    right-aligned in 16 bits; bits above the word's width are never read.

    ``ok[w]`` is registered at word ``w``'s last bit (``last``), so it is final in the clock
    after that bit was sampled, as the old fixed checkers' was, and held until the next frame
    (the master resets the decoder, and this engine with it, between cycles: ``ok`` then reads
    1, and every word's ``last`` writes it before the verdict reads it). A word with CRC width
    0 has no ``check`` bits and ends with ``ok`` = 1.

    Attributes
    ----------
    codes : In(ArrayLayout(Crc, words))
        Each word's CRC code (``cfg_wN_crc``), held for the cycle (engines of 2+ words).
    customs : In(ArrayLayout(CRC_SETTINGS, words))
        Each word's custom CRC (``cfg_wN_crc_*``), held for the cycle (engines of 2+ words
        with custom CRCs, without ``table``).
    widths : In(ArrayLayout(range(CRC_MAX_WIDTH + 1), words))
        With ``table``: each word's resolved CRC width (Configuration.crc_widths).
    table_index : Out(range(words))
        With ``table``: the word whose entry ``table`` must give (``load_index``).
    table : In(CRC_TABLE)
        With ``table``: word ``table_index``'s custom polynomial, start value and inversion,
        in the same clock.
    word_crc : In(CRC_SETTINGS)
        One-word engines: the word's CRC, resolved, held from ``load`` to its last bit.
    index : In(range(words))
        The word the current bit belongs to (builds of more than one word).
    load : In(1)
        Load word ``load_index``'s start value (before that word's first bit: with the CDS
        bit, and with the last bit of the word before, which it overrides in the register but
        not in that word's verdict).
    load_index : In(range(words))
        The word ``load`` prepares (builds of more than one word).
    cover : In(1)
        The bit is covered by the CRC (every bit of the word before the CRC field).
    check : In(1)
        The bit is one of the word's received CRC bits.
    last : In(1)
        The bit is its word's last: register the verdict in ``ok[index]``.
    bit : In(1)
        The received bit (only read with ``cover`` or ``check``).
    ok : Out(words)
        Per word: every received CRC bit matched.
    """

    def __init__(self, words, kinds=tuple(NAMED_CRCS), custom=True, table=False):
        """``kinds``: the named CRCs any word of the build may have; ``custom``: the build has
        custom CRCs (``customs``, or with ``table`` the table port). All three are unused by a
        one-word engine."""
        self._words = words
        self._kinds = tuple(kinds)
        self._custom = custom
        self._table = table and custom and words > 1
        if words == 1:
            settings = {"word_crc": In(CRC_SETTINGS)}
        elif self._table:
            settings = {"codes": In(data.ArrayLayout(Crc, words)),
                        "widths": In(data.ArrayLayout(range(CRC_MAX_WIDTH + 1), words)),
                        "table_index": Out(range(words)),
                        "table": In(CRC_TABLE)}
        else:
            settings = {"codes": In(data.ArrayLayout(Crc, words)),
                        **({"customs": In(data.ArrayLayout(CRC_SETTINGS, words))}
                           if custom else {})}
        super().__init__({
            **settings,
            **({"index": In(range(words)), "load_index": In(range(words))} if words > 1 else {}),
            "load": In(1),
            "cover": In(1),
            "check": In(1),
            "last": In(1),
            "bit": In(1),
            "ok": Out(words, init=2**words - 1),
        })

    def elaborate(self, platform):
        m = Module()
        n = self._words
        word = self.index if n > 1 else C(0, 1)

        if n == 1:
            load_crc = crc = self.word_crc
        else:
            def of_load_word(values):
                return select_word(self.load_index, [values[w] for w in range(n)])

            if self._table:
                custom = Signal(CRC_SETTINGS, name="table_crc")
                m.d.comb += [self.table_index.eq(self.load_index),
                             custom.width.eq(of_load_word(self.widths)),
                             custom.poly.eq(self.table.poly), custom.start.eq(self.table.start),
                             custom.inverted.eq(self.table.inverted)]
            else:
                custom = of_load_word(self.customs) if self._custom else None
            load_crc = crc_settings(of_load_word(self.codes), custom, self._kinds)
            # The current word's width, polynomial and inversion (its start value went into
            # the register at ``load``).
            crc = Signal(CRC_SETTINGS, name="settings")

        reg = Signal(CRC_MAX_WIDTH)
        mismatch = Signal()
        # The MSB of a ``width``-bit register: bit width - 1, i.e. bit ``width`` of the
        # register with a 0 below it (width 0 reads that 0 and is never used). The register is
        # loaded with the start value before the word's first bit, so this wide select runs
        # on flip-flops only; the control that follows the sampler picks late.
        msb = Cat(C(0, 1), reg).bit_select(crc.width, 1)
        shifted = Cat(C(0, 1), reg[:-1])
        feedback = msb ^ self.bit
        wrong = self.check & (self.bit ^ msb ^ crc.inverted)
        seen = mismatch | wrong

        with m.If(self.load):
            m.d.sync += [reg.eq(load_crc.start), mismatch.eq(0)]
            if n > 1:
                m.d.sync += [crc.width.eq(load_crc.width), crc.poly.eq(load_crc.poly),
                             crc.inverted.eq(load_crc.inverted)]
        with m.Elif(self.cover):
            m.d.sync += reg.eq(shifted ^ Mux(feedback, crc.poly, 0))
        with m.Elif(self.check):
            m.d.sync += [reg.eq(shifted), mismatch.eq(seen)]
        with m.If(self.last):
            for w in range(n):
                with m.If(word == w):
                    m.d.sync += self.ok[w].eq(~seen)
        return m
