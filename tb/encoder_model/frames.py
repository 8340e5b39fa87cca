"""Bit-exact model of what a BiSS encoder sends after Ack (docs/protocol.md, sections 5, 6 and 10).

A frame is ``Start | CDS | word0 [| word1 ...]``: one word, CPW + SPW (BiSS Safety), or a
chain of 1..8 slaves' words back to back (``FrameFormat(..., chain=True)``). Each word is
``Position | nE nW | LC | CRC`` with optional fields, all MSB first. The model builds those bits from values, parses them back,
and injects faults (flipped bits, corrupted CRCs, a CDS bit, LC errors) so the RTL tests can
check the master against frames that are right, and frames that are wrong on purpose.
"""

from dataclasses import dataclass

import protocol_facts as facts

from .crc import bits_to_int, crc6_biss, crc16_biss, crc_msb_first, int_to_bits

CRC_NONE, CRC6, CRC16 = "none", "crc6", "crc16"

CRC_WIDTHS = {CRC_NONE: 0, CRC6: facts.CRC6_WIDTH, CRC16: facts.CRC16_WIDTH}
_CRC_FUNCS = {CRC6: crc6_biss, CRC16: crc16_biss}


@dataclass(frozen=True)
class CustomCrc:
    """Any other CRC of a data word: ``width`` bits (1..16), register polynomial without its
    top term, start value, and whether the encoder sends the register inverted. Non-reflected,
    MSB first, over every bit of the word before it, like the BiSS CRCs (iC-MB4 and BP3's
    CPOLY / CSTART name such CRCs)."""
    width: int
    poly: int
    start: int = 0
    inverted: bool = True

    def __post_init__(self):
        if not 1 <= self.width <= 16:
            raise ValueError(f"a custom CRC is 1..16 bits wide, not {self.width}")
        if not (0 <= self.poly < 1 << self.width and 0 <= self.start < 1 << self.width):
            raise ValueError(f"poly and start must fit in {self.width} bits")

    def __call__(self, bits):
        return crc_msb_first(bits, width=self.width, poly=self.poly, init=self.start,
                             xor_out=(1 << self.width) - 1 if self.inverted else 0)


def crc_width(crc):
    """Bits of a word's CRC field: a named kind or a :class:`CustomCrc`."""
    return crc.width if isinstance(crc, CustomCrc) else CRC_WIDTHS[crc]


def _crc_func(crc):
    return crc if isinstance(crc, CustomCrc) else _CRC_FUNCS[crc]


def word_crc(crc, bits):
    """The CRC ``crc`` (CRC6, CRC16 or a :class:`CustomCrc`) over ``bits`` as sent: the value
    a word carries after them (also extended SSI's, encoder_model.ssi)."""
    return _crc_func(crc)(bits)

DATA_BITS_MAX = 64          # widest position field the model accepts (BiSS C data word limit)
FRAME_HEADER_BITS = 2       # Start and CDS precede the first word


@dataclass(frozen=True)
class WordFormat:
    """Layout of one data word: position, optional nE/nW, optional LC, optional CRC."""
    data_bits: int
    nenw: bool = True
    lc: bool = False
    crc: object = CRC6      # CRC_NONE, CRC6, CRC16 or a CustomCrc
    gray: bool = False      # the position is sent Gray-coded (the CRC covers the bits as sent)
    signed: bool = False    # the position field is two's complement (to_signed reads it)

    def __post_init__(self):
        if not 1 <= self.data_bits <= DATA_BITS_MAX:
            raise ValueError(f"data_bits must be 1..{DATA_BITS_MAX}, got {self.data_bits}")
        if not isinstance(self.crc, CustomCrc) and self.crc not in CRC_WIDTHS:
            raise ValueError(f"crc must be one of {sorted(CRC_WIDTHS)} or a CustomCrc, "
                             f"got {self.crc!r}")

    @property
    def crc_bits(self):
        return crc_width(self.crc)

    @property
    def total_bits(self):
        return (self.data_bits + (facts.NE_NW_BITS if self.nenw else 0)
                + (facts.LC_BITS if self.lc else 0) + self.crc_bits)


#: Words a frame may have: one slave, BiSS Safety's CPW + SPW, or a chain of up to 8 slaves
#: (one Ack, one Start, one CDS, then every slave's words back to back).
MAX_WORDS = 8


@dataclass(frozen=True)
class FrameFormat:
    """One encoder configuration: a single word, CPW + SPW for BiSS Safety, or the words of a
    chain of slaves (``chain=True``).

    A two-word format is BiSS Safety (:attr:`is_safety`: the SPW is the CPW with its
    :attr:`spw_shift` LSBs dropped) unless it says ``chain=True``; a format of three or more
    words is always a chain (each word its own slave, its own position)."""
    name: str
    words: tuple[WordFormat, ...]
    chain: bool = False

    def __post_init__(self):
        object.__setattr__(self, "words", tuple(self.words))
        if not 1 <= len(self.words) <= MAX_WORDS:
            raise ValueError(f"{self.name}: a frame has 1..{MAX_WORDS} words, "
                             f"got {len(self.words)}")
        if not all(isinstance(w, WordFormat) for w in self.words):
            raise ValueError(f"{self.name}: words must be WordFormat instances")
        if self.is_safety and self.spw_shift < 0:
            raise ValueError(f"{self.name}: the SPW cannot be finer than the CPW")

    @property
    def total_bits(self):
        """Data-word bits after Start and CDS (no Ack, no stop bit)."""
        return sum(w.total_bits for w in self.words)

    @property
    def is_safety(self):
        """BiSS Safety (CPW + SPW): two words, not declared a chain."""
        return len(self.words) == 2 and not self.chain

    @property
    def is_chain(self):
        """Words of separate slaves: declared so, or more than two words."""
        return self.chain or len(self.words) > 2

    @property
    def spw_shift(self):
        """How many CPW LSBs the SPW drops (0 for frames that have no SPW)."""
        return self.words[0].data_bits - self.words[1].data_bits if self.is_safety else 0

    def word_offsets(self):
        """Index in :func:`build_frame`'s bit list of each word's first bit (after Start, CDS)."""
        out, first = [], FRAME_HEADER_BITS
        for w in self.words:
            out.append(first)
            first += w.total_bits
        return out


def _single(name, data_bits):
    return FrameFormat(name, (WordFormat(data_bits),))


def _safety(name, cpw_bits, spw_bits):
    return FrameFormat(name, (WordFormat(cpw_bits),
                              WordFormat(spw_bits, lc=True, crc=CRC16)))


def chain_3():
    """Issue 26's chain of three BiSS C slaves on one cable, each word different: a 26-bit
    word with nE/nW and CRC-6; a 17-bit word with nE/nW and a custom CRC-8 (x^8 + x^5 + x^3 +
    x^2 + x + 1: register polynomial 0x2F, start 0xA5, sent inverted); a 12-bit word without
    nE/nW and a custom CRC-4 (x^4 + x + 1: 0x3, start 0x9, sent plain)."""
    return FrameFormat("chain_3", (
        WordFormat(26),
        WordFormat(17, crc=CustomCrc(8, 0x2F, 0xA5, True)),
        WordFormat(12, nenw=False, crc=CustomCrc(4, 0x3, 0x9, False)),
    ), chain=True)


def bp3(dl_pos):
    """BP3 Standard Encoder Profile frame with a DL_POS-bit position (C = 0: separate CRC-6)."""
    if not 1 <= dl_pos <= facts.BP3_POSITION_BITS_MAX:
        raise ValueError(f"BP3 DL_POS must be 1..{facts.BP3_POSITION_BITS_MAX}, got {dl_pos}")
    return _single(f"bp3_{dl_pos}", dl_pos)


PRESETS = {f.name: f for f in (
    # BiSS Safety, docs/protocol.md, section 5.2 table: (CPW bits, SPW bits)
    _safety("resolute_fs_lmm", 32, 32),
    _safety("resolute_fs_rsm", 28, 24),
    _safety("resolute_fs_rsh", 36, 28),
    _safety("fortis_fs_rsh", 36, 28),
    # BiSS C unidirectional single word, docs/protocol.md, section 5.1
    *(_single(f"evolute_{n}", n) for n in (26, 32, 36)),
    *(_single(f"resolute_c_{n}", n) for n in (18, 26, 32, 36)),
    *(bp3(n) for n in (1, 24, facts.BP3_POSITION_BITS_MAX)),
    # A chain of slaves (issue 26): each word its own slave
    chain_3(),
)}


@dataclass
class WordValue:
    """Field values of one word. nE/nW are active low: 1 = no error / no warning."""
    position: int
    ne: int = 1
    nw: int = 1
    lc: int | None = None


@dataclass
class FrameFaults:
    """Deliberate corruption applied by :func:`build_frame`.

    flip_bits : indices into the returned bit list (Start = 0, CDS = 1, first data bit = 2).
    crc_xor   : per word, XORed into that word's sent CRC (0 = untouched).
    cds       : value sent in the CDS slot (0 on unidirectional encoders).
    """
    flip_bits: tuple[int, ...] = ()
    crc_xor: tuple[int, ...] = ()
    cds: int = 0


def _check_field(name, value, n_bits):
    if not isinstance(value, int) or not 0 <= value < (1 << n_bits):
        raise ValueError(f"{name}={value!r} does not fit in {n_bits} bits")


def word_bits(fmt, value, *, crc_xor=0):
    """Bits of one word: position, nE, nW, LC, then CRC over everything before it.

    ``crc_xor`` corrupts the sent CRC (used by :class:`FrameFaults`).
    """
    _check_field("position", value.position, fmt.data_bits)
    sent = to_gray(value.position) if fmt.gray else value.position
    bits = int_to_bits(sent, fmt.data_bits)
    if fmt.nenw:
        _check_field("ne", value.ne, 1)
        _check_field("nw", value.nw, 1)
        bits += [value.ne, value.nw]
    if fmt.lc:
        if value.lc is None:
            raise ValueError("this word has an LC field: WordValue.lc is required")
        _check_field("lc", value.lc, facts.LC_BITS)
        bits += int_to_bits(value.lc, facts.LC_BITS)
    elif value.lc is not None:
        raise ValueError("WordValue.lc given but this word has no LC field")
    if fmt.crc == CRC_NONE:
        if crc_xor:
            raise ValueError("crc_xor given for a word without CRC")
        return bits
    _check_field("crc_xor", crc_xor, fmt.crc_bits)
    return bits + int_to_bits(_crc_func(fmt.crc)(bits) ^ crc_xor, fmt.crc_bits)


def to_gray(n):
    """The reflected binary (Gray) code of ``n``: neighbouring values differ in one bit."""
    return n ^ (n >> 1)


def from_gray(g):
    """The binary value of the Gray code ``g``: each binary bit is the XOR of the Gray bits at
    and above it."""
    n, g = g, g >> 1
    while g:
        n ^= g
        g >>= 1
    return n


def to_signed(field, bits):
    """The value of a ``bits``-wide two's complement field: its top bit weighs -2**(bits - 1)."""
    _check_field("field", field, bits)
    return field - (1 << bits) if field >> (bits - 1) else field


def build_frame(fmt, words, faults=None):
    """Bits the encoder sends after Ack: ``[Start, CDS, word bits...]``, faults applied."""
    faults = faults or FrameFaults()
    if len(words) != len(fmt.words):
        raise ValueError(f"{fmt.name} needs {len(fmt.words)} word values, got {len(words)}")
    if len(faults.crc_xor) > len(fmt.words):
        raise ValueError("more crc_xor entries than words")
    _check_field("cds", faults.cds, 1)
    crc_xor = tuple(faults.crc_xor) + (0,) * (len(fmt.words) - len(faults.crc_xor))
    bits = [facts.START_BIT, faults.cds]
    for wfmt, value, xor in zip(fmt.words, words, crc_xor):
        bits += word_bits(wfmt, value, crc_xor=xor)
    for index in faults.flip_bits:
        if not 0 <= index < len(bits):
            raise ValueError(f"flip index {index} outside the {len(bits)}-bit frame")
        bits[index] ^= 1
    return bits


def parse_frame(fmt, bits):
    """Inverse of :func:`build_frame`: the fields of every word and whether each CRC matches.

    Returns ``{"start", "cds", "crc_ok", "words": [{"position", "ne", "nw", "lc", "crc",
    "crc_ok"}, ...]}``; ``crc_ok`` at top level is True when every word's CRC matches.
    ne/nw/lc/crc are None when the word has no such field.
    """
    bits = list(bits)
    if len(bits) != FRAME_HEADER_BITS + fmt.total_bits:
        raise ValueError(f"{fmt.name}: expected {FRAME_HEADER_BITS + fmt.total_bits} bits, "
                         f"got {len(bits)}")
    pos = FRAME_HEADER_BITS

    def take(n):
        nonlocal pos
        pos += n
        return bits[pos - n:pos]

    words = []
    for wfmt in fmt.words:
        covered = take(wfmt.data_bits)
        position = bits_to_int(covered)
        word = {"position": from_gray(position) if wfmt.gray else position, "ne": None, "nw": None, "lc": None,
                "crc": None, "crc_ok": True}
        if wfmt.nenw:
            nenw = take(facts.NE_NW_BITS)
            word["ne"], word["nw"] = nenw
            covered += nenw
        if wfmt.lc:
            lc = take(facts.LC_BITS)
            word["lc"] = bits_to_int(lc)
            covered += lc
        if wfmt.crc != CRC_NONE:
            word["crc"] = bits_to_int(take(wfmt.crc_bits))
            word["crc_ok"] = word["crc"] == _crc_func(wfmt.crc)(covered)
        words.append(word)
    return {"start": bits[0], "cds": bits[1], "words": words,
            "crc_ok": all(w["crc_ok"] for w in words)}


class SignOfLife:
    """BiSS Safety LC counter: LC_FIRST, ..., LC_MAX, LC_FIRST, ... (0 is never sent).

    Each method returns the LC of one frame. :meth:`next` is the healthy encoder; the others
    are faults the master must detect: :meth:`repeat` (same value again), :meth:`skip` (frames
    lost), :meth:`zero` (the forbidden value). A fault does not disturb the healthy sequence,
    except that :meth:`skip` really consumes the skipped values.
    """

    def __init__(self, first=facts.LC_FIRST):
        _check_field("first", first, facts.LC_BITS)
        self._upcoming = first
        self._last = None

    @staticmethod
    def successor(value):
        return facts.LC_FIRST if value >= facts.LC_MAX else value + 1

    def next(self):
        self._last, self._upcoming = self._upcoming, self.successor(self._upcoming)
        return self._last

    def repeat(self):
        """The previous frame's LC again."""
        if self._last is None:
            raise ValueError("nothing to repeat before the first next()")
        return self._last

    def skip(self, n):
        """Lose ``n`` values, then send the one after them."""
        if n < 0:
            raise ValueError(f"skip count must be >= 0, got {n}")
        for _ in range(n):
            self._upcoming = self.successor(self._upcoming)
        return self.next()

    def zero(self):
        return 0


class EncoderFrameSource:
    """A moving encoder: position function in, per-latch word values and frame bits out.

    ``position_at(t)`` gives the position in CPW counts at time ``t`` (seconds); it wraps modulo
    ``2**words[0].data_bits``. The SPW (if any) is the CPW with its ``spw_shift`` LSBs dropped;
    the LC word draws from :attr:`sign_of_life` (override per frame with ``lc=``). In a chain
    every slave has its own position: ``chain_positions_at(t)`` gives one per word (each
    wrapped to its word); without it word N shows ``position_at(t)`` too.
    """

    def __init__(self, fmt, position_at, *, sign_of_life=None, ne=1, nw=1,
                 chain_positions_at=None):
        self.fmt = fmt
        self.position_at = position_at
        self.chain_positions_at = chain_positions_at
        self.sign_of_life = sign_of_life or SignOfLife()
        self.ne, self.nw = ne, nw

    def _positions(self, t_latch):
        words = self.fmt.words
        if self.fmt.is_chain:
            raw = (self.chain_positions_at(t_latch) if self.chain_positions_at
                   else [self.position_at(t_latch)] * len(words))
            return [p % (1 << w.data_bits) for p, w in zip(raw, words)]
        cpw = self.position_at(t_latch) % (1 << words[0].data_bits)
        return [cpw, cpw >> self.fmt.spw_shift][:len(words)]

    def values_at(self, t_latch, *, lc=None):
        values = []
        for wfmt, position in zip(self.fmt.words, self._positions(t_latch)):
            word_lc = None
            if wfmt.lc:
                word_lc = self.sign_of_life.next() if lc is None else lc
            values.append(WordValue(position, self.ne, self.nw, word_lc))
        return values

    def frame_at(self, t_latch, faults=None, *, lc=None):
        """``(bits, values)`` of the frame latched at ``t_latch``."""
        values = self.values_at(t_latch, lc=lc)
        return build_frame(self.fmt, values, faults), values
