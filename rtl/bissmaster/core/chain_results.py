"""The chain memory: the data of words 2..7, written by the decoder as each word ends."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..params import CHAIN_FIRST_WORD, CHAIN_MEMORY_WORD_BITS as WORD_BITS, MAX_WORDS

#: Memory words per data word: its bits 31..0, then 63..32.
HALVES = 2
#: Width of the read address: every chain word of the largest build (words 2..7), so that a
#: reader (the register map) addresses every build the same way; a word the build lacks
#: reads 0.
CHAIN_ADDR_BITS = (HALVES * (MAX_WORDS - CHAIN_FIRST_WORD) - 1).bit_length()
#: Width of a chain word's index (W - 2), the same in every build (a build of one chain word
#: would otherwise have a zero-width index).
CHAIN_INDEX_BITS = (MAX_WORDS - CHAIN_FIRST_WORD - 1).bit_length()


class ChainResults(wiring.Component):
    """The data of a chain's words 2..7 in one memory of two pages instead of two flip-flop
    copies per word (the decoder's shift register and the result register; issue 27).

    Writing: ``word_end`` strobes in the clock the last bit of chain word ``CHAIN_FIRST_WORD
    + index`` is sampled; ``data`` holds that word's data from the next clock until the next
    word's first data bit, at least one sample period (4 clocks) later. Its bits 31..0 are
    written in the clock after ``word_end``, its bits 63..32 (0 above the word) in the one
    after, into the page being written. ``publish`` (a frame whose fields become the result:
    the result registers' ``report_frame``, at least 2 clocks after the last word's
    ``word_end``) makes that page the one read and takes ``words_published`` (the frame's
    words); the other page is written next. A frame that is not published (a fault) is overwritten
    by the next, so the page read always holds the last published frame's words, as the
    result registers hold the last decoded frame's.

    Reading: memory word ``read_addr`` = 2 (W - 2) + h is bits 32 h + 31 .. 32 h of word W,
    the register map's order (``chain.w2_lo``, ``chain.w2_hi``, ...). ``read_addr`` with
    ``read_en`` in one clock; from the next, ``read_data`` is that word as it is in each
    clock, until the next ``read_en``: the memory is read asynchronously from the address
    taken (distributed RAM), so a reader that takes the word a clock or more later (the
    register map, at ``r_load``) gets that clock's value, as from a flip-flop. The published
    frame changes in the clock after ``publish``, the clock the result registers change in
    (``done``). The word is 0 for a word the published frame did not have, and for every
    word before the first publication (also after a reset: the memory's contents are not
    reset).

    Parameters
    ----------
    words : int
        The build's words (3..8): the memory holds words 2 .. ``words`` - 1.
    data_bits : int
        Width of ``data``: the longest of those words, 1..64.

    Attributes
    ----------
    data : In(data_bits)
    index : In(CHAIN_INDEX_BITS)
    word_end, publish : In(1)
    words_published : In(range(words + 1))
        ``words`` above: the frame's word count, taken with ``publish``.
    read_addr : In(CHAIN_ADDR_BITS)
        A word the build lacks (``read_addr`` // 2 + 2 >= ``words``) reads 0.
    read_en : In(1)
    read_data : Out(32)
    """

    def __init__(self, words, data_bits):
        if not CHAIN_FIRST_WORD < words <= MAX_WORDS:
            raise ValueError(f"the chain memory holds words 2..{MAX_WORDS - 1} of a build of "
                             f"3 to {MAX_WORDS} words, not {words}")
        if not 1 <= data_bits <= HALVES * WORD_BITS:
            raise ValueError(f"a chain word has 1 to {HALVES * WORD_BITS} data bits, "
                             f"not {data_bits}")
        self._chain = words - CHAIN_FIRST_WORD
        self._data_bits = data_bits
        super().__init__({
            "data": In(data_bits),
            "index": In(CHAIN_INDEX_BITS),
            "word_end": In(1),
            "publish": In(1),
            "words_published": In(range(words + 1)),
            "read_addr": In(CHAIN_ADDR_BITS),
            "read_en": In(1),
            "read_data": Out(WORD_BITS),
        })

    def elaborate(self, platform):
        m = Module()
        slots = HALVES * self._chain
        slot_bits = (slots - 1).bit_length()
        # Two pages: the one read (the last published frame) and the one written.
        m.submodules.memory = memory = Memory(shape=WORD_BITS, depth=2 << slot_bits, init=[])
        wr = memory.write_port()
        rd = memory.read_port(domain="comb")
        write_page, read_page = Signal(), Signal()
        published = Signal(range(self._chain + 1))     # chain words of the published frame
        with m.If(self.publish):
            m.d.sync += [read_page.eq(write_page), write_page.eq(~write_page),
                         published.eq(Mux(self.words_published > CHAIN_FIRST_WORD,
                                          self.words_published - CHAIN_FIRST_WORD, 0))]

        # The word's bits 31..0 in the clock after its end (its last bit may be a data bit,
        # in ``data`` from then on), bits 63..32 in the one after, into the page being
        # written when it ended.
        low, high = Signal(), Signal()
        index = Signal.like(self.index)
        page = Signal()
        m.d.sync += [low.eq(self.word_end), high.eq(low)]
        with m.If(self.word_end):
            m.d.sync += [index.eq(self.index), page.eq(write_page)]
        data = self.data.as_unsigned()
        low_half, high_half = data[:WORD_BITS], data[WORD_BITS:]
        m.d.comb += [
            wr.en.eq(low | high),
            wr.addr.eq(Cat(Cat(high, index)[:slot_bits], page)),
            wr.data.eq(Mux(high, high_half, low_half) if len(high_half) else
                       Mux(high, 0, low_half)),
        ]

        # The read: the address taken at ``read_en``, the memory read asynchronously from it,
        # so the word is that of the clock it is taken in, as a flip-flop's would be; 0 for a
        # word the published frame did not have.
        address = Signal.like(self.read_addr)
        with m.If(self.read_en):
            m.d.sync += address.eq(self.read_addr)
        m.d.comb += [
            rd.addr.eq(Cat(address[:slot_bits], read_page)),
            self.read_data.eq(Mux((address >> 1) < published, rd.data, 0)),
        ]
        return m
