"""The master's interfaces as data layouts, and the flat Verilog port names derived from them.

The configuration, a frame's result and the counters are :mod:`amaranth.lib.data` structures:
a word's settings and a word's result are nested structs. The components pass these views to
each other; only :class:`~bissmaster.master.BissMaster` flattens them into Verilog ports, with
:func:`flat_fields`, the one place where a port name is made from a field's path.
"""

from amaranth.hdl import C
from amaranth.lib import data

from . import protocol
from .params import (CHAIN_FIRST_WORD, CRC_SETTINGS, CRC_WIDTH_ONLY, DELAY_SPREAD_WIDTH, FAULTS,
                     LINE_CHECK_WIDTH, QUIET_WIDTH, AccessStatus, Status, word_config,
                     counter_settle, counter_words)


def config_layout(params):
    """Runtime configuration (the ``cfg_*`` ports): the MA clock, the time limits, each word.

    The member order is the port order.
    """
    tw = params.timer_width
    # ``cfg_wN_signed`` only in builds with signed words (the field is the word's last).
    word = word_config(params, signed=params.signed_words)
    members = {
        "ma_half_period": params.half_period_width,
        "request_period": tw,
        "break_time": tw,
        "ack_limit": tw,
        "timeout_limit": tw,
        "delay_limit": params.delay_limit_width,
        "end_check": 1,
        "quiet_time": QUIET_WIDTH,
        "noise_limit": LINE_CHECK_WIDTH,
        "delay_tolerance": LINE_CHECK_WIDTH,
        "confirm_frames": LINE_CHECK_WIDTH,
        "w0": word,
    }
    # A custom CRC per word (``cfg_w0_crc`` = 3): ``cfg_w0_crc_width``, ``_poly``, ``_start``,
    # ``_inverted`` (with ``crc_table``: the width alone; the rest is in the CRC table).
    custom = CRC_WIDTH_ONLY if params.crc_table_built else CRC_SETTINGS
    if params.custom_crc:
        members["w0_crc"] = custom
    # Words 1 .. N - 1 (a Safety encoder's SPW, a chain's further slaves), each with its
    # enable: ``cfg_wN_enable``, ``cfg_wN_*``, ``cfg_wN_crc_*``.
    for w in range(1, params.words):
        members.update({f"w{w}_enable": 1, f"w{w}": word})
        if params.custom_crc:
            members[f"w{w}_crc"] = custom
    if params.words >= 2:
        members.update({"spw_check": 1, "spw_tolerance": 8})
    # SSI mode (docs/ports.md, "SSI mode"): ``cfg_ssi``, the round trip ``cfg_ssi_delay``, one
    # error bit after the position and its polarity, the double transmission.
    if params.ssi:
        members.update({"ssi": 1, "ssi_delay": params.delay_limit_width, "ssi_error": 1,
                        "ssi_error_low": 1, "ssi_double": 1})
    return data.StructLayout(members)


def config_ports(params):
    """``(port name, path, shape)`` of every ``cfg_*`` port, in port order.

    The one place a configuration field gets its port name: :class:`~bissmaster.master.BissMaster`
    makes its ports from it, and host-side code (:func:`bissmaster.bp3.derive_config`) names the
    settings it derives with it.
    """
    return flat_fields(config_layout(params), "cfg_")


def config_words(cfg, params):
    """The per-word settings of a :func:`config_layout` view, word 0 first."""
    return [cfg[f"w{w}"] for w in range(params.words)]


def config_enables(cfg, params):
    """Which words a :func:`config_layout` view puts in the frame, word 0 first (word 0 is
    always in it: the constant 1)."""
    return [C(1, 1)] + [cfg[f"w{w}_enable"] for w in range(1, params.words)]


def config_custom_crcs(cfg, params):
    """The per-word custom CRC settings of a :func:`config_layout` view, word 0 first (an
    empty list in builds without ``custom_crc``; with ``crc_table``, views of the width
    alone)."""
    if not params.custom_crc:
        return []
    return [cfg[f"w{w}_crc"] for w in range(params.words)]


def word_result_layout(bits, position=True):
    """One decoded word: its data field (right-justified), nE, nW and its CRC verdict; without
    ``position`` the flags only (a word whose data is in the chain memory)."""
    return data.StructLayout({**({"position": bits} if position else {}),
                              "ne": 1, "nw": 1, "crc_ok": 1})


def result_layout(params):
    """The result of the last cycle, held from one ``done`` to the next (docs/ports.md).

    The member order is the port order. Seam for chains of slaves: the words are separate
    members ``word0``, ``word1``, ... so that a chain adds ``word<n>`` per slave word.
    """
    members = {"status": Status}
    if params.timestamped:
        members["timestamp"] = params.timestamp_width
    members.update({"line_delay": params.delay_width, "cds": 1,
                    "noise_events": LINE_CHECK_WIDTH, "delay_settled": 1,
                    "settled_delay": params.delay_width, "delay_spread": DELAY_SPREAD_WIDTH})
    for w, bits in enumerate(params.max_data_bits):
        members[f"word{w}"] = word_result_layout(
            bits, position=not (params.chain_words_in_memory and w >= CHAIN_FIRST_WORD))
    members.update({"lc": protocol.LC_BITS, "lc_repeat": 1, "lc_skip": 1, "lc_zero": 1})
    if params.words >= 2:
        members["spw_mismatch"] = 1
    return data.StructLayout(members)


def fault_layout():
    """One event strobe per status that ends a cycle without a frame verdict."""
    return data.StructLayout({status.name.lower(): 1 for status in FAULTS})


#: A buffer byte's index: up to 64 bytes per register access.
BUFFER_ADDRESS_BITS = (protocol.BANK_BYTES - 1).bit_length()
#: The buffers' host ports are 32 bits wide: byte i is lane i % 4 of word i // 4.
BUFFER_LANES = 4
BUFFER_WORDS = protocol.BANK_BYTES // BUFFER_LANES
BUFFER_WORD_BITS = (BUFFER_WORDS - 1).bit_length()


def access_request_layout():
    """A register access as the host asks for it (the ``ca_*`` request ports), in port order."""
    return data.StructLayout({
        "slave_id": protocol.CONTROL_ID_BITS,
        "address": protocol.CONTROL_ADDRESS_BITS,
        "count": protocol.BANK_BYTES.bit_length(),     # 1 .. 64
        "write": 1,
    })


def access_result_layout():
    """The result of the last register access, held from one ``ca_done`` to the next."""
    return data.StructLayout({
        "status": AccessStatus,
        "bytes_done": protocol.BANK_BYTES.bit_length(),
    })


def buffer_write_layout():
    """The host's write port into the write buffer: a word of 4 bytes (byte ``i`` of the access,
    to register ``address + i``, is lane ``i % 4`` of word ``i // 4``), a write enable per
    lane."""
    return data.StructLayout({"addr": BUFFER_WORD_BITS, "data": BUFFER_LANES * 8,
                              "en": BUFFER_LANES})


#: Saturating error counters, each with a ``count_<name>`` output port, in port order.
COUNTERS = (
    "crc_word0", "crc_word1", "no_ack", "no_start", "delay_range", "slo_stuck_low",
    "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch", "overrun", "aborted",
    "no_stop", "noisy_line", "delay_jump", "noise_event",
    "ca_crc4_error", "ca_no_answer", "ca_refused", "ca_aborted", "ca_data_fault",
)
#: The counters that only a two-word build has.
WORD1_COUNTERS = ("crc_word1", "spw_mismatch")
#: The counters of the register-access statuses (builds with the engine), named
#: ``ca_<status>``.
ACCESS_COUNTERS = ("ca_crc4_error", "ca_no_answer", "ca_refused", "ca_aborted", "ca_data_fault")


#: The counters a ``counter_ram`` build keeps in memory, in memory order: slot ``i`` is half
#: ``i % 2`` of word ``i // 2`` (the low half for even ``i``), the order of the register map's
#: counter registers (``count_crc`` .. ``count_noise``, biss_master.rdl).
RAM_COUNTERS = COUNTERS[:16]
#: Words of that memory: two counts each.
COUNT_WORDS = counter_words(len(RAM_COUNTERS))
#: Word address bits of the counter memory's read port.
COUNT_ADDR_BITS = (COUNT_WORDS - 1).bit_length()
#: Longest wait, in clocks, for a count to land in that memory after its event (15: the bus tops
#: hold a cycle's end for its counts at most this long; docs/ports.md, Counters).
COUNT_SETTLE = counter_settle(COUNT_WORDS)


def counter_slots(params):
    """A ``counter_ram`` build's memory slots: the :data:`RAM_COUNTERS`, ``None`` for those the
    build does not have (they read 0); ``()`` for other builds."""
    if not params.counter_ram:
        return ()
    names = counter_names(params)
    return tuple(name if name in names else None for name in RAM_COUNTERS)


def counter_ports(params):
    """The counters with a ``count_<name>`` port: all but those in memory."""
    return tuple(name for name in counter_names(params) if name not in counter_slots(params))


def counter_names(params):
    """The :data:`COUNTERS` a build has: none without counters, no word-1 ones for one word,
    no access ones without the register-access engine; a build of more words (a chain) has
    ``crc_word<N>`` for each word N >= 2 too, after ``crc_word1``."""
    if not params.counters:
        return ()
    names = []
    for name in COUNTERS:
        if ((params.words >= 2 or name not in WORD1_COUNTERS)
                and (params.register_access or name not in ACCESS_COUNTERS)):
            names.append(name)
        if name == "crc_word1":
            names += [f"crc_word{w}" for w in range(2, params.words)]
    return tuple(names)


def flat_fields(layout, prefix=""):
    """``(port name, path, shape)`` for every leaf of a struct layout, in member order.

    A nested member's name joins its path with ``_``: ``w0`` / ``data_bits`` under the prefix
    ``cfg_`` is the port ``cfg_w0_data_bits``.
    """
    fields = []
    for name, field in layout:
        if isinstance(field.shape, data.StructLayout):
            fields += [(full, (name, *path), shape)
                       for full, path, shape in flat_fields(field.shape, f"{prefix}{name}_")]
        else:
            fields.append((f"{prefix}{name}", (name,), field.shape))
    return fields


def field(view, path):
    """The member of a view at ``path`` (as given by :func:`flat_fields`)."""
    for name in path:
        view = view[name]
    return view
