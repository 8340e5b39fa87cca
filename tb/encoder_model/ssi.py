"""Bit-exact model of an SSI encoder (docs/frames_research.md, section 2; section 3.1 items 7-11).

Written from the protocol facts collected there (source short names in brackets), not from
``rtl/``. An SSI encoder has no Ack, Start, CDS or CRC: the master clocks the data line
directly.

* Idle: clock and data high. [POSITAL; TR]
* The first falling clock edge latches the position and starts a retriggerable monoflop.
  [POSITAL; TR; Balluff; Beckhoff KL5001]
* The MSB goes on the line at the first rising edge, then one bit per rising edge.
  [POSITAL; TR; Balluff; SICK DME5000]
* n bits need n + 1 clock pulses: the rising edge after the LSB drives the line low.
  [POSITAL; Balluff]
* The line stays low for the monoflop time tm, then goes high (ready); each falling edge
  retriggers tm. [POSITAL; Kübler; Balluff; Rongde; TR]
* A new clock train within tm sends the same latched value again [INTACTON; Kübler; Vertex];
  a clock continued past the word reads zeros (iC-MU RSSI = 0) or the word again after one zero
  bit (iC-MU RSSI = 1, "ring operation"). [iC-MU]
* Binary or Gray; 0..2 error bits after the position, active high or low, Gray-coded with the
  data or not, by product. [Beckhoff; iC-MU; Leuze; SICK DL100; KEB]
* "Extended SSI": nE and nW (active low, as in a BiSS word) after the position and a CRC over
  every bit before it, like a BiSS C word without Ack and Start. [iC-MU MODEA 0x7]

The pure functions (:func:`ssi_bits`, :func:`line_levels`, :func:`parse_ssi`,
:func:`line_high_at`) give the bits and levels; :class:`SsiEncoder` runs clock trains over time
(latch, monoflop, repeats). Levels are those at the encoder, right after each rising edge:
encoder delay and cable are left to the cocotb side. Choices no source settles are marked
"(model choice)" and listed in README.md.
"""

from dataclasses import dataclass, field

import protocol_facts as facts

from .crc import bits_to_int, int_to_bits
from .frames import CRC_NONE, CRC_WIDTHS, CustomCrc, crc_width, word_crc

DATA_BITS_MAX = 64              # the widest position the model takes (issue 26: up to 64 bits)
ERROR_BITS_MAX = 2              # issue 26 / this model: 0..2 error bits after the position
TM_DEFAULT_S = 20e-6            # iC-MU: fixed 20 us timeout "to meet ... standard SSI"
IDLE_LEVEL = 1                  # clock and data idle high [POSITAL; TR]
TRAILING_LEVEL = 0              # the level after the last bit (monoflop running) [POSITAL; Balluff]

REPEAT_ZEROS = "zeros"          # clocks past the word read 0 (iC-MU RSSI = 0)
REPEAT_RING = "ring"            # the word again after one zero bit (iC-MU RSSI = 1)
REPEAT_SAME_VALUE = "same_value"    # a new train within tm restarts the same word (Kübler, ...)
REPEAT_MODES = (REPEAT_ZEROS, REPEAT_RING, REPEAT_SAME_VALUE)

ACTIVE_HIGH, ACTIVE_LOW = "high", "low"
RETRIGGER_FALLING = "falling"   # each falling edge restarts tm (TR COK-65)
RETRIGGER_ANY = "any"           # tm from the last clock edge of either kind (POSITAL's wording)


@dataclass(frozen=True)
class SsiFormat:
    """One SSI encoder's word and behaviour.

    data_bits      : position bits, 1..64, sent MSB first.
    gray           : the position is sent Gray-coded.
    error_bits     : 0..2 error bits after the position.
    error_polarity : one of ``"high"`` / ``"low"`` per error bit (``()`` = all active high):
                     the line level of an *active* error is 1 (high) or 0 (low). [iC-MU MODEA]
    gray_errors    : the error bits are Gray-coded together with the data [SICK DL100; KEB];
                     needs ``gray``. (model choice: the position and the error levels, polarity
                     applied, form one Gray-coded word)
    repeat         : ``"zeros"``, ``"ring"`` or ``"same_value"`` (module doc).
    tm_s           : monoflop time.
    retrigger      : ``"falling"`` (tm runs from the last falling edge, TR) or ``"any"``
                     (from the last clock edge, which ends a train with a rising edge).
    nenw           : extended SSI: nE and nW (active low, 1 = no error / no warning) after the
                     error bits. [iC-MU MODEA 0x7]
    crc            : extended SSI: a CRC after everything else (``frames.CRC_NONE``, ``CRC6``,
                     ``CRC16`` or a ``frames.CustomCrc``), computed over every bit before it
                     as sent, exactly as a BiSS word's CRC. [iC-MU MODEA 0x7]
    """
    data_bits: int
    gray: bool = False
    error_bits: int = 0
    error_polarity: tuple[str, ...] = ()
    gray_errors: bool = False
    repeat: str = REPEAT_ZEROS
    tm_s: float = TM_DEFAULT_S
    retrigger: str = RETRIGGER_FALLING
    nenw: bool = False
    crc: object = CRC_NONE

    def __post_init__(self):
        if not isinstance(self.data_bits, int) or not 1 <= self.data_bits <= DATA_BITS_MAX:
            raise ValueError(f"data_bits must be 1..{DATA_BITS_MAX}, got {self.data_bits!r}")
        if not isinstance(self.error_bits, int) or not 0 <= self.error_bits <= ERROR_BITS_MAX:
            raise ValueError(f"error_bits must be 0..{ERROR_BITS_MAX}, got {self.error_bits!r}")
        polarity = tuple(self.error_polarity) or (ACTIVE_HIGH,) * self.error_bits
        if len(polarity) != self.error_bits or any(p not in (ACTIVE_HIGH, ACTIVE_LOW)
                                                   for p in polarity):
            raise ValueError(f"error_polarity needs one of {ACTIVE_HIGH!r}/{ACTIVE_LOW!r} per "
                             f"error bit ({self.error_bits}), got {self.error_polarity!r}")
        object.__setattr__(self, "error_polarity", polarity)
        if self.gray_errors and not (self.gray and self.error_bits):
            raise ValueError("gray_errors needs gray=True and at least one error bit")
        if self.repeat not in REPEAT_MODES:
            raise ValueError(f"repeat must be one of {REPEAT_MODES}, got {self.repeat!r}")
        if not self.tm_s > 0:
            raise ValueError(f"tm_s must be > 0, got {self.tm_s!r}")
        if self.retrigger not in (RETRIGGER_FALLING, RETRIGGER_ANY):
            raise ValueError(f"retrigger must be {RETRIGGER_FALLING!r} or {RETRIGGER_ANY!r}, "
                             f"got {self.retrigger!r}")
        if not isinstance(self.crc, CustomCrc) and self.crc not in CRC_WIDTHS:
            raise ValueError(f"crc must be one of {sorted(CRC_WIDTHS)} or a CustomCrc, "
                             f"got {self.crc!r}")
        object.__setattr__(self, "nenw", bool(self.nenw))

    @property
    def flag_bits(self):
        """The bits after the position and before the CRC: error bits, nE nW."""
        return self.error_bits + (facts.NE_NW_BITS if self.nenw else 0)

    @property
    def crc_bits(self):
        return crc_width(self.crc)

    @property
    def total_bits(self):
        """Bits of one word on the line: position + error bits (+ nE nW + CRC, extended)."""
        return self.data_bits + self.flag_bits + self.crc_bits

    @property
    def clocks(self):
        """Clock pulses of a complete transmission: n bits need n + 1. [POSITAL; Balluff]"""
        return self.total_bits + 1


@dataclass(frozen=True)
class SsiReading:
    """A parsed word: the position in binary and each error flag (True = error active); with
    extended SSI nE / nW as on the line and whether the CRC matches (None: no such field)."""
    position: int
    errors: tuple[bool, ...] = ()
    ne: int | None = None
    nw: int | None = None
    crc_ok: bool | None = None


# -- Gray code on bit lists (MSB first), as a serial encoder or master does it -----------------
# Independent of frames.to_gray / from_gray (integers), which the tests compare it with.

def gray_encode_bits(bits):
    """Binary bits -> Gray bits: the MSB is kept, each further bit is the XOR of the binary bit
    and the one above it."""
    bits = list(bits)
    return bits[:1] + [a ^ b for a, b in zip(bits, bits[1:])]


def gray_decode_bits(bits):
    """Gray bits -> binary bits: each binary bit is the XOR of the binary bit above it and its
    own Gray bit."""
    out = []
    for g in bits:
        out.append(g if not out else out[-1] ^ g)
    return out


def _error_levels(fmt, errors):
    errors = tuple(errors)
    if len(errors) != fmt.error_bits:
        raise ValueError(f"{fmt.error_bits} error flag(s) expected, got {len(errors)}")
    levels = []
    for flag, polarity in zip(errors, fmt.error_polarity):
        if flag not in (0, 1):       # True / False are 1 / 0
            raise ValueError(f"error flags are booleans, got {flag!r}")
        levels.append(int(bool(flag)) if polarity == ACTIVE_HIGH else int(not flag))
    return levels


def ssi_bits(fmt, position, errors=None, nenw=None):
    """The word the encoder sends after the latch, MSB first, as on the line (Gray applied):
    exactly ``fmt.total_bits`` bits. ``errors``: one flag per error bit (True = active), default
    none active. ``nenw``: (nE, nW) line levels of an extended-SSI word (default (1, 1): no
    error, no warning); its CRC covers every bit before it, as sent."""
    if not isinstance(position, int) or not 0 <= position < 1 << fmt.data_bits:
        raise ValueError(f"position={position!r} does not fit in {fmt.data_bits} bits")
    data = int_to_bits(position, fmt.data_bits)
    err = _error_levels(fmt, (False,) * fmt.error_bits if errors is None else errors)
    if fmt.gray_errors:
        bits = gray_encode_bits(data + err)
    else:
        bits = (gray_encode_bits(data) if fmt.gray else data) + err
    if fmt.nenw:
        flags = (1, 1) if nenw is None else tuple(nenw)
        if len(flags) != facts.NE_NW_BITS or any(f not in (0, 1) for f in flags):
            raise ValueError(f"nenw is two line levels (nE, nW), got {nenw!r}")
        bits += [int(f) for f in flags]
    elif nenw is not None:
        raise ValueError("nenw given for a format without nE / nW")
    if fmt.crc != CRC_NONE:
        bits += int_to_bits(word_crc(fmt.crc, bits), fmt.crc_bits)
    return bits


def parse_ssi(fmt, bits):
    """Inverse of :func:`ssi_bits`: the position in binary and the error flags."""
    bits = list(bits)
    if len(bits) != fmt.total_bits:
        raise ValueError(f"expected {fmt.total_bits} bits, got {len(bits)}")
    extra = {}
    if fmt.crc != CRC_NONE:
        body = bits[:-fmt.crc_bits]
        extra["crc_ok"] = word_crc(fmt.crc, body) == bits_to_int(bits[-fmt.crc_bits:])
        bits = body
    if fmt.nenw:
        extra["ne"], extra["nw"] = bits[-facts.NE_NW_BITS:]
        bits = bits[:-facts.NE_NW_BITS]
    if fmt.gray_errors:
        bits = gray_decode_bits(bits)
    elif fmt.gray:
        bits = gray_decode_bits(bits[:fmt.data_bits]) + bits[fmt.data_bits:]
    position = bits_to_int(bits[:fmt.data_bits])
    errors = tuple(level == (1 if polarity == ACTIVE_HIGH else 0)
                   for level, polarity in zip(bits[fmt.data_bits:], fmt.error_polarity))
    return SsiReading(position, errors, **extra)


def level_after(fmt, word, index):
    """The line after rising edge ``index + 1`` counted from the word's start (``word`` as sent).

    zeros / same_value: the word, then 0 [POSITAL; Balluff; iC-MU RSSI = 0]; same_value past
    the word within one train is a model choice. ring: word, one 0, word, one 0, ... [iC-MU]
    (model choice: that one 0 is the one after the LSB, so the ring period is n + 1 clocks)
    """
    if fmt.repeat == REPEAT_RING:
        index %= len(word) + 1
    return word[index] if index < len(word) else TRAILING_LEVEL


def line_levels(fmt, position, errors=None, n_clocks=None, nenw=None):
    """The data line right after each of the master's rising edges 1..n_clocks of one clock
    train that starts from idle (the first falling edge latched ``position``).

    Edge 1 shows the MSB, edge k the k-th bit, edge ``total_bits + 1`` drives the line low; past
    that, ``fmt.repeat`` decides (zeros, or ring: the word again after that one zero).
    ``n_clocks`` defaults to ``fmt.clocks`` (n + 1). The line then stays at the last level until
    the monoflop runs out (:func:`line_high_at`), then goes high.
    """
    n_clocks = fmt.clocks if n_clocks is None else n_clocks
    if not isinstance(n_clocks, int) or n_clocks < 0:
        raise ValueError(f"n_clocks must be an int >= 0, got {n_clocks!r}")
    word = ssi_bits(fmt, position, errors, nenw)
    return [level_after(fmt, word, i) for i in range(n_clocks)]


def read_at_rising_edges(levels):
    """What a master sampling *at* each rising edge reads when the encoder's delay is above zero
    and below one clock period: the level before that edge, so the idle 1 first and the last
    level left out. [TR p. 69: it drops that 1 or uses it, with the 0 after the LSB, to watch
    for a broken line]"""
    return [IDLE_LEVEL] + list(levels[:-1]) if levels else []


def line_high_at(fmt, last_fall_s, last_rise_s=None):
    """When the line returns high: tm after the last falling edge (each falling edge retriggers
    the monoflop, TR), or with ``fmt.retrigger == "any"`` tm after the last clock edge of either
    kind (``last_rise_s`` required)."""
    if fmt.retrigger == RETRIGGER_FALLING:
        return last_fall_s + fmt.tm_s
    if last_rise_s is None:
        raise ValueError("retrigger='any' needs the time of the last rising edge")
    return max(last_fall_s, last_rise_s) + fmt.tm_s


# -- Over time: clock trains, latch, monoflop --------------------------------------------------

@dataclass
class SsiTrain:
    """One clock train as the encoder lived through it (master times = encoder times)."""
    t_first_fall_s: float
    n_clocks: int
    period_s: float
    new_latch: bool             # the first fall found the monoflop expired: a fresh latch
    t_latch_s: float            # when the sent value was latched (an earlier train's if not new)
    position: int
    errors: tuple[bool, ...]
    word: list[int]             # the word as sent (ssi_bits)
    levels: list[int]           # line after each rising edge of this train
    level_before: int           # line level from the first fall to the first rise
    line_high_s: float          # when the line goes high unless a later train retriggers
    nenw: tuple[int, int] | None = None     # extended SSI: (nE, nW) as sent

    def rising_edge_s(self, k):
        """Time of rising edge k (1..n_clocks): the clock falls at t0 + (k - 1) T and rises
        half a period later (50 % duty: model choice)."""
        return self.t_first_fall_s + (k - 1) * self.period_s + self.period_s / 2

    @property
    def t_last_fall_s(self):
        return self.t_first_fall_s + (self.n_clocks - 1) * self.period_s

    @property
    def t_last_rise_s(self):
        return self.rising_edge_s(self.n_clocks)


@dataclass
class SsiEncoder:
    """An SSI encoder over time: clock trains in, what it latched and sent out.

    ``position_at(t)`` gives the position (wrapped to ``data_bits``) at time ``t``;
    ``errors_at(t)`` the error flags (default: none active); ``nenw_at(t)`` an extended-SSI
    word's (nE, nW) (default (1, 1)). :meth:`train` runs one clock train;
    :meth:`level_at` gives the data line at any time after the trains run so far.

    A train whose first fall comes at or after the line went high latches anew. One that comes
    earlier (within tm) retriggers the monoflop and latches nothing: ``same_value`` restarts
    the latched word from its MSB [INTACTON; Kübler; Vertex]; ``zeros`` and ``ring`` go on
    shifting where the previous train stopped (model choice: a shift register that keeps
    shifting).
    """
    fmt: SsiFormat
    position_at: object
    errors_at: object = None
    nenw_at: object = None
    trains: list[SsiTrain] = field(default_factory=list, init=False)
    _shifted: int = field(default=0, init=False, repr=False)   # rising edges since (re)start

    def train(self, t_first_fall_s, n_clocks=None, period_s=1e-6):
        """Run one clock train: ``n_clocks`` pulses (default ``fmt.clocks``), the first fall at
        ``t_first_fall_s``, period ``period_s``. Returns its :class:`SsiTrain`."""
        fmt = self.fmt
        n_clocks = fmt.clocks if n_clocks is None else n_clocks
        if not isinstance(n_clocks, int) or n_clocks < 1:
            raise ValueError(f"a clock train has n_clocks >= 1, got {n_clocks!r}")
        if not 0 < period_s < fmt.tm_s:
            # tm sets the lowest clock rate (TR): a longer period lets the monoflop run out
            # between two falling edges of one train
            raise ValueError(f"period_s must be > 0 and below tm ({fmt.tm_s!r} s), "
                             f"got {period_s!r}")
        prev = self.trains[-1] if self.trains else None
        if prev is not None and t_first_fall_s <= prev.t_last_rise_s:
            raise ValueError("a train starts after the previous one's last rising edge "
                             f"({prev.t_last_rise_s!r} s), not at {t_first_fall_s!r} s")
        # a fall at exactly the moment the line goes high latches anew (model choice)
        new_latch = prev is None or t_first_fall_s >= prev.line_high_s
        if new_latch:
            t_latch = t_first_fall_s
            position = self.position_at(t_latch) % (1 << fmt.data_bits)
            errors = tuple(self.errors_at(t_latch)) if self.errors_at else (False,) * fmt.error_bits
            nenw = (tuple(self.nenw_at(t_latch)) if self.nenw_at else (1, 1)) if fmt.nenw else None
            word = ssi_bits(fmt, position, errors, nenw)
            self._shifted = 0
            level_before = IDLE_LEVEL
        else:
            t_latch, position, errors, word, nenw = (prev.t_latch_s, prev.position, prev.errors,
                                                     prev.word, prev.nenw)
            if fmt.repeat == REPEAT_SAME_VALUE:
                self._shifted = 0
            level_before = prev.levels[-1]
        levels = [level_after(fmt, word, self._shifted + i) for i in range(n_clocks)]
        self._shifted += n_clocks
        t = SsiTrain(t_first_fall_s, n_clocks, period_s, new_latch, t_latch, position, errors,
                     word, levels, level_before, 0.0, nenw)
        t.line_high_s = line_high_at(fmt, t.t_last_fall_s, t.t_last_rise_s)
        self.trains.append(t)
        return t

    def level_at(self, t_s):
        """The data line at time ``t_s`` (the level after an edge at exactly ``t_s``).

        After a train's last edge the line keeps its last level (low after a complete word; the
        current bit after an aborted train: model choice) until ``line_high_s``, then is high.
        From a train's first fall to its first rise it keeps the level it had (model choice).
        """
        started = [tr for tr in self.trains if tr.t_first_fall_s <= t_s]
        if not started:
            return IDLE_LEVEL
        tr = started[-1]
        if t_s >= tr.line_high_s:
            return IDLE_LEVEL
        k = sum(1 for i in range(1, tr.n_clocks + 1) if tr.rising_edge_s(i) <= t_s)
        return tr.levels[k - 1] if k else tr.level_before
