"""BP3 Standard Encoder Profile on the host: identification, EDS, the core's data-channel settings.

Nothing here talks to hardware. :func:`identify` runs its register accesses through two
callables the caller supplies (cocotb against the simulated core; the C driver's
biss_bp3_read_eds makes the same accesses in C, docs/driver.md);
:func:`decode_profile_id` and :func:`decode_eds` turn register bytes into typed records;
:func:`derive_config` turns a record into the values of the core's ``cfg_*`` ports. Each check
that fails raises a :class:`Bp3Error` that names the register, byte or field: no setting is ever
derived from data that did not pass every check.

Protocol facts: ``docs/protocol.md`` sections 6, 7 and 10.

Where the profile part of the EDS is (an assumption)
----------------------------------------------------
Register 0x41 points to the bank where the EDS *starts* (the iC-Haus iC-MU datasheet calls it
"pointer to first EDS bank", "start of EDS part"). The BP3 profile says an EDS is a common part
followed by the profile part, and counts the profile part in banks (BP_LEN = 1). None of the
sources read (iC-Haus iC-MU and iC-MB4 datasheets, the BiSS C protocol description, Microchip's
and TI's BiSS masters, Lenz's BiSS C library) says how long the common part is or how it points
to the profile part. This module assumes that the common part fills exactly one bank, so that
the BP3 bank is the bank after the pointer: ``profile_bank_offset=1``, the default of
:func:`identify`. An encoder whose pointer names the BP3 bank itself is read with
``profile_bank_offset=0``. A wrong offset cannot go unnoticed: the bank read then fails the
checksum, the BP_ID check or the cross-check with registers 0x42/0x43.
"""

import enum
import struct
from dataclasses import dataclass, field

from .. import protocol
from ..layouts import config_ports
from ..params import CRC_MAX_WIDTH, Crc, MasterParams

__all__ = [
    "Bp3Error", "NotBp3Error", "FieldRangeError", "ChecksumError", "InconsistentFieldsError",
    "NoEdsError", "RegisterAccessError", "UnsupportedEncoderError",
    "CrcMode", "Feedback", "EncoderType", "Alignment", "ProfileId", "Bp3Eds", "Identification",
    "EDS_LAYOUT", "decode_profile_id", "decode_eds", "derive_config", "identify",
]


# -- Errors ------------------------------------------------------------------------------------

class Bp3Error(Exception):
    """An encoder's identification or EDS cannot be used; the message says where and why."""


class NotBp3Error(Bp3Error):
    """The profile ID (register 0x42 bits 7:4, or the EDS's BP_ID) is not BP3's 0b0110."""


class FieldRangeError(Bp3Error):
    """A register or EDS field holds a value the profile does not allow."""


class ChecksumError(Bp3Error):
    """The EDS bank's CHKSUM byte is not the sum of its other bytes."""


class InconsistentFieldsError(Bp3Error):
    """The EDS contradicts registers 0x42/0x43 (BP_ID, DL)."""


class NoEdsError(Bp3Error):
    """Register 0x41 (EDS pointer) reads 0x00 or 0xFF: the encoder has no EDS."""


class RegisterAccessError(Bp3Error):
    """A register read returned the wrong number of bytes, or a bank select did not take."""


class UnsupportedEncoderError(Bp3Error):
    """A valid BP3 encoder whose data channel this build of the core cannot read as described."""


# -- Field codes -------------------------------------------------------------------------------

class CrcMode(enum.IntEnum):
    """C, register 0x42 bit 0."""
    SEPARATE = 0    # CRC separate from the data, checked by the master (Standard Encoder)
    SAFETY = 1      # mandatory within a BiSS Safety encoder


class Feedback(enum.IntEnum):
    """FB1 / FB2: the function of a feedback bit (both active low on the line)."""
    ERROR = 1       # nE
    WARNING = 2     # nW


class EncoderType(enum.IntEnum):
    """EN_TYP."""
    ROTARY = 0
    LINEAR = 1


class Alignment(enum.IntEnum):
    """MT_FMT: how the multiturn value sits in its field."""
    RIGHT = 0
    LEFT = 1


# -- Registers 0x42 / 0x43 ---------------------------------------------------------------------

@dataclass(frozen=True)
class ProfileId:
    """Registers 0x42 (ID = 0b0110, VER, C) and 0x43 (DL) of a BP3 encoder, checked.

    Attributes
    ----------
    version : int
        VER, register 0x42 bits 3:1: 1.
    crc_mode : CrcMode
        C, register 0x42 bit 0.
    data_length : int
        DL, register 0x43 bits 6:0: data bits without the CRC, 0x02..0x39 with C = 0,
        0x02..0x3F with C = 1.
    """
    version: int
    crc_mode: CrcMode
    data_length: int

    @property
    def position_bits(self):
        """DL_POS = DL - 2 (the feedback bits nE, nW) with C = 0; ``None`` with C = 1, where
        the profile gives no such split."""
        if self.crc_mode is CrcMode.SEPARATE:
            return self.data_length - protocol.NE_NW_BITS
        return None

    def to_bytes(self):
        """The contents of registers 0x42 and 0x43 (and of EDS bytes BP_ID, DL)."""
        return bytes([(protocol.BP3_PROFILE_ID << 4) | (self.version << 1) | self.crc_mode,
                      self.data_length])


def _check_byte(name, value):
    if not isinstance(value, int) or not 0 <= value <= 0xFF:
        raise ValueError(f"{name} must be an integer from 0 to 255, not {value!r}")


def _decode_profile_id(id_byte, dl_byte, id_where, dl_where):
    profile, version, c = id_byte >> 4, (id_byte >> 1) & 0b111, id_byte & 1
    if profile != protocol.BP3_PROFILE_ID:
        raise NotBp3Error(f"{id_where} = 0x{id_byte:02X}: profile ID (bits 7:4) 0b{profile:04b} "
                          f"is not BP3 (0b{protocol.BP3_PROFILE_ID:04b})")
    if version != protocol.BP3_VERSION:
        raise FieldRangeError(f"{id_where} = 0x{id_byte:02X}: VER (bits 3:1) = {version}; "
                              f"{protocol.BP3_VERSION} is the only BP3 version "
                              f"(0 not allowed, 2..7 reserved)")
    mode = CrcMode(c)
    dl_max = (protocol.BP3_DL_MAX_SEPARATE_CRC if mode is CrcMode.SEPARATE
              else protocol.BP3_DL_MAX_SAFETY)
    if not protocol.BP3_DL_MIN <= dl_byte <= dl_max:
        raise FieldRangeError(f"{dl_where} = 0x{dl_byte:02X}: DL must be "
                              f"0x{protocol.BP3_DL_MIN:02X}..0x{dl_max:02X} with C = {c} "
                              f"(and bit 7 = 0)")
    return ProfileId(version, mode, dl_byte)


def decode_profile_id(reg_0x42, reg_0x43):
    """Check and decode the BP3 profile ID registers.

    Parameters
    ----------
    reg_0x42, reg_0x43 : int
        The bytes read from registers 0x42 and 0x43.

    Returns
    -------
    ProfileId

    Raises
    ------
    NotBp3Error
        ID (0x42 bits 7:4) is not 0b0110.
    FieldRangeError
        VER is not 1, or DL is outside the range C allows (or 0x43 bit 7 is set).
    """
    _check_byte("reg_0x42", reg_0x42)
    _check_byte("reg_0x43", reg_0x43)
    return _decode_profile_id(reg_0x42, reg_0x43,
                              f"register 0x{protocol.REG_PROFILE_ID:02X}",
                              f"register 0x{protocol.REG_PROFILE_ID + 1:02X}")


# -- EDS bank ----------------------------------------------------------------------------------

#: The BP3 EDS bank (docs/protocol.md, section 7): symbol, byte address, :mod:`struct` code (big endian).
#: Bytes 0x07 and 0x3A..0x3E are not fields (they count in CHKSUM only).
EDS_LAYOUT = (
    ("BP_VER", 0x00, "B"), ("BP_LEN", 0x01, "B"), ("BP_ID", 0x02, "B"), ("DL", 0x03, "B"),
    ("FB1", 0x04, "B"), ("FB2", 0x05, "B"), ("PON_PDL", 0x06, "B"),
    ("EN_TYP", 0x08, "B"), ("POS_NUM", 0x09, "B"),
    ("MT_LEN", 0x0A, "B"), ("MT_FMT", 0x0B, "B"), ("CO_LEN", 0x0C, "B"), ("CO_FMT", 0x0D, "B"),
    ("FI_LEN", 0x0E, "B"), ("FI_FMT", 0x0F, "B"),
    ("MT_CNT", 0x10, "I"), ("SIP_CNT", 0x14, "I"), ("SIP_RES", 0x18, "I"),
    ("CPOLY", 0x1C, "I"), ("CSTART", 0x20, "I"),
    ("ABS_ACU", 0x24, "H"), ("REL_ACU", 0x26, "H"), ("SPD_ACU", 0x28, "H"), ("HYST", 0x2A, "H"),
    ("SPD_MAX", 0x2C, "H"), ("ACC_MAX", 0x2E, "H"),
    ("TMP_MIN", 0x30, "H"), ("TMP_MAX", 0x32, "H"), ("VLT_MIN", 0x34, "H"), ("VLT_MAX", 0x36, "H"),
    ("CUR_MAX", 0x38, "H"),
    ("CHKSUM", 0x3F, "B"),
)
_ADDRESS = {symbol: address for symbol, address, _ in EDS_LAYOUT}
_CHECKSUM_ADDRESS = _ADDRESS["CHKSUM"]

#: Fields whose codes are an enumeration.
_ENUMS = {"FB1": Feedback, "FB2": Feedback, "EN_TYP": EncoderType, "MT_FMT": Alignment}
#: Fields with a range the profile states (inclusive).
_RANGES = {"BP_VER": (1, 1), "BP_LEN": (1, 1), "PON_PDL": (1, 254), "POS_NUM": (0, 2)}


@dataclass(frozen=True)
class Bp3Eds:
    """The 64-byte BP3 EDS bank, every field of the profile's table, checked.

    Attribute names are the table's symbols in lower case; ``dl`` is the unnamed byte 0x03.
    Unsigned integers unless an enumeration is given; U16/U32 fields are big endian in the bank.

    Attributes
    ----------
    bp_ver : int
        Profile version: 1.
    bp_len : int
        Length of this profile in banks: 1.
    bp_id : int
        Profile ID, the content of register 0x42 (0x62 for C = 0).
    dl : int
        Data length, the content of register 0x43.
    fb1, fb2 : Feedback
        Function of the first and second feedback bit (nE, nW).
    pon_pdl : int
        Longest power-on delay until position data is available, ms (1..254).
    en_typ : EncoderType
    pos_num : int
        Number of position values: 0 undefined, 1 or 2.
    mt_len, co_len, fi_len : int
        Multiturn, coarse and fine length in bits.
    mt_fmt : Alignment
    co_fmt, fi_fmt : int
        Coarse and fine format; docs/protocol.md gives no codes for them, so they stay raw bytes.
    mt_cnt : int
        Distinguishable revolutions / periods.
    sip_cnt : int
        Signal periods per revolution, or the signal period length in nm (linear).
    sip_res : int
        Resolution factor per signal period (LSB of the interpolation).
    cpoly : int
        CRC polynomial bits 32:1 (x^0 implied: 0x43 is stored as 0x21); see
        :attr:`crc_polynomial`.
    cstart : int
        CRC start value.
    abs_acu, rel_acu, spd_acu, hyst : int
        Absolute, repeat and speed-dependent accuracy, hysteresis.
    spd_max, acc_max : int
        Largest speed (1/min or m/min) and acceleration.
    tmp_min, tmp_max : int
        Operating temperature, K.
    vlt_min, vlt_max : int
        Operating voltage, mV.
    cur_max : int
        Largest current, mA.
    chksum : int
        Sum of bytes 0x00..0x3E, mod 256 (checked).
    raw : bytes
        The 64 bytes as read.
    """
    bp_ver: int
    bp_len: int
    bp_id: int
    dl: int
    fb1: Feedback
    fb2: Feedback
    pon_pdl: int
    en_typ: EncoderType
    pos_num: int
    mt_len: int
    mt_fmt: Alignment
    co_len: int
    co_fmt: int
    fi_len: int
    fi_fmt: int
    mt_cnt: int
    sip_cnt: int
    sip_res: int
    cpoly: int
    cstart: int
    abs_acu: int
    rel_acu: int
    spd_acu: int
    hyst: int
    spd_max: int
    acc_max: int
    tmp_min: int
    tmp_max: int
    vlt_min: int
    vlt_max: int
    cur_max: int
    chksum: int
    raw: bytes = field(repr=False)

    @property
    def profile_id(self):
        """BP_ID and DL decoded as :class:`ProfileId` (checked when the bank was decoded)."""
        return _decode_profile_id(self.bp_id, self.dl, _where("BP_ID"), _where("DL"))

    @property
    def crc_polynomial(self):
        """The CRC polynomial with its top and x^0 terms (CPOLY 0x21 -> 0x43); 0 if CPOLY is 0."""
        return (self.cpoly << 1) | 1 if self.cpoly else 0


def _where(symbol):
    return f"EDS byte 0x{_ADDRESS[symbol]:02X} ({symbol})"


def decode_eds(bank, *, profile=None):
    """Check and decode a BP3 EDS bank.

    Parameters
    ----------
    bank : bytes
        The 64 bytes of the bank, address 0x00 first.
    profile : ProfileId, optional
        Registers 0x42/0x43 as read from the encoder; BP_ID and DL must then hold the same.

    Returns
    -------
    Bp3Eds

    Raises
    ------
    ChecksumError
        CHKSUM is not the sum of bytes 0x00..0x3E mod 256 (checked first).
    NotBp3Error
        BP_ID is not a BP3 profile ID.
    FieldRangeError
        A field outside what the profile allows (BP_VER, BP_LEN, BP_ID's VER, DL, FB1, FB2,
        PON_PDL, EN_TYP, POS_NUM, MT_FMT).
    InconsistentFieldsError
        BP_ID or DL differ from ``profile``.
    """
    bank = bytes(bank)
    if len(bank) != protocol.BANK_BYTES:
        raise ValueError(f"an EDS bank is {protocol.BANK_BYTES} bytes, not {len(bank)}")
    if profile is not None and not isinstance(profile, ProfileId):
        raise TypeError(f"profile must be a ProfileId, not {profile!r}")

    checksum = sum(bank[:_CHECKSUM_ADDRESS]) & 0xFF
    if bank[_CHECKSUM_ADDRESS] != checksum:
        raise ChecksumError(f"{_where('CHKSUM')} = 0x{bank[_CHECKSUM_ADDRESS]:02X}, but bytes "
                            f"0x00..0x{_CHECKSUM_ADDRESS - 1:02X} sum to 0x{checksum:02X} "
                            f"(mod 256)")

    values = {symbol: struct.unpack_from(">" + code, bank, address)[0]
              for symbol, address, code in EDS_LAYOUT}
    _decode_profile_id(values["BP_ID"], values["DL"], _where("BP_ID"), _where("DL"))
    for symbol, (low, high) in _RANGES.items():
        if not low <= values[symbol] <= high:
            allowed = f"{low}" if low == high else f"{low}..{high}"
            raise FieldRangeError(f"{_where(symbol)} = {values[symbol]}, must be {allowed}")
    for symbol, codes in _ENUMS.items():
        try:
            values[symbol] = codes(values[symbol])
        except ValueError:
            known = ", ".join(f"{c.value} ({c.name})" for c in codes)
            raise FieldRangeError(f"{_where(symbol)} = {values[symbol]}, not one of {known}") \
                from None

    if profile is not None:
        id_reg, dl_reg = profile.to_bytes()
        for symbol, register, expected in (("BP_ID", protocol.REG_PROFILE_ID, id_reg),
                                           ("DL", protocol.REG_PROFILE_ID + 1, dl_reg)):
            if values[symbol] != expected:
                raise InconsistentFieldsError(
                    f"{_where(symbol)} = 0x{values[symbol]:02X}, but register "
                    f"0x{register:02X} = 0x{expected:02X}")

    return Bp3Eds(**{symbol.lower(): value for symbol, value in values.items()}, raw=bank)


# -- The core's settings -----------------------------------------------------------------------

#: The CRCs the core can check, by their polynomial with the top term. Every one starts at 0
#: and is sent inverted (section 6).
_CORE_CRCS = {
    (1 << protocol.CRC6_WIDTH) | protocol.CRC6_POLY: Crc.CRC6,       # 0x43
    (1 << protocol.CRC16_WIDTH) | protocol.CRC16_POLY: Crc.CRC16,    # 0x190D9
}


def _data_crc(eds, params):
    """Word 0's CRC settings for the CRC that CPOLY and CSTART name: ``{path: value}``. CRC-6
    0x43 with start 0 is the named CRC-6 (code 1), as before custom CRCs existed; any other
    polynomial of degree 1..16 with a start value that fits is a custom CRC (code 3), sent
    inverted as every BiSS CRC is (section 6)."""
    if eds.cpoly == 0:
        raise UnsupportedEncoderError(f"{_where('CPOLY')} = 0: no CRC; a BP3 data channel has "
                                      f"one, and the core will not read positions unchecked")
    polynomial = eds.crc_polynomial                     # with its top term and x^0
    width = polynomial.bit_length() - 1
    kind = _CORE_CRCS.get(polynomial) if eds.cstart == protocol.CRC_INIT else None
    if kind is not None and kind in params.word_crcs[0]:
        return {("w0", "crc"): kind}        # the custom settings are not read with it
    if not params.custom_crc:
        raise UnsupportedEncoderError(
            f"{_where('CPOLY')} = 0x{eds.cpoly:X}, {_where('CSTART')} = 0x{eds.cstart:X} "
            f"(polynomial 0x{polynomial:X}): this build has no custom CRCs and checks word 0 "
            f"with {[k.name for k in params.word_crcs[0]]} only")
    if not 1 <= width <= CRC_MAX_WIDTH:
        raise UnsupportedEncoderError(
            f"{_where('CPOLY')} = 0x{eds.cpoly:X} (polynomial 0x{polynomial:X}): a CRC of "
            f"{width} bits; the core checks CRCs of 1..{CRC_MAX_WIDTH} bits")
    if eds.cstart >> width:
        raise UnsupportedEncoderError(f"{_where('CSTART')} = 0x{eds.cstart:X}: wider than the "
                                      f"{width}-bit CRC")
    return {("w0", "crc"): Crc.CUSTOM, ("w0_crc", "width"): width,
            ("w0_crc", "poly"): polynomial & ((1 << width) - 1),
            ("w0_crc", "start"): eds.cstart, ("w0_crc", "inverted"): 1}


def _port_values(settings, params):
    """The one place settings become port names: ``{path: value}`` -> ``{cfg_* port: int}``."""
    ports = {path: name for name, path, _ in config_ports(params)}
    word0 = {path for path in ports if path[0] == "w0"}
    assert word0 <= settings.keys(), f"word 0 settings not derived: {word0 - settings.keys()}"
    return {ports[path]: int(value) for path, value in settings.items()}


def derive_config(eds, *, params=None):
    """The core's data-channel settings for a BP3 encoder.

    A BP3 Standard Encoder (C = 0) sends one word: DL_POS = DL - 2 position bits, nE, nW, and
    the CRC that CPOLY and CSTART name (CRC-6 0x43 from 0: the named CRC-6; any other: a
    custom CRC, ``cfg_w0_crc`` = 3 and the ``cfg_w0_crc_*`` settings). Word 0 is set to read it; a two-word build gets word 1
    and the SPW check switched off. Settings the EDS does not determine (MA clock, time limits,
    ``cfg_end_check``) are not returned.

    Parameters
    ----------
    eds : Bp3Eds
        A decoded EDS (its BP_ID and DL give C and DL).
    params : MasterParams, optional
        The build the settings are for; default :class:`MasterParams()`.

    Returns
    -------
    dict of str to int
        ``{port name: value}``, e.g. ``{"cfg_w0_data_bits": 26, "cfg_w0_nenw": 1,
        "cfg_w0_lc": 0, "cfg_w0_crc": 1, "cfg_w1_enable": 0, "cfg_spw_check": 0}``.

    Raises
    ------
    UnsupportedEncoderError
        C = 1 (a BiSS Safety encoder: the EDS does not describe its words; configure them from
        its datasheet), feedback bits other than nE then nW, DL_POS of 0 or longer than the
        build's word 0, no CRC, a CRC wider than 16 bits or a start value wider than it, or
        (in a build without custom CRCs) a CRC other than the build's named ones.
    """
    params = MasterParams() if params is None else params
    if not isinstance(eds, Bp3Eds):
        raise TypeError(f"eds must be a Bp3Eds, not {eds!r}")
    if not isinstance(params, MasterParams):
        raise TypeError(f"params must be a MasterParams, not {params!r}")
    profile = eds.profile_id
    if profile.crc_mode is not CrcMode.SEPARATE:
        raise UnsupportedEncoderError(
            f"{_where('BP_ID')} = 0x{eds.bp_id:02X}: C = 1, a BiSS Safety encoder; the BP3 EDS "
            f"does not give its word layout, so no settings are derived (set the safety words "
            f"from the encoder's datasheet)")
    if (eds.fb1, eds.fb2) != (Feedback.ERROR, Feedback.WARNING):
        raise UnsupportedEncoderError(
            f"{_where('FB1')} / {_where('FB2')} = {eds.fb1.name} / {eds.fb2.name}: the core reads "
            f"the two feedback bits as nE then nW")
    bits, most = profile.position_bits, params.max_data_bits[0]
    if not 1 <= bits <= most:
        raise UnsupportedEncoderError(f"{_where('DL')} = 0x{eds.dl:02X}: DL_POS = {bits} position "
                                      f"bits; this build reads 1..{most} in word 0")
    settings = {
        ("w0", "data_bits"): bits,
        ("w0", "nenw"): 1,
        ("w0", "lc"): 0,
        ("w0", "gray"): 0,                  # BP3 positions are binary
        **_data_crc(eds, params),
    }
    if params.signed_words:
        settings[("w0", "signed")] = 0      # ... and unsigned
    if params.words >= 2:
        settings[("spw_check",)] = 0
    for w in range(1, params.words):        # one slave: no word after word 0
        settings[(f"w{w}_enable",)] = 0
    return _port_values(settings, params)


# -- Identification sequence -------------------------------------------------------------------

@dataclass(frozen=True)
class Identification:
    """What :func:`identify` found.

    Attributes
    ----------
    profile : ProfileId
        Registers 0x42/0x43.
    eds_bank : int
        Register 0x41: the bank where the EDS starts.
    profile_bank : int
        The bank read as the BP3 profile part (``eds_bank + profile_bank_offset``).
    eds : Bp3Eds
    config : dict of str to int
        :func:`derive_config` of ``eds``.
    """
    profile: ProfileId
    eds_bank: int
    profile_bank: int
    eds: Bp3Eds
    config: dict


def identify(read_registers, write_register, *, slave_id=0, profile_bank_offset=1, params=None):
    """Identify a BP3 encoder, read its EDS and derive the core's data-channel settings.

    The accesses, in order: one sequential read of registers 0x40..0x43 (bank select, EDS
    pointer, profile ID); if the BP3 bank is not selected already, a write of 0x40 and a read
    back of it; a sequential read of 0x00..0x3F; and a write restoring 0x40. The restore is made
    whenever the bank select was written, also when a later access or check fails.

    Parameters
    ----------
    read_registers : callable
        ``read_registers(slave_id, address, count) -> bytes``: ``count`` consecutive registers
        from ``address`` (a sequential access). Its own errors propagate unchanged.
    write_register : callable
        ``write_register(slave_id, address, data)``: write the bytes ``data`` from ``address``.
    slave_id : int
        0..7, the encoder's position in the chain.
    profile_bank_offset : int
        Banks from the EDS start (register 0x41) to the BP3 profile bank; 1 assumes a common EDS
        part of one bank (see the module's docstring), 0 that the pointer names the BP3 bank.
    params : MasterParams, optional
        The build to derive settings for (:func:`derive_config`).

    Returns
    -------
    Identification

    Raises
    ------
    NoEdsError
        Register 0x41 is 0x00 or 0xFF.
    RegisterAccessError
        A read returned a wrong number of bytes, or the bank select reads back another bank.
    Bp3Error
        Any error of :func:`decode_profile_id`, :func:`decode_eds` and :func:`derive_config`.
    """
    if not isinstance(slave_id, int) or not 0 <= slave_id < 2**protocol.CONTROL_ID_BITS:
        raise ValueError(f"slave_id must be an integer from 0 to "
                         f"{2**protocol.CONTROL_ID_BITS - 1}, not {slave_id!r}")
    if not isinstance(profile_bank_offset, int) or profile_bank_offset < 0:
        raise ValueError(f"profile_bank_offset must be a non-negative integer, "
                         f"not {profile_bank_offset!r}")

    def read(address, count):
        data = read_registers(slave_id, address, count)
        try:
            data = bytes(data)
        except (TypeError, ValueError):
            raise RegisterAccessError(f"reading {count} register(s) from 0x{address:02X} "
                                      f"returned {data!r}, not bytes") from None
        if len(data) != count:
            raise RegisterAccessError(f"reading {count} register(s) from 0x{address:02X} "
                                      f"returned {len(data)} byte(s)")
        return data

    def select(bank):
        write_register(slave_id, protocol.REG_BANK_SELECT, bytes([bank]))

    # 0x40 bank select, 0x41 EDS pointer, 0x42/0x43 profile ID: one sequential access.
    previous, pointer, reg_id, reg_dl = read(protocol.REG_BANK_SELECT, 4)
    profile = decode_profile_id(reg_id, reg_dl)
    if pointer in protocol.EDS_BANK_NONE:
        raise NoEdsError(f"register 0x{protocol.REG_EDS_BANK:02X} = 0x{pointer:02X}: the encoder "
                         f"has no EDS")
    bank = pointer + profile_bank_offset
    if bank > 0xFF:
        raise FieldRangeError(f"register 0x{protocol.REG_EDS_BANK:02X} = 0x{pointer:02X} with "
                              f"profile_bank_offset {profile_bank_offset} names bank {bank}, "
                              f"beyond the last bank 0xFF")

    if bank == previous:
        raw = read(0x00, protocol.BANK_BYTES)
    else:
        select(bank)
        try:
            selected = read(protocol.REG_BANK_SELECT, 1)[0]
            if selected != bank:
                raise RegisterAccessError(
                    f"register 0x{protocol.REG_BANK_SELECT:02X} reads 0x{selected:02X} after "
                    f"selecting bank 0x{bank:02X}")
            raw = read(0x00, protocol.BANK_BYTES)
        finally:
            select(previous)

    eds = decode_eds(raw, profile=profile)
    return Identification(profile, pointer, bank, eds, derive_config(eds, params=params))
