"""Where each data word's fields end, registered from its runtime configuration."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from ..params import CRC_MAX_WIDTH, WORD_CONFIG, WORD_INDEX_WIDTH
from .word_select import select_word


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


def tail_bits(word, crc_width, extra=0, width=WORD_INDEX_WIDTH, error_bit=None):
    """Bits after a word's data field (nE/nW, LC, the SSI error bit, CRC), plus ``extra``,
    modulo ``2**width``: a table on the flag bits plus the CRC's width (a WORD_CONFIG view and
    its resolved CRC width; ``error_bit`` as in :func:`_flag_table`)."""
    flags = _flag_table(word, error_bit, width, lambda *f: flag_bits(*f) + extra)
    return (flags + crc_width)[:width]


def word_length(word, crc_width, extra=0, width=WORD_INDEX_WIDTH, error_bit=None):
    """Bits of one word on the line (plus ``extra``), from its runtime configuration (a
    WORD_CONFIG view and its resolved CRC width; ``error_bit`` as in :func:`_flag_table`)."""
    return (word.data_bits + tail_bits(word, crc_width, extra, width, error_bit))[:width]


#: One word's field ends, as bit indices inside the word (``idx`` of the decoder counts from 0
#: at the word's first data bit). ``_m1`` / ``_p1``: the end minus / plus one, so the decoder
#: compares ``idx`` with a register and never adds in front of a compare. ``data_at0`` and
#: ``lc_at0``: the data and the LC field are in progress at bit 0 (the decoder's field flags
#: for the word's first bit).
FIELD_ENDS = data.StructLayout({
    "data_end_p1": WORD_INDEX_WIDTH,    # the nW bit (data_bits + 1)
    "data_end_m1": WORD_INDEX_WIDTH,    # the last data bit
    "nenw_end_m1": WORD_INDEX_WIDTH,    # the last nE/nW (or SSI error) bit
    "lc_end_m1": WORD_INDEX_WIDTH,      # the last LC bit (the last flag bit)
    "word_end_m1": WORD_INDEX_WIDTH,    # the word's last bit
    "data_at0": 1,
    "lc_at0": 1,
})


def field_ends(wcfg, crc_width, err=None):
    """One word's :data:`FIELD_ENDS` as a dict of values (combinational) from its settings (a
    WORD_CONFIG view), its resolved CRC width and, for word 0 of an SSI build, its error bit.
    The "- 1" and "+ 1" are folded into tables on the flag bits (modulo
    ``2**WORD_INDEX_WIDTH``): a field end of 0, which only an invalid ``data_bits`` of 0 gives,
    becomes ``2**WORD_INDEX_WIDTH - 1``, which a bit index never reaches inside a word."""
    iw = WORD_INDEX_WIDTH
    # The flag fields' lengths: nE/nW (or the SSI error bit), and those plus LC.
    nenw_bits = _flag_table(wcfg, err, 2, lambda n, lc, e: flag_bits(n, 0, e))
    nenw_lc_bits = _flag_table(wcfg, err, 4, flag_bits)
    nenw_m1 = _flag_table(wcfg, err, iw, lambda n, lc, e: flag_bits(n, 0, e) - 1)
    nenw_lc_m1 = _flag_table(wcfg, err, iw, lambda *f: flag_bits(*f) - 1)
    return {
        "data_end_p1": (wcfg.data_bits + 1)[:iw],
        "data_end_m1": (wcfg.data_bits + C(2**iw - 1, iw))[:iw],
        "nenw_end_m1": (wcfg.data_bits + nenw_m1)[:iw],
        "lc_end_m1": (wcfg.data_bits + nenw_lc_m1)[:iw],
        # data_bits >= 1, so "- 1" folded into the table (modulo 2**iw) never wraps.
        "word_end_m1": (wcfg.data_bits + tail_bits(wcfg, crc_width, extra=-1,
                                                   error_bit=err))[:iw],
        "data_at0": wcfg.data_bits != 0,
        "lc_at0": (wcfg.data_bits + nenw_bits == 0) & (wcfg.data_bits + nenw_lc_bits != 0),
    }


class FieldEnds(wiring.Component):
    """The field boundaries of the word the decoder is in, and of the word after it, as
    registers: the decoder compares its bit index with them and never adds in front of a
    compare.

    One word: ``current`` is registered from word 0's configuration in every clock (not
    reset: it follows ``words``, ``crc_widths`` and ``error_bit`` even while the decoder
    around it is held in reset), valid one clock after its inputs settle.

    More words (issue 27: two sets of registers, not one per word): ``begin`` loads word 0's
    ends into ``current`` and word 1's into ``following``; ``advance`` (at a word's last bit,
    when another word follows) moves ``following`` into ``current`` and loads the ends of the
    word two after the one that ended (counted here: word 2 at the first ``advance`` after
    ``begin``, then one more at each). Both are valid in the clock after, so a word may begin
    in the clock after the one before ended (one sample per clock). The word to load next is a
    register, so that no decode of the decoder's state sits in front of the word multiplexer
    (it was the multi-word builds' critical path, docs/performance.md); it is word 1 from
    reset, so every frame's ``begin`` must come after a reset (the master holds the decoder,
    and this block in it, in reset between cycles) and at most once. The configuration must
    be stable from ``begin`` to the frame's end (the master latches it, or its bank holds it,
    for the cycle); ``following`` is meaningless in the last word.

    Parameters
    ----------
    words : int
        Words of the build.
    error_bit : bool
        Word 0 may have an SSI error bit after its data (SSI builds).

    Attributes
    ----------
    words : In(ArrayLayout(WORD_CONFIG, words))
    crc_widths : In(ArrayLayout(range(CRC_MAX_WIDTH + 1), words))
        Each word's settings and its resolved CRC width.
    error_bit : In(1)
        Word 0 has an SSI error bit (SSI builds: ``ssi & ssi_error``).
    begin, advance : In(1)
        Builds of more than one word: word 0 begins; the decoder moves on to the next word.
    current : Out(FIELD_ENDS)
        The current word's field ends (registered).
    following : Out(FIELD_ENDS)
        Builds of more than one word: the next word's (registered).
    """

    def __init__(self, words, error_bit=False, word_layout=WORD_CONFIG):
        self._words = words
        self._error_bit = error_bit
        super().__init__({
            "words": In(data.ArrayLayout(word_layout, words)),
            "crc_widths": In(data.ArrayLayout(range(CRC_MAX_WIDTH + 1), words)),
            **({"error_bit": In(1)} if error_bit else {}),
            **({"begin": In(1), "advance": In(1),
                "following": Out(FIELD_ENDS)} if words > 1 else {}),
            "current": Out(FIELD_ENDS),
        })

    def elaborate(self, platform):
        m = Module()
        n = self._words
        err = self.error_bit if self._error_bit else None
        current = Signal(FIELD_ENDS, name="current_ends", reset_less=True)
        first = field_ends(self.words[0], self.crc_widths[0], err)
        m.d.comb += self.current.eq(current)
        if n == 1:
            m.d.sync += [current[k].eq(v) for k, v in first.items()]
            return m
        following = Signal(FIELD_ENDS, name="following_ends", reset_less=True)
        m.d.comb += self.following.eq(following)
        # The word whose ends go into ``following`` next: word 1 at ``begin`` (from reset: the
        # master holds the decoder in reset before every frame), then two after the current
        # one at each ``advance`` (never word 0: only word 0 has the SSI error bit). A
        # register: one multiplexer on the settings, then one computation of the ends, with
        # nothing of the decoder's state in front of them.
        pick = Signal(range(max(n, 3)), name="following_word", init=1)
        chosen = field_ends(select_word(pick, [self.words[w] for w in range(n)]),
                            select_word(pick, [self.crc_widths[w] for w in range(n)]))
        with m.If(self.begin):
            m.d.sync += [current[k].eq(v) for k, v in first.items()]
            m.d.sync += [following[k].eq(v) for k, v in chosen.items()]
            m.d.sync += pick.eq(2)
        with m.Elif(self.advance):
            m.d.sync += current.eq(following)
            m.d.sync += [following[k].eq(v) for k, v in chosen.items()]
            m.d.sync += pick.eq((pick + 1)[:len(pick)])
        return m
