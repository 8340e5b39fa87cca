"""Elaboration-time parameters, the runtime configuration layout and the status codes.

:class:`MasterParams` fixes what the hardware *can* do (maximum word lengths, which CRCs exist,
counter widths); the runtime configuration (:data:`WORD_CONFIG` and the ``cfg_*`` ports of
:class:`~bissmaster.master.BissMaster`) chooses, within those limits, what it *does*.
"""

import math
from dataclasses import dataclass

from amaranth.hdl import Shape
from amaranth.lib import data, enum

from . import protocol


class Crc(enum.IntEnum, shape=2):
    """CRC of a data word (runtime code ``cfg_wN_crc``, 2 bits)."""
    NONE = 0
    CRC6 = 1    # 0x43, BiSS C / CPW / BP3
    CRC16 = 2   # 0x190D9, BiSS Safety SPW
    CUSTOM = 3  # the word's own CRC: the cfg_wN_crc_* ports (builds with custom_crc)


#: Widths of the named CRCs (the custom CRC's width is a setting).
CRC_WIDTH = {Crc.NONE: 0, Crc.CRC6: protocol.CRC6_WIDTH, Crc.CRC16: protocol.CRC16_WIDTH}
#: The widest CRC the engine checks.
CRC_MAX_WIDTH = 16

#: A word's CRC as the engine runs it (:class:`~bissmaster.core.crc_engine.CrcEngine`), and the
#: ``cfg_wN_crc_*`` ports of a custom CRC. ``poly`` is the register polynomial without its top
#: term (x^6 + x + 1 is 0x03), right-aligned in ``width`` bits, as is ``start``; the CRC runs
#: MSB first, not reflected, over every bit of the word before it; ``inverted``: the encoder
#: sends the complement of the register. ``width`` 0: no CRC.
CRC_SETTINGS = data.StructLayout({
    "width": range(CRC_MAX_WIDTH + 1),
    "poly": CRC_MAX_WIDTH,
    "start": CRC_MAX_WIDTH,
    "inverted": 1,
})
#: The part of a word's custom CRC that only the CRC engine reads, one word at a time: what a
#: ``crc_table`` build keeps in a memory (the bank's) instead of flip-flops per word. The width
#: stays a flip-flop setting per word: the configuration check reads every word's at once.
CRC_TABLE = data.StructLayout({
    "poly": CRC_MAX_WIDTH,
    "start": CRC_MAX_WIDTH,
    "inverted": 1,
})
#: A word's custom CRC as a ``crc_table`` build's ``cfg_wN_crc_*`` ports give it: the width.
CRC_WIDTH_ONLY = data.StructLayout({"width": range(CRC_MAX_WIDTH + 1)})


class Status(enum.IntEnum, shape=4):
    """Outcome of one request cycle, reported with every ``done`` strobe.

    Codes 0..5 and 13..15 judge a received frame: when several apply, the first in the order
    1..5, 13, 14, 15 wins (a CRC error makes the LC meaningless, an LC error makes the
    plausibility check moot; the line checks of issue 28 come last, so that every frame the
    protocol's checks refuse is counted as before, and UNCONFIRMED is a frame that passed
    them all). Codes 6..12 end a cycle without a frame;
    with ``cfg_end_check``, NO_STOP and SLO_STUCK_LOW can end a cycle whose frame was received,
    and then replace the frame's verdict (the frame is not reported).
    """
    OK = 0
    CRC_ERROR_WORD0 = 1     # CPW / single word
    CRC_ERROR_WORD1 = 2     # SPW
    CRC_ERROR_BOTH = 3
    SIGN_OF_LIFE = 4        # LC repeated, skipped or zero (see the lc_* flags)
    SPW_MISMATCH = 5        # SPW does not match the CPW within the tolerance
    NO_ACK = 6              # SLO never went low after the 2nd MA rise (encoder missing, line broken)
    NO_START = 7            # Ack lasted longer than the Ack limit
    DELAY_RANGE = 8         # round trip beyond the limit, or SLO low before the 2nd MA rise
    SLO_STUCK_LOW = 9       # encoder never became ready (timeout never ended)
    ABORTED = 10            # the abort input ended the cycle
    BAD_CONFIG = 11         # runtime configuration out of range; no cycle was started
    NO_STOP = 12            # cfg_end_check: SLO high at the stop bit (line stuck high, long frame)
    NOISY_LINE = 13         # more noise events since the last frame than cfg_noise_limit
    DELAY_JUMP = 14         # the round trip left the settled one by more than the tolerance
    UNCONFIRMED = 15        # passed every check, but within cfg_confirm_frames of a fault


STATUS_WIDTH = Shape.cast(Status).width


class AccessStatus(enum.IntEnum, shape=3):
    """Outcome of one register access (control channel), reported with ``ca_done``.

    See :class:`~bissmaster.control.register_access.RegisterAccess` and docs/control.md.
    """
    OK = 0
    CRC4_ERROR = 1      # a read byte's CRC-4 (or a write's echoed CRC-4) is wrong
    NO_ANSWER = 2       # no IDL0 from the slave: CDS always 0 (unidirectional encoder, no slave)
    REFUSED = 3         # R/W echo, slave start bit or P echo missing, or a write echoed differently
    ABORTED = 4         # ``ca_abort``: the control frame was cancelled with 14 CDM = 0 frames
    DATA_FAULT = 5      # a frame carrying a control bit did not pass (status not OK or UNCONFIRMED)
    BAD_REQUEST = 6     # byte count 0 or > 64, or address + count beyond 0x7F; nothing sent

#: Width of the MA half-period setting, and of the timers that count within one MA phase: the
#: largest a build may have (``MasterParams.half_period_width``, its default), and the width of
#: the register map's field.
HALF_PERIOD_WIDTH = protocol.MA_HALF_PERIOD_MAX.bit_length()
#: The narrowest ``half_period_width``: 4 bits, half periods up to 15 clocks.
HALF_PERIOD_WIDTH_MIN = 4
#: Width of ``cfg_quiet_time`` (clocks SLO must be high before MA starts; 0: the default).
QUIET_WIDTH = 12
#: Width of ``cfg_noise_limit``, ``noise_events`` and ``cfg_delay_tolerance``: 4 bits; the value
#: 15 turns a check off (the noise count saturates at 15).
LINE_CHECK_WIDTH = 4
#: Width of ``delay_spread`` (clocks, saturating at 255): jitter alone spreads the Ack edge
#: over a half period.
DELAY_SPREAD_WIDTH = 8
#: Width of the slot and MA-edge counters of one cycle (saturating): Ack slots plus the frame.
#: 2**16 - 1 slots outlast every Ack limit the timers can hold at the shortest half period.
SLOT_WIDTH = 16
#: Most data bits of one word (iC-MB4 reads up to 64 per slave).
DATA_BITS_MAX = 64
#: Bits of the longest word on the line: data, nE/nW, LC and the longest CRC.
WORD_BITS_MAX = DATA_BITS_MAX + protocol.NE_NW_BITS + protocol.LC_BITS + protocol.CRC16_WIDTH
#: Width of a bit index inside one word.
WORD_INDEX_WIDTH = WORD_BITS_MAX.bit_length()
#: Most data words one frame can have (a chain of up to 8 one-word slaves, as iC-MB4 reads).
MAX_WORDS = 8
#: The first word after a Safety encoder's CPW and SPW: words from here on are a chain's
#: further slaves (their own registers behind the bus; in memory with ``chain_memory``).
CHAIN_FIRST_WORD = 2
#: Bits of one word of the chain memory (a chain word's data is two of them, low first).
CHAIN_MEMORY_WORD_BITS = 32


def frame_length_width(words):
    """Width of a frame's length in bits: ``words`` of the longest, plus the slots around
    them (8 bits for one or two words)."""
    return max(WORD_INDEX_WIDTH + 1, (words * WORD_BITS_MAX + 8).bit_length())


#: The counter memory of a ``counter_ram`` build (:class:`~bissmaster.core.counter_ram.CounterRam`,
#: read by the bus tops' register map): words of 32 bits, each holding two counts, the even slot
#: in the low half.
COUNTER_WORD_BITS = 32
#: Bits of one count's half of a counter memory word: the widest count the memory holds.
COUNTER_HALF_BITS = COUNTER_WORD_BITS // 2


def counter_words(slots):
    """Words of a counter memory holding ``slots`` counts, two per word."""
    return (slots + 1) // 2


def counter_settle(words):
    """The longest wait, in clocks, for a count to land in a counter memory of ``words`` words:
    a read issued ``words + 3`` clocks after an event's clock returns it, whatever the other
    counts do (the words take turns, one per clock, over two words at least; CounterRam's
    docstring)."""
    return max(words, 2) + 3


#: The statuses that end a cycle without a frame verdict (codes 6..12): each has a one-clock
#: event strobe in :func:`~bissmaster.layouts.fault_layout`.
FAULTS = tuple(s for s in Status if Status.NO_ACK <= s <= Status.NO_STOP)

#: Runtime description of one data word. ``data_bits`` counts the position/data bits only.
WORD_CONFIG = data.StructLayout({
    "data_bits": 6,     # 1 .. MasterParams.max_data_bits[word] (7 bits for 64: word_config)
    "nenw": 1,          # word ends with nE, nW
    "lc": 1,            # word carries the 6-bit sign-of-life counter after nE/nW
    "crc": Crc,         # Crc code
    "gray": 1,          # the data field is Gray-coded: reported as binary
    "signed": 1,        # the data field is two's complement: sign-extended to the port's width
})
#: WORD_CONFIG without ``signed`` (builds without ``signed_words``): the same fields at the same
#: bits, one shorter, so a view of it assigned to a WORD_CONFIG reads ``signed`` = 0.
WORD_CONFIG_UNSIGNED = data.StructLayout(
    {name: field.shape for name, field in WORD_CONFIG if name != "signed"})


def word_config(params, signed=True):
    """The word description of a build: :data:`WORD_CONFIG` (or, ``signed=False``,
    :data:`WORD_CONFIG_UNSIGNED`), with a 7-bit ``data_bits`` in a build with a word of 64 data
    bits (``data_bits`` 1..64); every other build keeps the 6-bit field (1..63)."""
    layout = WORD_CONFIG if signed else WORD_CONFIG_UNSIGNED
    if max(params.max_data_bits) < DATA_BITS_MAX:
        return layout
    return data.StructLayout({name: (DATA_BITS_MAX.bit_length() if name == "data_bits"
                                     else field.shape) for name, field in layout})


def _cycles(seconds, clk_hz):
    return math.ceil(seconds * clk_hz - 1e-9)


@dataclass(frozen=True)
class MasterParams:
    """What the generated hardware supports.

    Parameters
    ----------
    sys_clk_hz : int
        System clock the core runs on; only used to turn the protocol's default times
        (break, Ack limit, timeout limit) into clock counts.
    max_data_bits : tuple of int
        Longest data field per word; its length (1 .. :data:`MAX_WORDS`) is the number of
        words the core can decode: one slave's word, a Safety encoder's CPW and SPW, or a
        chain of slaves' words back to back (docs/frames.md). Default: 55 (BP3 DL_POS
        maximum) for word 0, 40 for the SPW.
    word_crcs : tuple of tuple of Crc
        The named CRCs (:attr:`Crc.CRC6`, :attr:`Crc.CRC16`) each word accepts. A runtime
        choice outside this set is a configuration error. :attr:`Crc.NONE` is always accepted.
        One programmable engine checks every word's CRC in turn; this only sets which codes
        the configuration check lets through.
    max_line_delay : int
        Longest round trip the delay counter can measure, in system clocks.
    timer_width : int
        Width of the time settings (period, break, Ack and timeout limits) in system clocks.
    half_period_width : int
        Width of ``cfg_ma_half_period`` and of the counters that run within one MA period (the
        MA clock's phase counter, the sampler's slot timer and its reload values), 4 ..
        :data:`HALF_PERIOD_WIDTH` (16, the default): the slowest MA clock is ``sys_clk_hz /
        (2 * (2**half_period_width - 1))``. BiSS allows MA down to 80 kHz (docs/protocol.md):
        at 100 MHz that is a half period of 625 clocks, 10 bits; at 24 MHz, 150 clocks, 8
        bits. A narrower build is smaller (issue 27: the iCE40 UP5K); a longer half period
        than it holds cannot be set on the core's port, and behind the bus it is BAD_CONFIG.
    counter_width : int
        Width of each saturating error counter; 0 builds no counters (no ``count_*`` ports and
        no ``clear_counters``), for the smallest core.
    counter_ram : bool
        Keep the data channel's counters in one memory, two per 32-bit word (issue 27): the
        ``count_<name>`` ports of those counters give way to one read port (``count_addr``,
        ``count_en``, ``count_data``; docs/ports.md, Counters), and a count lands a few clocks
        after its event instead of one. Needs ``counter_width`` 1..16. The bus tops always
        build their cores this way.
    chain_memory : bool
        Keep the data of words 2..7 (a chain's further slaves) in one memory instead of
        flip-flops (issue 27): the decoder shifts them through one register and writes each
        word as it ends, and the ``word<N>_position`` ports of those words give way to one
        read port (``chain_addr``, ``chain_en``, ``chain_data``; docs/ports.md, Chains).
        Nothing changes in a build of one or two words. The bus tops build their chain cores
        this way.
    config_hold : bool
        The ``cfg_*`` inputs change only while the core lets them (issue 27; the bus tops
        build their cores this way): the core then reads them directly through the cycle
        instead of a copy latched per cycle (a flip-flop per configuration bit). The input
        ``cfg_hold`` keeps the controller in IDLE; the ``cfg_*`` inputs may change only after
        a clock with ``cfg_hold`` high and ``busy`` low (they hold their new value from the
        next clock). A ``start``, ``trigger`` or periodic tick that comes while ``cfg_hold``
        keeps the controller waiting is taken when it is released, not dropped
        (docs/ports.md, "Configuration"). The register bank holds a channel's configuration
        write until then (docs/bus.md).
    crc_table : bool
        The custom CRCs' polynomials, start values and inversions (:data:`CRC_TABLE`) are not
        ``cfg_wN_crc_*`` ports but entries of a memory outside the core, one per word, read
        through ``crc_table_addr`` (word N) and ``crc_table_data`` (its entry, combinational:
        an asynchronous read; issue 27: one table read instead of a multiplexer over every
        word's flip-flops). Needs ``config_hold`` (the table changes only while the core lets
        it, as the ``cfg_*`` inputs). Nothing changes in a build of one word or without
        ``custom_crc``. The bus tops build their cores this way.
    timestamp_width : int
        Width of the free-running time base behind the ``timestamp`` output; 0 builds neither.
    time_input : bool
        The ``timestamp`` captures the input ``time_now`` instead of a counter of the core's
        own (issue 27): several cores then share one time base (one counter for all channels
        of a bus top, whose timestamps are one clock's by construction). Needs a timestamp.
    custom_crc : bool
        Accept :attr:`Crc.CUSTOM`: each word's CRC may be any of width 1..16, polynomial,
        start value and inversion, set on its ``cfg_wN_crc_*`` ports (latched per cycle).
        Without it those ports are not built and code 3 is a configuration error.
    signed_words : bool
        Accept ``cfg_wN_signed``: a word's data may be two's complement, sign-extended to its
        port's width (one LUT per data bit). Without it those ports are not built and every
        word is unsigned.
    ssi : bool
        Accept ``cfg_ssi``: the channel may run SSI frames instead of BiSS (docs/ports.md,
        "SSI mode"): no Ack, Start or CDS, word 0 clocked out directly, the round trip set on
        ``cfg_ssi_delay``, an optional error bit (``cfg_ssi_error``, ``cfg_ssi_error_low``) and
        an optional double transmission (``cfg_ssi_double``). Without it those ports are not
        built.
    register_access : bool
        Build the register-access engine (control channel, CDM/CDS; the ``ca_*`` ports) and
        the CDM hold of MA. Without it MA is never held low after a frame.
    start_wait_frames : int
        Register reads: frames the engine waits (CDM = 1) for a slave start bit delayed by the
        slave's processing time, before it gives up with REFUSED (1 .. 255).
    """
    sys_clk_hz: int = 100_000_000
    max_data_bits: tuple = (protocol.BP3_POSITION_BITS_MAX, 40)
    word_crcs: tuple = ((Crc.CRC6, Crc.CRC16), (Crc.CRC6, Crc.CRC16))
    max_line_delay: int = 4095
    timer_width: int = 24
    half_period_width: int = HALF_PERIOD_WIDTH
    counter_width: int = 16
    counter_ram: bool = False
    chain_memory: bool = False
    config_hold: bool = False
    crc_table: bool = False
    timestamp_width: int = 32
    time_input: bool = False
    custom_crc: bool = True
    signed_words: bool = True
    ssi: bool = True
    register_access: bool = True
    start_wait_frames: int = 16

    def __post_init__(self):
        if not isinstance(self.sys_clk_hz, int) or not 1_000_000 <= self.sys_clk_hz <= 1_000_000_000:
            raise ValueError(f"sys_clk_hz must be an integer from 1 MHz to 1 GHz, not {self.sys_clk_hz!r}")
        if not 1 <= len(self.max_data_bits) <= MAX_WORDS:
            raise ValueError(f"max_data_bits must name 1 to {MAX_WORDS} words, "
                             f"not {self.max_data_bits!r}")
        for bits in self.max_data_bits:
            if not isinstance(bits, int) or not 1 <= bits <= DATA_BITS_MAX:
                raise ValueError(f"each max_data_bits entry must be an integer from 1 to "
                                 f"{DATA_BITS_MAX}, not {bits!r}")
        if len(self.word_crcs) != len(self.max_data_bits):
            raise ValueError(f"word_crcs must have one entry per word ({len(self.max_data_bits)}), "
                             f"not {self.word_crcs!r}")
        for crcs in self.word_crcs:
            for kind in crcs:
                if kind not in (Crc.CRC6, Crc.CRC16):
                    raise ValueError(f"word_crcs entries must be Crc.CRC6 or Crc.CRC16, not {kind!r}")
        if not isinstance(self.max_line_delay, int) or not 16 <= self.max_line_delay < 2**20:
            raise ValueError(f"max_line_delay must be an integer from 16 to 2**20-1 system clocks, "
                             f"not {self.max_line_delay!r}")
        if not isinstance(self.timer_width, int) or not 16 <= self.timer_width <= 32:
            raise ValueError(f"timer_width must be an integer from 16 to 32, not {self.timer_width!r}")
        if (not isinstance(self.half_period_width, int)
                or not HALF_PERIOD_WIDTH_MIN <= self.half_period_width <= HALF_PERIOD_WIDTH):
            raise ValueError(f"half_period_width must be an integer from {HALF_PERIOD_WIDTH_MIN} "
                             f"to {HALF_PERIOD_WIDTH}, not {self.half_period_width!r}")
        for default in (self.break_default, self.ack_limit_default, self.timeout_limit_default):
            if default >= 2**self.timer_width:
                raise ValueError(f"timer_width {self.timer_width} cannot hold the default time "
                                 f"{default} clocks at {self.sys_clk_hz} Hz")
        if not isinstance(self.counter_width, int) or not 0 <= self.counter_width <= 32:
            raise ValueError(f"counter_width must be an integer from 0 (no counters) to 32, "
                             f"not {self.counter_width!r}")
        if not isinstance(self.counter_ram, bool):
            raise ValueError(f"counter_ram must be a bool, not {self.counter_ram!r}")
        if not isinstance(self.config_hold, bool):
            raise ValueError(f"config_hold must be a bool, not {self.config_hold!r}")
        if not isinstance(self.crc_table, bool):
            raise ValueError(f"crc_table must be a bool, not {self.crc_table!r}")
        if self.crc_table and not self.config_hold:
            raise ValueError("crc_table needs config_hold (the table may change only while the "
                             "core is held idle)")
        if not isinstance(self.chain_memory, bool):
            raise ValueError(f"chain_memory must be a bool, not {self.chain_memory!r}")
        if self.counter_ram and not 1 <= self.counter_width <= COUNTER_HALF_BITS:
            raise ValueError(f"counter_ram needs counter_width 1..{COUNTER_HALF_BITS} (two counts "
                             f"per {COUNTER_WORD_BITS}-bit word), not {self.counter_width}")
        if not isinstance(self.time_input, bool):
            raise ValueError(f"time_input must be a bool, not {self.time_input!r}")
        if self.time_input and self.timestamp_width == 0:
            raise ValueError("time_input needs a timestamp (timestamp_width 16..64, not 0)")
        if not isinstance(self.timestamp_width, int) or not (
                self.timestamp_width == 0 or 16 <= self.timestamp_width <= 64):
            raise ValueError(f"timestamp_width must be 0 (no timestamp) or an integer from 16 "
                             f"to 64, not {self.timestamp_width!r}")
        if not isinstance(self.custom_crc, bool):
            raise ValueError(f"custom_crc must be a bool, not {self.custom_crc!r}")
        if not isinstance(self.signed_words, bool):
            raise ValueError(f"signed_words must be a bool, not {self.signed_words!r}")
        if not isinstance(self.ssi, bool):
            raise ValueError(f"ssi must be a bool, not {self.ssi!r}")
        if not isinstance(self.register_access, bool):
            raise ValueError(f"register_access must be a bool, not {self.register_access!r}")
        if not isinstance(self.start_wait_frames, int) or not 1 <= self.start_wait_frames <= 255:
            raise ValueError(f"start_wait_frames must be an integer from 1 to 255, "
                             f"not {self.start_wait_frames!r}")

    @property
    def counters(self):
        """The error counters are built."""
        return self.counter_width > 0

    @property
    def timestamped(self):
        """The time base and the ``timestamp`` output are built."""
        return self.timestamp_width > 0

    @property
    def words(self):
        return len(self.max_data_bits)

    @property
    def chain_words_in_memory(self):
        """Words 2..7 of this build are kept in the chain memory (``chain_memory`` in a build
        of more than two words)."""
        return self.chain_memory and self.words > CHAIN_FIRST_WORD

    @property
    def crc_table_built(self):
        """The custom CRCs' polynomials, start values and inversions are read from the table
        (``crc_table`` in a build of two words or more with ``custom_crc``)."""
        return self.crc_table and self.custom_crc and self.words >= 2

    @property
    def cycle_timer_width(self):
        """Width of the cycle timer and the NO_START limit: the longest limit it compares with
        is the Ack limit plus one MA period (two half periods) plus one clock, and one bit more for
        it."""
        return max(self.timer_width, self.half_period_width + 1) + 1

    @property
    def delay_tolerance_width(self):
        """Width of the round-trip check's tolerance: the half period plus
        ``cfg_delay_tolerance``, one bit more than the wider of the two."""
        return max(self.half_period_width, LINE_CHECK_WIDTH) + 1

    @property
    def slowest_ma_hz(self):
        """The slowest MA clock the build can run: the longest half period it holds."""
        return self.sys_clk_hz / (2 * (2**self.half_period_width - 1))

    @property
    def delay_limit_width(self):
        """Width of the ``cfg_delay_limit`` port."""
        return self.max_line_delay.bit_length()

    @property
    def delay_width(self):
        """Width of the delay counter: one more than the limit needs, so that a saturated
        count is out of range for every limit."""
        return (self.max_line_delay + 1).bit_length()

    # Defaults for runtime time settings left at 0.
    @property
    def break_default(self):
        """Break after power-on, an abort or a line fault: 40 us."""
        return _cycles(protocol.BREAK_TIME_S, self.sys_clk_hz)

    @property
    def ack_limit_default(self):
        """Longest wait for the Ack edge, and for the Start bit after it: 40 us."""
        return _cycles(max(protocol.PROCESSING_TIME_MAX_S, protocol.LINE_DELAY_MAX_S), self.sys_clk_hz)

    @property
    def quiet_default(self):
        """How long SLO must be high before MA starts (``cfg_quiet_time`` = 0): 1 us, longer than
        the noise pulses a line typically picks up, short next to the encoder's timeout (12.5
        us at least) and the request period (31.25 us at least); at most 4095 clocks."""
        return min(_cycles(protocol.QUIET_TIME_S, self.sys_clk_hz), 2**QUIET_WIDTH - 1)

    @property
    def timeout_limit_default(self):
        """Longest time SLO may stay low before a cycle: twice the longest static slave timeout."""
        return _cycles(2 * protocol.SLAVE_TIMEOUT_MAX_S, self.sys_clk_hz)

    def describe(self):
        """One line per parameter, for the header of generated Verilog."""
        return [
            f"sys_clk_hz      = {self.sys_clk_hz}",
            f"max_data_bits   = {list(self.max_data_bits)}",
            f"word_crcs       = {[[k.name for k in w] for w in self.word_crcs]}"
            + (" and CUSTOM (cfg_wN_crc_*)" if self.custom_crc else ""),
            f"max_line_delay  = {self.max_line_delay} clocks",
            f"timer_width     = {self.timer_width}",
            *([f"half_period_width = {self.half_period_width} (MA down to "
               f"{self.slowest_ma_hz / 1e3:.1f} kHz)"]
              if self.half_period_width != HALF_PERIOD_WIDTH else []),
            f"counter_width   = {self.counter_width}" + ("" if self.counters else " (no counters)")
            + (" in memory (count_addr, count_data)" if self.counter_ram else ""),
            f"timestamp_width = {self.timestamp_width}" + ("" if self.timestamped else " (no timestamp)")
            + (" of the input time_now" if self.time_input else ""),
            *(["chain_memory    = on (words 2.. in memory: chain_addr, chain_data)"]
              if self.chain_words_in_memory else []),
            *(["ssi             = on (cfg_ssi*)"] if self.ssi else []),
            *([f"register_access = on, start wait {self.start_wait_frames} frames"]
              if self.register_access else []),
            f"defaults (cfg = 0): break {self.break_default}, ack limit {self.ack_limit_default}, "
            f"timeout limit {self.timeout_limit_default} clocks",
        ]
