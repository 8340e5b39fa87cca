"""BiSS C control communication, slave side: CRC-4, a banked register file, a BP3 EDS bank and
the CDM/CDS state machine of an encoder (docs/protocol.md sections 7 and 10).

Written from the protocol description only; nothing here comes from ``rtl/`` (no ``bissmaster``
import), because this is what the RTL's register-access engine is checked against.

Frame alignment (docs/protocol.md, section 10): after data frame ``n`` the master holds MA low through the
encoder's timeout for CDM = 1 or leaves it high for CDM = 0; the encoder samples that bit at the
end of its timeout and answers it in the CDS slot of frame ``n + 1``. :meth:`ControlSlave.step`
is that moment: it takes the CDM of frame ``n`` and returns the CDS of frame ``n + 1``.

The layout the slave implements, frames counted from ``s0``, the frame whose CDM is S:

============  ===========================================  ======================================
frame         CDM (master, sent after the frame)           CDS (slave, in the frame)
============  ===========================================  ======================================
s0            S = 1 (after >= 14 frames of CDM = 0)        0
s0+1..s0+17   CTS, ID[2:0], ADR[6:0], CRC4[3:0], R, W      s0+1..s0+8 IDL0..IDL7, then 0
s0+17, +18    (W), S = 1                                   echo of R (s0+17), echo of W (s0+18)
s0+19..s0+30  read: 12 x 0; write: DATA[7:0], CRC4[3:0]    s0+19 start bit; s0+20..s0+27 DATA or
                                                           its echo; s0+28..s0+31 CRC4 or its echo
s0+31         P = 0                                        (CRC4 bit 0 / its echo)
s0+32         S = 1: next register (sequential) or 0: end  echo of P
============  ===========================================  ======================================

A sequential continuation repeats the last four rows with ``c0`` = the frame of the new S
(``c0 = s0 + 32`` for the second register): CDS ``c0+1`` start bit, ``c0+2..c0+9`` data (echo),
``c0+10..c0+13`` CRC4 (echo), CDM ``c0+1..c0+12`` slots, ``c0+13`` P, CDS ``c0+14`` = echo of P,
and ``c0 + 14`` is the next continuation's S: 14 frames per further register, as the spec says.
That reading agrees with the Lenz BiSS C master library (github.com/lenzencoders/BISS-C,
``BiSS_C_Master/lib/BiSS_C_Master/biss_c_master.c``: S again right after P, 13 CDM bits per
register after it) and with Microchip's chapter (an optional start bit after the stop bit).

Readings the spec leaves open (each one a constructor option where it matters; see
tb/encoder_model/README.md):

* Idle count (``strict_idle``): by default an S needs 14 consecutive CDM = 0 on the line before
  it, whatever they were (the spec's text: 14 zeros cancel any control frame and precede the
  next). After a read, whose 12 slots and P are zeros, one more frame then does. With
  ``strict_idle=True`` only the frames after the end of the previous control frame count (P
  excluded): the spec's "14 idle + 32 = 46 frames per access" arithmetic, stricter than its
  text (a master that gives up in the middle of a read and then sends 14 zeros is not answered:
  the slave finishes the read on those zeros and wants 14 more). In both readings 14
  consecutive zeros inside a control frame cancel it and count as the next frame's idle.
* IDL bits: answered to S, CTS, ID and ADR[6:4] before the slave knows the ID, so they depend
  only on the slave: slave 0 sends 1,0,0,0,0,0,0,0 (spec); other IDs a one-hot bit at their
  own position (``idl`` option; unconfirmed).
* A request the slave does not take (another slave's ID, a bad header CRC-4, CTS = 0 commands,
  R = W) is answered with the IDL bits and then CDS = 0 until the line idles (14 zeros).
* Refused write (a read-only register, ``refused_write``): ``"no_start"`` (default) echoes R
  and W and withholds the start bit; ``"no_echo"`` withholds the W echo and the start bit. A
  refused register inside a sequential write gets no start bit.
* A write whose data CRC-4 is wrong is not executed; the echo still echoes what arrived, and
  the slave takes no continuation after it. P received as 1 is echoed and ends the frame.
* Address wrap in a sequential access (``wrap_address``): 0x7F + 1 = 0x00 (7-bit counter) or,
  with ``False``, no start bit for the register after 0x7F.
* Processing time (``start_delay``): the start bit may come ``start_delay`` frames late; the
  master keeps CDM = 1 meanwhile (TI's master), and everything after it shifts.
"""

from __future__ import annotations

from dataclasses import dataclass

from .crc import _check_bit, bits_to_int, int_to_bits

__all__ = [
    "IDLE_FRAMES", "CRC4_WIDTH", "CRC4_POLY", "CRC4_XOR_OUT", "BANK_SIZE",
    "BANK_SELECT", "EDS_BANK", "PROFILE_ID", "DATA_LENGTH", "SERIAL_NUMBER", "DEVICE_ID",
    "MANUFACTURER_ID", "USER_REGISTERS", "ADDRESS_BITS", "ADDRESS_COUNT", "ID_BITS", "DATA_BITS",
    "IDL_BITS", "SLOTS",
    "crc4", "crc4_header", "crc4_data", "byte_bits", "bits_value",
    "RegisterFile", "Bp3Eds", "eds_checksum", "ControlFaults", "SlaveAccess", "ControlSlave",
]

# -- protocol facts (docs/protocol.md, section 10) ---------------------------------------------------------
IDLE_FRAMES = 14            # CDM = 0 frames before S; as many in a row cancel a control frame
CRC4_WIDTH = 4
CRC4_POLY = 0x3             # x^4 + x + 1 without its x^4 term (0x13 with it)
CRC4_INIT = 0
CRC4_XOR_OUT = 0xF          # sent inverted
ID_BITS = 3
ADDRESS_BITS = 7
DATA_BITS = 8
IDL_BITS = 8
SLOTS = DATA_BITS + CRC4_WIDTH      # CDM bits after a start bit, before P

# Control frame offsets from s0 (the frame whose CDM is S).
CTS_AT = 1
HEADER_CRC_END = 15         # the last header CRC bit (s0+12 .. s0+15)
R_AT, W_AT, SECOND_S_AT = 16, 17, 18

# -- standard registers (docs/protocol.md, sections 7 and 10) ----------------------------------------------
BANK_SIZE = 64                      # 0x00..0x3F show the selected bank
BANK_SELECT = 0x40                  # R/W
EDS_BANK = 0x41                     # read only: where the EDS starts; 0x00 / 0xFF = no EDS
PROFILE_ID = 0x42                   # read only (BP3: 0x62 | C)
DATA_LENGTH = 0x43                  # read only (BP3: DL)
SERIAL_NUMBER = range(0x44, 0x48)   # read only, raw bytes
USER_REGISTERS = range(0x48, 0x78)  # the model's writable RAM (not from the spec)
DEVICE_ID = range(0x78, 0x7E)       # read only, raw bytes
MANUFACTURER_ID = range(0x7E, 0x80)  # read only, raw bytes
ADDRESS_COUNT = 1 << ADDRESS_BITS

# -- BP3 profile (docs/protocol.md, section 7) -------------------------------------------------------------
BP3_ID = 0b0110
BP3_VERSION = 1
BP3_FEEDBACK_BITS = 2               # nE, nW: DL = DL_POS + 2
BP3_DL_MAX = {0: 0x39, 1: 0x3F}     # by the C bit
BP3_DL_MIN = 0x02


def _check_uint(name, value, n_bits):
    if not isinstance(value, int) or not 0 <= value < (1 << n_bits):
        raise ValueError(f"{name} must be an unsigned {n_bits}-bit int, not {value!r}")
    return value


def byte_bits(value, n=DATA_BITS):
    """``value`` as ``n`` bits, MSB first (the order every control field is sent in)."""
    return int_to_bits(_check_uint("value", value, n), n)


#: Inverse of :func:`byte_bits` (the model's MSB-first conversion, :func:`crc.bits_to_int`).
bits_value = bits_to_int


def crc4(bits):
    """CRC-4 of a bit sequence as the line carries it: x^4 + x + 1, start 0, MSB first, inverted.

    A shift register fed one bit at a time, the textbook (non-reflected) definition.
    """
    mask = (1 << CRC4_WIDTH) - 1
    reg = CRC4_INIT
    for bit in bits:
        feedback = ((reg >> (CRC4_WIDTH - 1)) & 1) ^ _check_bit(bit)
        reg = (reg << 1) & mask
        if feedback:
            reg ^= CRC4_POLY
    return reg ^ CRC4_XOR_OUT


def crc4_header(slave_id, address, cts=1):
    """The header CRC-4: over the 11 bits CTS, ID[2:0], ADR[6:0] (S excluded)."""
    return crc4([_check_bit(cts)] + byte_bits(slave_id, ID_BITS) + byte_bits(address, ADDRESS_BITS))


def crc4_data(value):
    """The data CRC-4: over DATA[7:0] (both directions)."""
    return crc4(byte_bits(value))


# -- register file ----------------------------------------------------------------------------
def eds_checksum(bank):
    """BP3 CHKSUM: the sum of bytes 0x00..0x3E, modulo 256."""
    if len(bank) != BANK_SIZE:
        raise ValueError(f"an EDS bank has {BANK_SIZE} bytes, not {len(bank)}")
    return sum(bank[:BANK_SIZE - 1]) & 0xFF


class RegisterFile:
    """The 128 registers a BiSS slave shows, with banks behind 0x00..0x3F.

    0x00..0x3F show bank ``read(0x40)``; 0x40 is read/write; 0x41..0x47 and 0x78..0x7F are read
    only; 0x48..0x77 are plain read/write registers (the model's "user registers"). Bank bytes
    are read only unless the bank is listed in ``writable_banks``; a bank that was never set
    reads 0x00. The multi-byte IDs are raw bytes at increasing addresses (byte order is the
    manufacturer's, docs/protocol.md, section 10).
    """

    def __init__(self, *, eds_bank=0x00, profile_id=0x00, data_length=0x00,
                 serial_number=bytes(4), device_id=bytes(6), manufacturer_id=bytes(2),
                 banks=None, writable_banks=(), bank_select=0x00):
        self._regs = bytearray(ADDRESS_COUNT)
        for name, rng, raw in (("serial_number", SERIAL_NUMBER, serial_number),
                               ("device_id", DEVICE_ID, device_id),
                               ("manufacturer_id", MANUFACTURER_ID, manufacturer_id)):
            raw = bytes(raw)
            if len(raw) != len(rng):
                raise ValueError(f"{name} must be {len(rng)} bytes, not {len(raw)}")
            self._regs[rng.start:rng.stop] = raw
        self._regs[EDS_BANK] = _check_uint("eds_bank", eds_bank, 8)
        self._regs[PROFILE_ID] = _check_uint("profile_id", profile_id, 8)
        self._regs[DATA_LENGTH] = _check_uint("data_length", data_length, 8)
        self._regs[BANK_SELECT] = _check_uint("bank_select", bank_select, 8)
        self.banks: dict[int, bytearray] = {}
        for number, data in (banks or {}).items():
            self.set_bank(number, data)
        self.writable_banks = {_check_uint("writable bank", b, 8) for b in writable_banks}

    @classmethod
    def bp3(cls, eds: Bp3Eds, *, eds_bank=1, serial_number=b"\x12\x34\x56\x78",
            device_id=b"BP3MOD", manufacturer_id=b"iC", **kwargs):
        """A BP3 encoder: 0x42/0x43 from ``eds``, its EDS bank at ``eds_bank`` (pointer 0x41).

        The 64-byte BP3 table is placed directly at the bank the pointer names (no common EDS
        part in front of it: how a common part locates the profile part is not settled here).
        """
        if eds_bank in (0x00, 0xFF):
            raise ValueError(f"eds_bank 0x00 and 0xFF mean 'no EDS', not {eds_bank:#04x}")
        return cls(eds_bank=eds_bank, profile_id=eds.profile_id, data_length=eds.data_length,
                   serial_number=serial_number, device_id=device_id,
                   manufacturer_id=manufacturer_id,
                   banks={eds_bank: eds.to_bytes(), **kwargs.pop("banks", {})}, **kwargs)

    def set_bank(self, number, data):
        data = bytes(data)
        _check_uint("bank number", number, 8)
        if len(data) != BANK_SIZE:
            raise ValueError(f"a bank has {BANK_SIZE} bytes, not {len(data)}")
        self.banks[number] = bytearray(data)

    @property
    def bank_select(self):
        return self._regs[BANK_SELECT]

    def writable(self, address):
        _check_uint("address", address, ADDRESS_BITS)
        if address < BANK_SIZE:
            return self.bank_select in self.writable_banks
        return address == BANK_SELECT or address in USER_REGISTERS

    def read(self, address):
        _check_uint("address", address, ADDRESS_BITS)
        if address < BANK_SIZE:
            bank = self.banks.get(self.bank_select)
            return 0 if bank is None else bank[address]
        return self._regs[address]

    def write(self, address, value):
        """Store ``value``; False (and nothing changes) if the register is read only."""
        _check_uint("value", value, DATA_BITS)
        if not self.writable(address):
            return False
        if address < BANK_SIZE:
            self.banks.setdefault(self.bank_select, bytearray(BANK_SIZE))[address] = value
        else:
            self._regs[address] = value
        return True


# -- BP3 EDS bank ------------------------------------------------------------------------------
_EDS_LAYOUT = (     # (field, address, bytes) from the table in docs/protocol.md, section 7; U16/U32 big endian
    ("bp_ver", 0x00, 1), ("bp_len", 0x01, 1), ("bp_id", 0x02, 1), ("dl", 0x03, 1),
    ("fb1", 0x04, 1), ("fb2", 0x05, 1), ("pon_pdl", 0x06, 1), ("en_typ", 0x08, 1),
    ("pos_num", 0x09, 1), ("mt_len", 0x0A, 1), ("mt_fmt", 0x0B, 1), ("co_len", 0x0C, 1),
    ("co_fmt", 0x0D, 1), ("fi_len", 0x0E, 1), ("fi_fmt", 0x0F, 1),
    ("mt_cnt", 0x10, 4), ("sip_cnt", 0x14, 4), ("sip_res", 0x18, 4), ("cpoly", 0x1C, 4),
    ("cstart", 0x20, 4), ("abs_acu", 0x24, 2), ("rel_acu", 0x26, 2), ("spd_acu", 0x28, 2),
    ("hyst", 0x2A, 2), ("spd_max", 0x2C, 2), ("acc_max", 0x2E, 2), ("tmp_min", 0x30, 2),
    ("tmp_max", 0x32, 2), ("vlt_min", 0x34, 2), ("vlt_max", 0x36, 2), ("cur_max", 0x38, 2),
)
CHKSUM_AT = 0x3F
U32_MAX = 0xFFFFFFFF


@dataclass(frozen=True)
class Bp3Eds:
    """The BP3 profile part of an EDS (one 64-byte bank), field names as in docs/protocol.md, section 7.

    ``dl_pos`` and ``c`` decide BP_ID (0x60 | VER << 1 | C) and DL (DL_POS + 2, the nE/nW bits;
    the model uses the same rule for C = 1, unconfirmed). The other fields are plausible values
    of a rotary encoder; override any of them. CPOLY is stored without x^0 (0x43 -> 0x21).
    """
    dl_pos: int
    c: int = 0
    bp_ver: int = BP3_VERSION
    bp_len: int = 1
    fb1: int = 1                    # nE
    fb2: int = 2                    # nW
    pon_pdl: int = 10               # ms
    en_typ: int = 0                 # rotary
    pos_num: int = 1
    mt_len: int = 0
    mt_fmt: int = 0
    co_len: int | None = None       # default: DL_POS - MT_LEN
    co_fmt: int = 0
    fi_len: int = 0
    fi_fmt: int = 0
    mt_cnt: int | None = None       # default: 2 ** MT_LEN (at most 0xFFFFFFFF)
    sip_cnt: int | None = None      # default: with sip_res, 2 ** (DL_POS - MT_LEN) counts/rev
    sip_res: int | None = None
    cpoly: int = 0x43 >> 1
    cstart: int = 0
    abs_acu: int = 100
    rel_acu: int = 10
    spd_acu: int = 20
    hyst: int = 1
    spd_max: int = 12000
    acc_max: int = 1000
    tmp_min: int = 233              # K
    tmp_max: int = 378
    vlt_min: int = 4500             # mV
    vlt_max: int = 5500
    cur_max: int = 150              # mA

    def __post_init__(self):
        _check_uint("c", self.c, 1)
        dl_max = BP3_DL_MAX[self.c] - BP3_FEEDBACK_BITS
        if not isinstance(self.dl_pos, int) or not 1 <= self.dl_pos <= dl_max:
            raise ValueError(f"dl_pos must be 1..{dl_max} with C = {self.c}, not {self.dl_pos!r}")
        if not 0 <= self.mt_len <= self.dl_pos:
            raise ValueError(f"mt_len must be 0..dl_pos, not {self.mt_len!r}")
        single_turn = self.dl_pos - self.mt_len
        res_bits = min(single_turn, 31)
        defaults = {"co_len": single_turn, "mt_cnt": min(1 << self.mt_len, U32_MAX),
                    "sip_res": 1 << res_bits, "sip_cnt": 1 << (single_turn - res_bits)}
        for name, value in defaults.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, value)
        for name, _, size in _EDS_LAYOUT:
            _check_uint(name, self.value_of(name), 8 * size)

    @property
    def profile_id(self):
        """Register 0x42 / EDS byte 0x02: ID 0b0110, VER, C."""
        return (BP3_ID << 4) | (self.bp_ver << 1) | self.c

    @property
    def data_length(self):
        """Register 0x43 / EDS byte 0x03: DL = DL_POS + 2."""
        return self.dl_pos + BP3_FEEDBACK_BITS

    def value_of(self, name):
        """The value of one EDS field (BP_ID and DL are derived)."""
        if name == "bp_id":
            return self.profile_id
        if name == "dl":
            return self.data_length
        return getattr(self, name)

    def to_bytes(self):
        """The 64 bytes of the bank, checksum at 0x3F."""
        bank = bytearray(BANK_SIZE)
        for name, address, size in _EDS_LAYOUT:
            bank[address:address + size] = self.value_of(name).to_bytes(size, "big")
        bank[CHKSUM_AT] = eds_checksum(bank)
        return bytes(bank)


# -- the control slave -------------------------------------------------------------------------
@dataclass
class ControlFaults:
    """Deliberate misbehaviour of :class:`ControlSlave` (all off by default).

    crc_xor       : XORed into every CRC-4 the slave sends (read data CRC, echo of a write's
                    CRC); ``crc_xor_registers`` limits it to those register indices of an access
                    (0 = the first register), None = all.
    unidirectional: CDS always 0 and CDM ignored (a RESOLUTE / EVOLUTE: no control side).
    write_protected: every register is read only (every write is refused).
    silent_from   : from CDS frame s0 + ``silent_from`` on, the slave sends CDS = 0 until its
                    control frame ends (it stops answering mid-frame); its state goes on.
    """
    crc_xor: int = 0
    crc_xor_registers: tuple[int, ...] | None = None
    unidirectional: bool = False
    write_protected: bool = False
    silent_from: int | None = None

    def __post_init__(self):
        _check_uint("crc_xor", self.crc_xor, CRC4_WIDTH)
        if self.silent_from is not None and (not isinstance(self.silent_from, int)
                                             or self.silent_from < 1):
            raise ValueError(f"silent_from must be >= 1 or None, not {self.silent_from!r}")


@dataclass
class SlaveAccess:
    """One register the slave read or was asked to write (appended as it happens)."""
    write: bool
    address: int
    value: int                      # the byte sent (read) or received (write)
    executed: bool                  # read: sent; write: stored
    reason: str = ""                # why a write was not stored
    frame: int = 0                  # ControlSlave.frame when it happened



class ControlSlave:
    """The control side of one BiSS slave, stepped once per data frame.

    Parameters
    ----------
    registers : RegisterFile
        What reads return and writes change (an empty one by default).
    slave_id : int
        The ID (0..7) the slave answers to; 0 for a point-to-point encoder.
    idl : sequence of 8 bits, optional
        The IDL0..IDL7 answer; default one-hot at ``slave_id`` (1,0,...,0 for slave 0).
    start_delay : int
        Extra frames before the slave's start bit (its processing time).
    refused_write : "no_start" or "no_echo"
        How a write to a read-only register is refused (module doc).
    wrap_address : bool
        Sequential access past 0x7F continues at 0x00 (True) or gets no start bit (False).
    strict_idle : bool
        Count the 14 idle frames only after a control frame ended (module doc); default: any
        14 consecutive CDM = 0.
    faults : ControlFaults
        Deliberate faults; may be replaced at any time (``slave.faults = ...``).

    Attributes
    ----------
    cds : int
        The CDS bit of the next data frame.
    frame : int
        Number of :meth:`step` calls so far.
    accesses : list of SlaveAccess
        Every register read or write request, in order.
    aborts : int
        Control frames ended by 14 consecutive CDM = 0 rather than after P (cancelled by the
        master, or refused by the slave and waited out).
    """

    def __init__(self, registers=None, *, slave_id=0, idl=None, start_delay=0,
                 refused_write="no_start", wrap_address=True, strict_idle=False, faults=None):
        self.registers = registers if registers is not None else RegisterFile()
        self.slave_id = _check_uint("slave_id", slave_id, ID_BITS)
        if idl is None:
            idl = [int(i == slave_id) for i in range(IDL_BITS)]
        self.idl = tuple(_check_bit(b) for b in idl)
        if len(self.idl) != IDL_BITS:
            raise ValueError(f"idl must have {IDL_BITS} bits, not {len(self.idl)}")
        if not isinstance(start_delay, int) or start_delay < 0:
            raise ValueError(f"start_delay must be an int >= 0, not {start_delay!r}")
        self.start_delay = start_delay
        if refused_write not in ("no_start", "no_echo"):
            raise ValueError(f"refused_write must be 'no_start' or 'no_echo', "
                             f"not {refused_write!r}")
        self.refused_write = refused_write
        self.wrap_address = bool(wrap_address)
        self.strict_idle = bool(strict_idle)
        self.faults = faults if faults is not None else ControlFaults()
        self.cds = 0
        self.frame = 0
        self.accesses: list[SlaveAccess] = []
        self.aborts = 0
        self._state = "idle"
        self._zeros = 0         # consecutive CDM = 0 on the line, this frame's included
        self._zeros_before = 0  # the same before this frame's CDM
        self._idle = 0          # CDM = 0 frames since the last control frame ended (strict)
        self._k = 0             # offset of the CDM being received from s0
        self._header: list[int] = []
        self._write = False
        self._address = 0
        self._register = 0      # index of the register within the access
        self._slot = 0
        self._out_bits: list[int] = []      # read: DATA + CRC4 to send
        self._in_bits: list[int] = []       # write: DATA + CRC4 received
        self._write_failed = False
        self._delay = 0

    # -- public ------------------------------------------------------------------------------
    @property
    def state(self):
        """idle, header, delay, slots, stop, after_p or wait_idle."""
        return self._state

    @property
    def in_control_frame(self):
        return self._state != "idle"

    def step(self, cdm):
        """The CDM of frame n (sampled at the end of the timeout) in, the CDS of frame n+1 out."""
        _check_bit(cdm)
        self.frame += 1
        if self.faults.unidirectional:      # no control side at all: nothing read or written
            self.cds = 0
            return 0
        self._zeros_before = self._zeros
        self._zeros = self._zeros + 1 if cdm == 0 else 0
        if self._state not in ("idle", "after_p") and self._zeros >= IDLE_FRAMES:
            self.aborts += 1
            self._to_idle(self._zeros)
            out = 0
        else:
            out = getattr(self, f"_on_{self._state}")(cdm)
        self.cds = self._masked(out)
        return self.cds

    # -- states ------------------------------------------------------------------------------
    def _on_idle(self, cdm):
        ready = (self._idle if self.strict_idle else self._zeros_before) >= IDLE_FRAMES
        if cdm == 0:
            self._idle += 1
            return 0
        self._idle = 0
        if not ready:
            return 0                # a 1 without the idle frames before it is no S
        self._state, self._k, self._header, self._register = "header", 0, [], 0
        return self.idl[0]

    def _on_header(self, cdm):
        self._k += 1
        k = self._k
        self._header.append(cdm)
        if k < IDL_BITS:
            return self.idl[k]
        if k == HEADER_CRC_END:
            if not self._header_ok():
                self._state = "wait_idle"
            return 0
        if k == R_AT:
            return cdm              # echo of R
        if k == W_AT:
            return self._decide(self._header[R_AT - CTS_AT], cdm)
        if k == SECOND_S_AT:
            if cdm != 1:
                self._state = "wait_idle"
                return 0
            return self._begin_register()
        return 0

    def _on_delay(self, cdm):
        self._k += 1
        self._delay -= 1
        if self._delay > 0:
            return 0
        self._state, self._slot = "slots", 0
        return 1

    def _on_slots(self, cdm):
        self._k += 1
        j = self._slot
        self._slot += 1
        if self._write:
            self._in_bits.append(cdm)
            out = cdm
            if j >= DATA_BITS:
                out ^= (self._crc_xor() >> (SLOTS - 1 - j)) & 1
        else:
            out = self._out_bits[j]
        if self._slot == SLOTS:
            self._state = "stop"
            if self._write:
                self._finish_write()
        return out

    def _on_stop(self, cdm):
        self._k += 1
        if cdm != 0 or self._write_failed:
            self._state = "wait_idle"
        else:
            self._state = "after_p"
        return cdm                  # echo of P

    def _on_after_p(self, cdm):
        self._k += 1
        if cdm == 0:                # the control frame ends; this is the first idle frame
            self._state = "idle"
            self._idle = 1
            return 0
        self._register += 1
        self._address += 1
        if self._address >= ADDRESS_COUNT:
            if not self.wrap_address:
                self._state = "wait_idle"
                return 0
            self._address = 0
        if self._write and not self._writable(self._address):
            self._refuse(self._address, "read-only")
            self._state = "wait_idle"
            return 0
        return self._begin_register()

    def _on_wait_idle(self, cdm):
        self._k += 1
        return 0

    # -- helpers -----------------------------------------------------------------------------
    def _header_ok(self):
        h = self._header                                    # CTS, ID, ADR, CRC (k = 1..15)
        cts, ident, adr = h[0], bits_value(h[1:4]), bits_value(h[4:11])
        crc = bits_value(h[11:15])
        if cts != 1 or ident != self.slave_id or crc != crc4_header(ident, adr, cts):
            return False
        self._address = adr
        return True

    def _decide(self, r, w):
        """W received: the access is read (R=1, W=0) or write (R=0, W=1); the W echo."""
        if r == w:
            self._state = "wait_idle"
            return w
        self._write = w == 1
        if self._write and not self._writable(self._address):
            self._refuse(self._address, "read-only")
            self._state = "wait_idle"
            return w if self.refused_write == "no_start" else 0
        return w

    def _writable(self, address):
        return not self.faults.write_protected and self.registers.writable(address)

    def _refuse(self, address, reason):
        self.accesses.append(SlaveAccess(True, address, 0, False, reason, self.frame))

    def _begin_register(self):
        """S received for register ``_address``: the start bit now or after the delay."""
        self._in_bits, self._write_failed = [], False
        if not self._write:
            value = self.registers.read(self._address)
            self._out_bits = byte_bits(value) + byte_bits(crc4_data(value) ^ self._crc_xor(),
                                                          CRC4_WIDTH)
            self.accesses.append(SlaveAccess(False, self._address, value, True, "", self.frame))
        if self.start_delay:
            self._state, self._delay = "delay", self.start_delay
            return 0
        self._state, self._slot = "slots", 0
        return 1

    def _finish_write(self):
        value = bits_value(self._in_bits[:DATA_BITS])
        if bits_value(self._in_bits[DATA_BITS:]) != crc4_data(value):
            self._write_failed = True
            self.accesses.append(SlaveAccess(True, self._address, value, False, "crc",
                                             self.frame))
            return
        stored = self._writable(self._address) and self.registers.write(self._address, value)
        self._write_failed = not stored
        self.accesses.append(SlaveAccess(True, self._address, value, stored,
                                         "" if stored else "read-only", self.frame))

    def _crc_xor(self):
        regs = self.faults.crc_xor_registers
        return self.faults.crc_xor if regs is None or self._register in regs else 0

    def _to_idle(self, idle_frames):
        self._state = "idle"
        self._idle = idle_frames

    def _masked(self, out):
        silent = self.faults.silent_from
        if silent is not None and self._state != "idle" and self._k + 1 >= silent:
            return 0
        return out
