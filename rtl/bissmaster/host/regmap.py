"""The bus tops' register map as the host needs it: addresses, fields, status names.

Written here from docs/registers.md (generated from ``bus/biss_master.rdl``) and the status
tables of docs/ports.md and docs/control.md, never read from the RDL or the RTL at run time
(host code runs where neither the RDL compiler nor an FPGA build is; ``host/README.md``).
tb/tests/host/test_host_regmap.py checks every address, field, status and counter name here
against the SystemRDL source (through the test side's own reader, sim/shared/regspec.py) and
the test side's contract (tb/master_contract.py).

Addresses are byte addresses: a global register's is absolute, a channel register's is its
offset in the channel's block, channel ``n`` starting at :func:`channel_base` ``(n)``.
"""

#: The value of ``id``: "BiSS" in ASCII.
ID_VALUE = 0x42695353
#: The register map's major version this host software is written for (``version.major``).
MAP_MAJOR = 2
#: Channel n's block starts at CHANNEL_BASE + n * CHANNEL_STRIDE; at most MAX_CHANNELS.
CHANNEL_BASE = 0x200
CHANNEL_STRIDE = 0x200
MAX_CHANNELS = 8

#: Global registers: absolute byte address.
GLOBALS = {
    "id": 0x000,
    "version": 0x004,
    "channels": 0x008,
    "trigger": 0x00C,
    "irq_pending": 0x010,
}

#: A channel's registers: byte offset in its block.
CHANNEL = {
    "ctrl": 0x000,
    "state": 0x004,
    "caps": 0x008,
    "irq_status": 0x010,
    "irq_enable": 0x014,
    "cfg_ma": 0x020,
    "cfg_period": 0x024,
    "cfg_break": 0x028,
    "cfg_ack": 0x02C,
    "cfg_timeout": 0x030,
    "cfg_words": 0x034,
    "cfg_checks": 0x038,
    "cfg_quiet": 0x03C,
    "result.status": 0x040,
    "result.seq": 0x044,
    "result.w0_lo": 0x048,
    "result.w0_hi": 0x04C,
    "result.w1_lo": 0x050,
    "result.w1_hi": 0x054,
    "result.timestamp": 0x058,
    "result.line": 0x05C,
    "count_crc": 0x060,
    "count_ack": 0x064,
    "count_line": 0x068,
    "count_lc": 0x06C,
    "count_check": 0x070,
    "count_cycle": 0x074,
    "count_stop": 0x078,
    "count_noise": 0x07C,
    "cfg_crc0": 0x080,
    "cfg_crc0_start": 0x084,
    "cfg_crc1": 0x088,
    "cfg_crc1_start": 0x08C,
    "cfg_ssi": 0x090,
    "ca.request": 0x100,
    "ca.ctrl": 0x104,
    "ca.state": 0x108,
    "ca.count_crc4_answer": 0x10C,
    "ca.count_refused_aborted": 0x110,
    "ca.count_data_fault": 0x114,
    "ca.wbuf": 0x140,           # 16 words, write only
    "ca.rbuf": 0x180,           # 16 words, read only
}
#: Words in each of ca.wbuf / ca.rbuf (64 bytes).
BUFFER_WORDS = 16

#: Fields of each register: name -> (lsb, width). Registers not listed (result.w*_lo/hi,
#: result.timestamp, the buffers) are one field over the whole word.
FIELDS = {
    "id": {"id": (0, 32)},
    "version": {"minor": (0, 16), "major": (16, 16)},
    "channels": {"count": (0, 4)},
    "trigger": {"start": (0, 1)},
    "irq_pending": {"channel": (0, 8)},
    "ctrl": {"start": (0, 1), "abort": (1, 1), "clear_counters": (2, 1), "periodic": (8, 1),
             "trigger_enable": (9, 1)},
    "state": {"busy": (0, 1), "config_error": (1, 1)},
    "caps": {"data_bits_w0": (0, 7), "data_bits_w1": (8, 7), "timer_width": (16, 6),
             "counters": (24, 1), "timestamp": (25, 1), "register_access": (26, 1),
             "ssi": (27, 1), "words": (28, 4)},
    "irq_status": {"done": (0, 1), "error": (1, 1), "access_done": (2, 1)},
    "irq_enable": {"done": (0, 1), "error": (1, 1), "access_done": (2, 1)},
    "cfg_ma": {"ma_half_period": (0, 16), "delay_limit": (16, 12)},
    "cfg_period": {"request_period": (0, 24)},
    "cfg_break": {"break_time": (0, 24)},
    "cfg_ack": {"ack_limit": (0, 24)},
    "cfg_timeout": {"timeout_limit": (0, 24)},
    "cfg_words": {"w0_data_bits": (0, 7), "w0_nenw": (7, 1), "w0_lc": (8, 1), "w0_crc": (9, 2),
                  "w0_gray": (11, 1), "w0_signed": (12, 1), "w1_data_bits": (16, 7),
                  "w1_nenw": (23, 1), "w1_lc": (24, 1), "w1_crc": (25, 2), "w1_gray": (27, 1),
                  "w1_signed": (28, 1), "w1_enable": (31, 1)},
    "cfg_checks": {"end_check": (0, 1), "spw_check": (1, 1), "spw_tolerance": (8, 8),
                   "noise_limit": (16, 4), "delay_tolerance": (20, 4),
                   "confirm_frames": (24, 4)},
    "cfg_quiet": {"quiet_time": (0, 12)},
    "cfg_crc0": {"w0_crc_poly": (0, 16), "w0_crc_width": (16, 5), "w0_crc_inverted": (24, 1)},
    "cfg_crc0_start": {"w0_crc_start": (0, 16)},
    "cfg_crc1": {"w1_crc_poly": (0, 16), "w1_crc_width": (16, 5), "w1_crc_inverted": (24, 1)},
    "cfg_crc1_start": {"w1_crc_start": (0, 16)},
    "cfg_ssi": {"ssi": (0, 1), "ssi_error": (1, 1), "ssi_error_low": (2, 1),
                "ssi_double": (3, 1), "ssi_delay": (16, 12)},
    "result.status": {"status": (0, 4), "cds": (4, 1), "w0_ne": (8, 1), "w0_nw": (9, 1),
                      "w0_crc_ok": (10, 1), "w1_ne": (12, 1), "w1_nw": (13, 1),
                      "w1_crc_ok": (14, 1), "lc_repeat": (16, 1), "lc_skip": (17, 1),
                      "lc_zero": (18, 1), "spw_mismatch": (19, 1), "lc": (24, 6)},
    "result.seq": {"seq": (0, 16), "line_delay": (16, 13)},
    "result.w0_lo": {"data": (0, 32)},
    "result.w0_hi": {"data": (0, 32)},
    "result.w1_lo": {"data": (0, 32)},
    "result.w1_hi": {"data": (0, 32)},
    "result.timestamp": {"time": (0, 32)},
    "result.line": {"noise_events": (0, 4), "delay_settled": (4, 1), "delay_spread": (8, 8),
                    "settled_delay": (16, 13)},
    "count_crc": {"crc_word0": (0, 16), "crc_word1": (16, 16)},
    "count_ack": {"no_ack": (0, 16), "no_start": (16, 16)},
    "count_line": {"delay_range": (0, 16), "slo_stuck_low": (16, 16)},
    "count_lc": {"lc_repeat": (0, 16), "lc_skip": (16, 16)},
    "count_check": {"lc_zero": (0, 16), "spw_mismatch": (16, 16)},
    "count_cycle": {"overrun": (0, 16), "aborted": (16, 16)},
    "count_stop": {"no_stop": (0, 16), "noisy_line": (16, 16)},
    "count_noise": {"delay_jump": (0, 16), "noise_event": (16, 16)},
    "ca.request": {"slave_id": (0, 3), "address": (8, 7), "count": (16, 7), "write": (24, 1)},
    "ca.ctrl": {"start": (0, 1), "abort": (1, 1)},
    "ca.state": {"busy": (0, 1), "status": (4, 3), "bytes_done": (8, 7)},
    "ca.count_crc4_answer": {"crc4_error": (0, 16), "no_answer": (16, 16)},
    "ca.count_refused_aborted": {"refused": (0, 16), "aborted": (16, 16)},
    "ca.count_data_fault": {"data_fault": (0, 16)},
}

#: Words 2..7 of a chain (docs/bus.md, "Chains"): per word the same three settings registers
#: (16 bytes apart from 0x0A0), a CRC count and two result registers; capabilities and counts
#: two words to a register. Their fields have the same names in every word, so they are not
#: among CONFIG_REGISTERS (whose field names are the tool's settings names): the tool names a
#: chain word's settings ``wW_<field>`` (board.chain_settings).
CHAIN_WORDS = range(2, 8)
CHANNEL.update({
    "caps_chain": 0x018, "caps_chain2": 0x01C,
    "count_chain": 0x094, "count_chain2": 0x098, "count_chain3": 0x09C,
    **{f"cfg_w{w}{end}": 0x0A0 + 0x10 * (w - 2) + 4 * k for w in CHAIN_WORDS
       for k, end in enumerate(("", "_crc", "_crc_start"))},
    **{f"chain.w{w}_{half}": 0x1C0 + 8 * (w - 2) + 4 * k for w in CHAIN_WORDS
       for k, half in enumerate(("lo", "hi"))},
    "chain.flags": 0x1F0, "chain.updates": 0x1F4,
})
FIELDS.update({
    "caps_chain": {f"data_bits_{x}": (8 * k, 7) for k, x in enumerate("abcd")},
    "caps_chain2": {f"data_bits_{x}": (8 * k, 7) for k, x in enumerate("ab")},
    **{f"count_chain{n}": {"crc_a": (0, 16), "crc_b": (16, 16)} for n in ("", "2", "3")},
    **{f"cfg_w{w}": {"data_bits": (0, 7), "nenw": (8, 1), "lc": (9, 1), "crc": (10, 2),
                     "gray": (12, 1), "is_signed": (13, 1), "enable": (31, 1)}
       for w in CHAIN_WORDS},
    **{f"cfg_w{w}_crc": {"crc_poly": (0, 16), "crc_width": (16, 5), "crc_inverted": (24, 1)}
       for w in CHAIN_WORDS},
    **{f"cfg_w{w}_crc_start": {"crc_start": (0, 16)} for w in CHAIN_WORDS},
    "chain.updates": {"updates": (0, 16)},
    "chain.flags": {f"w{w}_{flag}": (4 * (w - 2) + k, 1) for w in CHAIN_WORDS
                    for k, flag in enumerate(("ne", "nw", "crc_ok"))},
    **{f"chain.w{w}_lo": {"data": (0, 32)} for w in CHAIN_WORDS},
    **{f"chain.w{w}_hi": {"data": (0, 32)} for w in CHAIN_WORDS},
})
#: Each chain word's settings registers (one READ_BURST each).
CHAIN_CONFIG_RUNS = tuple((f"cfg_w{w}", f"cfg_w{w}_crc", f"cfg_w{w}_crc_start")
                          for w in CHAIN_WORDS)
#: The chain words' CRC counts, in address order.
CHAIN_COUNTER_REGISTERS = ("count_chain", "count_chain2", "count_chain3")

#: The configuration registers, in address order: two runs of consecutive registers (one
#: READ_BURST each), the eight at 0x020, and each word's custom CRC and SSI mode at 0x080.
CONFIG_RUNS = (("cfg_ma", "cfg_period", "cfg_break", "cfg_ack", "cfg_timeout",
                "cfg_words", "cfg_checks", "cfg_quiet"),
               ("cfg_crc0", "cfg_crc0_start", "cfg_crc1", "cfg_crc1_start", "cfg_ssi"))
CONFIG_REGISTERS = CONFIG_RUNS[0] + CONFIG_RUNS[1]
#: The result block, in address order: one READ_BURST of these reads one snapshot (the first,
#: result.status, takes it).
RESULT_REGISTERS = ("result.status", "result.seq", "result.w0_lo", "result.w0_hi",
                    "result.w1_lo", "result.w1_hi", "result.timestamp", "result.line")
#: The data channel's error counters, in address order (count_crc .. count_stop).
COUNTER_REGISTERS = ("count_crc", "count_ack", "count_line", "count_lc", "count_check",
                     "count_cycle", "count_stop", "count_noise")
#: The register-access engine's counters, in address order.
CA_COUNTER_REGISTERS = ("ca.count_crc4_answer", "ca.count_refused_aborted",
                        "ca.count_data_fault")

#: ``result.status.status`` codes (docs/ports.md, Status codes).
STATUS = {
    "OK": 0, "CRC_ERROR_WORD0": 1, "CRC_ERROR_WORD1": 2, "CRC_ERROR_BOTH": 3,
    "SIGN_OF_LIFE": 4, "SPW_MISMATCH": 5, "NO_ACK": 6, "NO_START": 7, "DELAY_RANGE": 8,
    "SLO_STUCK_LOW": 9, "ABORTED": 10, "BAD_CONFIG": 11, "NO_STOP": 12,
    "NOISY_LINE": 13, "DELAY_JUMP": 14, "UNCONFIRMED": 15,
}
STATUS_NAME = {code: name for name, code in STATUS.items()}
#: Statuses of a received frame (its position, nE/nW, CRC verdicts and line delay are new).
FRAME_STATUSES = frozenset(("OK", "CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH",
                            "SIGN_OF_LIFE", "SPW_MISMATCH", "NOISY_LINE", "DELAY_JUMP",
                            "UNCONFIRMED"))
#: Statuses that say the encoder did not answer as an encoder does (no frame, or a line that
#: never goes back to idle): unplugged, unpowered, a broken wire, a wrong MA rate.
NO_ENCODER_STATUSES = frozenset(("NO_ACK", "NO_START", "DELAY_RANGE", "SLO_STUCK_LOW",
                                 "NO_STOP"))

#: ``ca.state.status`` codes (docs/control.md, Statuses).
CA_STATUS = {"OK": 0, "CRC4_ERROR": 1, "NO_ANSWER": 2, "REFUSED": 3, "ABORTED": 4,
             "DATA_FAULT": 5, "BAD_REQUEST": 6}
CA_STATUS_NAME = {code: name for name, code in CA_STATUS.items()}

#: ``cfg_wN_crc`` codes.
CRC_CODES = {"none": 0, "crc6": 1, "crc16": 2, "custom": 3}
CRC_NAMES = {code: name for name, code in CRC_CODES.items()}

#: Encoder register addresses over the control channel: 0..0x7F, 1..64 in one access.
ENCODER_REGISTERS = 0x80
MAX_ACCESS_BYTES = 4 * BUFFER_WORDS


def channel_base(ch):
    """The byte address of channel ``ch``'s block."""
    if not 0 <= ch < MAX_CHANNELS:
        raise ValueError(f"channel must be 0..{MAX_CHANNELS - 1}, not {ch!r}")
    return CHANNEL_BASE + CHANNEL_STRIDE * ch


def address(register, ch=None):
    """The byte address of a global ``register`` (``ch`` None) or of channel ``ch``'s."""
    if ch is None:
        return GLOBALS[register]
    return channel_base(ch) + CHANNEL[register]


def fields_of(register):
    """``{name: (lsb, width)}`` of ``register``."""
    return FIELDS[register]


def get(register, word, name=None):
    """The fields of ``word`` read from ``register``: a dict, or one field's value."""
    spec = FIELDS[register]
    if name is not None:
        lsb, width = spec[name]
        return (word >> lsb) & ((1 << width) - 1)
    return {n: (word >> lsb) & ((1 << width) - 1) for n, (lsb, width) in spec.items()}


def put(register, word=0, **values):
    """``word`` with the named fields of ``register`` replaced; a value too wide for its field
    raises ValueError."""
    spec = FIELDS[register]
    for name, value in values.items():
        if name not in spec:
            raise KeyError(f"{register} has no field {name!r} (fields: {', '.join(spec)})")
        lsb, width = spec[name]
        if not 0 <= int(value) < 1 << width:
            raise ValueError(f"{register}.{name} is {width} bit(s): 0..{(1 << width) - 1}, "
                             f"not {value}")
        word = word & ~(((1 << width) - 1) << lsb) | int(value) << lsb
    return word


def config_field(name):
    """The configuration register holding field ``name`` (``w0_data_bits``, or its port name
    ``cfg_w0_data_bits``); KeyError if none does."""
    bare = name[4:] if name.startswith("cfg_") else name
    for register in CONFIG_REGISTERS:
        if bare in FIELDS[register]:
            return register, bare
    known = ", ".join(f for r in CONFIG_REGISTERS for f in FIELDS[r])
    raise KeyError(f"no configuration field {name!r} (fields: {known})")
