"""bissmaster.bp3: profile ID registers, the EDS bank, the derived settings, identify().

Expected values are written here from docs/protocol.md (sections 7 and 10), the README's
port table and the committed port lists, not taken from the module: EDS banks are packed with
:mod:`struct` at the table's addresses, and the encoder is a dict-backed fake register file.
"""

import struct
from dataclasses import fields
from pathlib import Path

import pytest

from bissmaster import bp3
from bissmaster.params import Crc, MasterParams
from master_contract import CRC_CODE

from testkit import DATA

# -- The EDS bank, from the table of docs/protocol.md ------------------------------------------------------

#: Digest section 7: symbol (DL for the unnamed byte 0x03), address, struct code (big endian).
SPEC_EDS = [
    ("BP_VER", 0x00, "B"), ("BP_LEN", 0x01, "B"), ("BP_ID", 0x02, "B"), ("DL", 0x03, "B"),
    ("FB1", 0x04, "B"), ("FB2", 0x05, "B"), ("PON_PDL", 0x06, "B"), ("EN_TYP", 0x08, "B"),
    ("POS_NUM", 0x09, "B"), ("MT_LEN", 0x0A, "B"), ("MT_FMT", 0x0B, "B"), ("CO_LEN", 0x0C, "B"),
    ("CO_FMT", 0x0D, "B"), ("FI_LEN", 0x0E, "B"), ("FI_FMT", 0x0F, "B"),
    ("MT_CNT", 0x10, "I"), ("SIP_CNT", 0x14, "I"), ("SIP_RES", 0x18, "I"), ("CPOLY", 0x1C, "I"),
    ("CSTART", 0x20, "I"), ("ABS_ACU", 0x24, "H"), ("REL_ACU", 0x26, "H"), ("SPD_ACU", 0x28, "H"),
    ("HYST", 0x2A, "H"), ("SPD_MAX", 0x2C, "H"), ("ACC_MAX", 0x2E, "H"), ("TMP_MIN", 0x30, "H"),
    ("TMP_MAX", 0x32, "H"), ("VLT_MIN", 0x34, "H"), ("VLT_MAX", 0x36, "H"), ("CUR_MAX", 0x38, "H"),
    ("CHKSUM", 0x3F, "B"),
]

#: A BP3 encoder with C = 0 and DL 28 (26 position bits). Every field a different value, and
#: the multi-byte ones with different bytes, so a field read at the wrong address or in the
#: wrong byte order cannot match.
EXAMPLE = {
    "BP_VER": 1, "BP_LEN": 1, "BP_ID": 0x62, "DL": 28, "FB1": 1, "FB2": 2, "PON_PDL": 150,
    "EN_TYP": 1, "POS_NUM": 2, "MT_LEN": 12, "MT_FMT": 1, "CO_LEN": 9, "CO_FMT": 7,
    "FI_LEN": 5, "FI_FMT": 3, "MT_CNT": 0x11223344, "SIP_CNT": 0x55667788,
    "SIP_RES": 0x99AABBCC, "CPOLY": 0x21, "CSTART": 0, "ABS_ACU": 0x0102, "REL_ACU": 0x0304,
    "SPD_ACU": 0x0506, "HYST": 0x0708, "SPD_MAX": 0x090A, "ACC_MAX": 0x0B0C, "TMP_MIN": 233,
    "TMP_MAX": 358, "VLT_MIN": 4750, "VLT_MAX": 5250, "CUR_MAX": 200,
}
#: Bytes that are no field: they count in the checksum and nowhere else.
RESERVED = {0x07: 0x5A, 0x3A: 0xA1, 0x3B: 0xB2, 0x3C: 0xC3, 0x3D: 0xD4, 0x3E: 0xE5}


def build_bank(checksum=None, **overrides):
    """64 bytes of a BP3 EDS bank; the checksum is made right unless given."""
    values = {**EXAMPLE, **overrides}
    bank = bytearray(64)
    for symbol, address, code in SPEC_EDS:
        if symbol != "CHKSUM":
            struct.pack_into(">" + code, bank, address, values[symbol])
    for address, value in RESERVED.items():
        bank[address] = value
    bank[0x3F] = sum(bank[:0x3F]) % 256 if checksum is None else checksum
    return bytes(bank)


def test_layout_is_the_spec_table():
    assert list(bp3.EDS_LAYOUT) == SPEC_EDS


def test_every_eds_field_decoded():
    bank = build_bank()
    eds = bp3.decode_eds(bank)
    assert {f.name for f in fields(eds)} == {s.lower() for s, _, _ in SPEC_EDS} | {"raw"}
    for symbol, value in EXAMPLE.items():
        assert getattr(eds, symbol.lower()) == value, symbol
    assert eds.chksum == bank[0x3F] == sum(bank[:0x3F]) % 256
    assert eds.raw == bank
    assert eds.fb1 is bp3.Feedback.ERROR and eds.fb2 is bp3.Feedback.WARNING
    assert eds.en_typ is bp3.EncoderType.LINEAR
    assert eds.mt_fmt is bp3.Alignment.LEFT
    assert eds.crc_polynomial == 0x43
    assert eds.profile_id == bp3.ProfileId(1, bp3.CrcMode.SEPARATE, 28)


def test_multibyte_fields_are_big_endian():
    bank = build_bank()
    assert bank[0x10:0x14] == b"\x11\x22\x33\x44" and bank[0x1C:0x20] == b"\x00\x00\x00\x21"
    assert bank[0x30:0x32] == b"\x00\xe9"
    eds = bp3.decode_eds(bank)
    assert (eds.mt_cnt, eds.cpoly, eds.tmp_min) == (0x11223344, 0x21, 233)


def test_rotary_right_aligned_encoder():
    eds = bp3.decode_eds(build_bank(EN_TYP=0, MT_FMT=0, POS_NUM=0, PON_PDL=1))
    assert eds.en_typ is bp3.EncoderType.ROTARY and eds.mt_fmt is bp3.Alignment.RIGHT
    assert (eds.pos_num, eds.pon_pdl) == (0, 1)


@pytest.mark.parametrize("bank", [
    build_bank(checksum=(sum(build_bank()[:0x3F]) + 1) % 256),
    build_bank()[:0x20] + bytes([build_bank()[0x20] ^ 0x01]) + build_bank()[0x21:],
], ids=["checksum byte", "data byte"])
def test_checksum_mismatch(bank):
    with pytest.raises(bp3.ChecksumError, match=r"0x3F \(CHKSUM\)"):
        bp3.decode_eds(bank)


def test_bank_must_be_64_bytes():
    with pytest.raises(ValueError):
        bp3.decode_eds(build_bank()[:63])


# -- Registers 0x42 / 0x43 ----------------------------------------------------------------------

def test_profile_id_registers_decoded():
    assert bp3.decode_profile_id(0x62, 0x1C) == bp3.ProfileId(1, bp3.CrcMode.SEPARATE, 28)
    assert bp3.decode_profile_id(0x62, 0x1C).position_bits == 26
    safety = bp3.decode_profile_id(0x63, 0x3F)
    assert safety == bp3.ProfileId(1, bp3.CrcMode.SAFETY, 0x3F)
    assert safety.position_bits is None
    assert safety.to_bytes() == b"\x63\x3f"


@pytest.mark.parametrize("reg_42", [0x52, 0x72, 0x00, 0xE2])
def test_wrong_profile_id_register(reg_42):
    with pytest.raises(bp3.NotBp3Error, match="register 0x42"):
        bp3.decode_profile_id(reg_42, 0x1C)


@pytest.mark.parametrize("reg_42", [0x60, 0x64, 0x6E])      # VER 0, 2, 7
def test_profile_version_must_be_1(reg_42):
    with pytest.raises(bp3.FieldRangeError, match="VER"):
        bp3.decode_profile_id(reg_42, 0x1C)


DL_LIMITS = [   # (register 0x42, register 0x43, accepted)
    (0x62, 0x01, False), (0x62, 0x02, True), (0x62, 0x39, True), (0x62, 0x3A, False),
    (0x62, 0x3F, False), (0x62, 0x82, False),
    (0x63, 0x01, False), (0x63, 0x02, True), (0x63, 0x3A, True), (0x63, 0x3F, True),
    (0x63, 0x40, False), (0x63, 0xBF, False),
]


@pytest.mark.parametrize("reg_42, reg_43, accepted", DL_LIMITS)
def test_dl_range_per_c(reg_42, reg_43, accepted):
    if accepted:
        assert bp3.decode_profile_id(reg_42, reg_43).data_length == reg_43
    else:
        with pytest.raises(bp3.FieldRangeError, match="register 0x43"):
            bp3.decode_profile_id(reg_42, reg_43)


@pytest.mark.parametrize("reg_42, reg_43, accepted", DL_LIMITS)
def test_eds_dl_range_per_c(reg_42, reg_43, accepted):
    bank = build_bank(BP_ID=reg_42, DL=reg_43)
    if accepted:
        assert bp3.decode_eds(bank).dl == reg_43
    else:
        with pytest.raises(bp3.FieldRangeError, match=r"0x03 \(DL\)"):
            bp3.decode_eds(bank)


def test_wrong_profile_id_in_eds():
    with pytest.raises(bp3.NotBp3Error, match=r"0x02 \(BP_ID\)"):
        bp3.decode_eds(build_bank(BP_ID=0x72))


@pytest.mark.parametrize("symbol, value, address", [
    ("BP_VER", 0, 0x00), ("BP_VER", 2, 0x00), ("BP_LEN", 2, 0x01), ("BP_ID", 0x64, 0x02),
    ("FB1", 0, 0x04), ("FB1", 3, 0x04), ("FB2", 0, 0x05), ("PON_PDL", 0, 0x06),
    ("PON_PDL", 255, 0x06), ("EN_TYP", 2, 0x08), ("POS_NUM", 3, 0x09), ("MT_FMT", 2, 0x0B),
])
def test_eds_field_out_of_range(symbol, value, address):
    with pytest.raises(bp3.FieldRangeError, match=rf"0x{address:02X} \({symbol}\)"):
        bp3.decode_eds(build_bank(**{symbol: value}))


@pytest.mark.parametrize("registers, symbol", [
    ((0x63, 28), "BP_ID"),      # the encoder says C = 1, its EDS C = 0
    ((0x62, 30), "DL"),
])
def test_eds_inconsistent_with_registers(registers, symbol):
    profile = bp3.decode_profile_id(*registers)
    with pytest.raises(bp3.InconsistentFieldsError, match=rf"\({symbol}\).*register 0x4"):
        bp3.decode_eds(build_bank(), profile=profile)
    assert bp3.decode_eds(build_bank(), profile=bp3.decode_profile_id(0x62, 28)).dl == 28


# -- derive_config --------------------------------------------------------------------------------

def _eds(**overrides):
    return bp3.decode_eds(build_bank(**overrides))


@pytest.mark.parametrize("position_bits", [1, 13, 26, 36, 55])
def test_derive_config_default_build(position_bits):
    config = bp3.derive_config(_eds(DL=position_bits + 2))
    # README port table: cfg_wN_data_bits, cfg_wN_nenw, cfg_wN_lc, cfg_wN_crc (1 = CRC-6).
    assert config == {
        "cfg_w0_data_bits": position_bits, "cfg_w0_nenw": 1, "cfg_w0_lc": 0,
        "cfg_w0_crc": CRC_CODE["crc6"], "cfg_w0_gray": 0, "cfg_w0_signed": 0, "cfg_w1_enable": 0,
        "cfg_spw_check": 0,
    }
    assert all(type(v) is int for v in config.values())


def _ports(preset):
    return {line.split()[-1] for line in (DATA / f"ports_{preset}.txt").read_text().splitlines()}


@pytest.mark.parametrize("preset, params", [
    ("default", MasterParams()),
    # the biss-c preset: one CRC-6 word, no custom CRCs, no signed words
    ("biss-c", MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),), custom_crc=False,
                            signed_words=False)),
])
def test_derived_names_are_ports_of_the_build(preset, params):
    config = bp3.derive_config(_eds(DL=38), params=params)
    assert set(config) <= _ports(preset)
    assert {"cfg_w0_data_bits", "cfg_w0_nenw", "cfg_w0_lc", "cfg_w0_crc"} <= set(config)


def test_derive_config_chain_build_reads_one_slave():
    """A BP3 encoder alone on a chain build (three words): word 0 as the EDS says, every word
    after it out of the frame, no SPW check (docs/ports.md, Chains)."""
    params = MasterParams(max_data_bits=(40, 32, 24), word_crcs=((Crc.CRC6,),) * 3)
    config = bp3.derive_config(_eds(DL=38), params=params)
    assert set(config) <= _ports("chain")
    assert (config["cfg_w0_data_bits"], config["cfg_w1_enable"], config["cfg_w2_enable"],
            config["cfg_spw_check"]) == (36, 0, 0, 0)


def test_derive_config_one_word_build():
    params = MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),))
    assert bp3.derive_config(_eds(DL=38), params=params) == {
        "cfg_w0_data_bits": 36, "cfg_w0_nenw": 1, "cfg_w0_lc": 0, "cfg_w0_crc": CRC_CODE["crc6"],
        "cfg_w0_gray": 0, "cfg_w0_signed": 0}
    with pytest.raises(bp3.UnsupportedEncoderError, match="1..36"):
        bp3.derive_config(_eds(DL=39), params=params)


def test_derive_config_crc16_polynomial_maps_to_crc16():
    # 0x190D9 stored without x^0: 0xC86C. Not what BP3 prescribes, but what the core can check.
    assert bp3.derive_config(_eds(CPOLY=0xC86C))["cfg_w0_crc"] == CRC_CODE["crc16"]


#: CRCs a BP3 EDS may name besides CRC-6 0x43 from 0, with the settings of a custom CRC worked
#: out by hand from the EDS rule (CPOLY = the polynomial without x^0, shifted down one bit;
#: docs/protocol.md section 7): (CPOLY, CSTART) -> (width, register polynomial, start).
CUSTOM_FROM_EDS = [
    ((0x8810, 0xFFFF), (16, 0x1021, 0xFFFF)),   # x^16 + x^12 + x^5 + 1 (0x11021), start 0xFFFF
    ((0x97, 0x00), (8, 0x2F, 0x00)),            # iC-MB4's 8-bit 0x12F
    ((0x22, 0x00), (6, 0x05, 0x00)),            # 0x45: another 6-bit polynomial
    ((0x21, 0x01), (6, 0x03, 0x01)),            # CRC-6 0x43 but starting at 1
    ((0x5, 0x3), (3, 0x3, 0x3)),                # iC-MB4's 3-bit 0xB, start 3
]


@pytest.mark.parametrize("cpoly_cstart, settings", CUSTOM_FROM_EDS)
def test_derive_config_other_crcs_become_custom(cpoly_cstart, settings):
    cpoly, cstart = cpoly_cstart
    width, poly, start = settings
    config = bp3.derive_config(_eds(CPOLY=cpoly, CSTART=cstart))
    assert config["cfg_w0_crc"] == CRC_CODE["custom"]
    assert (config["cfg_w0_crc_width"], config["cfg_w0_crc_poly"], config["cfg_w0_crc_start"],
            config["cfg_w0_crc_inverted"]) == (width, poly, start, 1)


@pytest.mark.parametrize("overrides, params, match", [
    ({"BP_ID": 0x63, "DL": 0x30}, None, "C = 1"),             # BiSS Safety encoder: refused
    ({"DL": 2}, None, "DL_POS = 0"),
    ({"FB1": 2, "FB2": 1}, None, "nE then nW"),
    ({"FB2": 1}, None, "nE then nW"),
    ({"CPOLY": 0}, None, "no CRC"),
    ({"CPOLY": 0x10000}, None, "17 bits"),                  # x^17 + x^0: wider than 16 bits
    ({"CSTART": 0x40}, None, "CSTART"),                     # 7 bits for a 6-bit CRC
    ({"CPOLY": 0x22}, MasterParams(custom_crc=False), "no custom CRCs"),
    ({}, MasterParams(word_crcs=((Crc.CRC16,), (Crc.CRC16,)), custom_crc=False), "CRC16"),
])
def test_derive_config_refuses(overrides, params, match):
    with pytest.raises(bp3.UnsupportedEncoderError, match=match):
        bp3.derive_config(_eds(**overrides), params=params)


# -- identify() against a fake register file ------------------------------------------------------

class FakeEncoder:
    """Registers of a BP3 encoder as docs/protocol.md describes them (section 10): 0x00..0x3F show the
    bank that 0x40 selects, 0x41 points to the EDS, 0x42/0x43 hold the profile ID. Every access
    is logged; a sequential access covers consecutive addresses."""

    def __init__(self, banks, *, pointer, profile=(0x62, 28), bank_select=0, slave_id=0,
                 bank_select_writable=True):
        self.banks = {n: bytes(b) for n, b in banks.items()}
        self.regs = {0x40: bank_select, 0x41: pointer, 0x42: profile[0], 0x43: profile[1]}
        self.slave_id = slave_id
        self.bank_select_writable = bank_select_writable
        self.log = []

    def read_registers(self, slave_id, address, count):
        assert slave_id == self.slave_id and 0 <= address and address + count <= 0x80
        self.log.append(("read", address, count))
        bank = self.banks.get(self.regs[0x40], bytes(64))
        return bytes(bank[a] if a < 0x40 else self.regs.get(a, 0)
                     for a in range(address, address + count))

    def write_register(self, slave_id, address, data):
        assert slave_id == self.slave_id
        self.log.append(("write", address, bytes(data)))
        assert address == 0x40 and len(data) == 1, "identify writes only the bank select"
        if self.bank_select_writable:
            self.regs[0x40] = data[0]


COMMON_PART = bytes(range(0x80, 0xC0))      # whatever the common EDS part holds

EXPECTED_CONFIG = {"cfg_w0_data_bits": 26, "cfg_w0_nenw": 1, "cfg_w0_lc": 0,
                   "cfg_w0_crc": CRC_CODE["crc6"], "cfg_w0_gray": 0, "cfg_w0_signed": 0,
                   "cfg_w1_enable": 0,
                   "cfg_spw_check": 0}


def test_identify_default_offset_reads_the_bank_after_the_pointer():
    enc = FakeEncoder({2: COMMON_PART, 3: build_bank()}, pointer=2)
    found = bp3.identify(enc.read_registers, enc.write_register)
    assert (found.eds_bank, found.profile_bank) == (2, 3)
    assert found.profile == bp3.ProfileId(1, bp3.CrcMode.SEPARATE, 28)
    assert found.eds.raw == build_bank() and found.eds.sip_res == 0x99AABBCC
    assert found.config == EXPECTED_CONFIG
    assert enc.log == [("read", 0x40, 4), ("write", 0x40, b"\x03"), ("read", 0x40, 1),
                       ("read", 0x00, 64), ("write", 0x40, b"\x00")]
    assert enc.regs[0x40] == 0


def test_identify_offset_0_reads_the_pointer_bank():
    enc = FakeEncoder({2: build_bank(), 3: COMMON_PART}, pointer=2, bank_select=5)
    found = bp3.identify(enc.read_registers, enc.write_register, profile_bank_offset=0)
    assert (found.eds_bank, found.profile_bank, found.config) == (2, 2, EXPECTED_CONFIG)
    assert enc.log[1] == ("write", 0x40, b"\x02") and enc.log[-1] == ("write", 0x40, b"\x05")
    assert enc.regs[0x40] == 5


@pytest.mark.parametrize("banks, offset", [
    ({2: build_bank(), 3: COMMON_PART}, 1),
    ({2: build_bank(), 3: bytes(64)}, 1),           # an all-zero bank passes the checksum
    ({2: build_bank(), 3: b"\xff" * 64}, 1),
    ({2: COMMON_PART, 3: build_bank()}, 0),
])
def test_identify_wrong_offset_fails_loudly(banks, offset):
    enc = FakeEncoder(banks, pointer=2)
    with pytest.raises(bp3.Bp3Error):
        bp3.identify(enc.read_registers, enc.write_register, profile_bank_offset=offset)
    assert enc.regs[0x40] == 0


@pytest.mark.parametrize("pointer", [0x00, 0xFF])
def test_identify_no_eds(pointer):
    enc = FakeEncoder({}, pointer=pointer)
    with pytest.raises(bp3.NoEdsError, match=f"0x{pointer:02X}"):
        bp3.identify(enc.read_registers, enc.write_register)
    assert enc.log == [("read", 0x40, 4)]


def test_identify_not_bp3_reads_nothing_else():
    enc = FakeEncoder({3: build_bank()}, pointer=2, profile=(0x00, 0x00))
    with pytest.raises(bp3.NotBp3Error):
        bp3.identify(enc.read_registers, enc.write_register)
    assert enc.log == [("read", 0x40, 4)]


def test_identify_bank_already_selected_writes_nothing():
    enc = FakeEncoder({3: build_bank()}, pointer=2, bank_select=3)
    assert bp3.identify(enc.read_registers, enc.write_register).config == EXPECTED_CONFIG
    assert enc.log == [("read", 0x40, 4), ("read", 0x00, 64)]


def test_identify_restores_bank_when_the_eds_is_bad():
    enc = FakeEncoder({3: build_bank(checksum=0)}, pointer=2, bank_select=1)
    with pytest.raises(bp3.ChecksumError):
        bp3.identify(enc.read_registers, enc.write_register)
    assert enc.log[-1] == ("write", 0x40, b"\x01") and enc.regs[0x40] == 1


def test_identify_restores_bank_when_the_transport_fails():
    enc = FakeEncoder({3: build_bank()}, pointer=2)

    def failing_read(slave_id, address, count):
        if count == 64:
            raise TimeoutError("no answer")
        return enc.read_registers(slave_id, address, count)

    with pytest.raises(TimeoutError):
        bp3.identify(failing_read, enc.write_register)
    assert enc.log[-1] == ("write", 0x40, b"\x00") and enc.regs[0x40] == 0


def test_identify_bank_select_refused():
    enc = FakeEncoder({3: build_bank()}, pointer=2, bank_select=0, bank_select_writable=False)
    with pytest.raises(bp3.RegisterAccessError, match="0x40 reads 0x00"):
        bp3.identify(enc.read_registers, enc.write_register)
    assert ("read", 0x00, 64) not in enc.log


def test_identify_short_read():
    enc = FakeEncoder({3: build_bank()}, pointer=2)
    with pytest.raises(bp3.RegisterAccessError, match="returned 3 byte"):
        bp3.identify(lambda s, a, n: enc.read_registers(s, a, n)[:3], enc.write_register)


def test_identify_eds_inconsistent_with_registers():
    enc = FakeEncoder({3: build_bank()}, pointer=2, profile=(0x62, 30))
    with pytest.raises(bp3.InconsistentFieldsError):
        bp3.identify(enc.read_registers, enc.write_register)
    assert enc.regs[0x40] == 0


def test_identify_safety_encoder_refused():
    enc = FakeEncoder({3: build_bank(BP_ID=0x63, DL=0x30)}, pointer=2, profile=(0x63, 0x30))
    with pytest.raises(bp3.UnsupportedEncoderError, match="C = 1"):
        bp3.identify(enc.read_registers, enc.write_register)
    assert enc.regs[0x40] == 0


def test_identify_slave_id_and_params_passed_through():
    enc = FakeEncoder({7: build_bank(DL=38)}, pointer=6, profile=(0x62, 38), slave_id=5)
    params = MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),))
    found = bp3.identify(enc.read_registers, enc.write_register, slave_id=5, params=params)
    assert found.config == {"cfg_w0_data_bits": 36, "cfg_w0_nenw": 1, "cfg_w0_lc": 0,
                            "cfg_w0_crc": CRC_CODE["crc6"], "cfg_w0_gray": 0, "cfg_w0_signed": 0}


def test_identify_bank_beyond_0xff():
    enc = FakeEncoder({}, pointer=0xFE)
    with pytest.raises(bp3.FieldRangeError, match="bank 256"):
        bp3.identify(enc.read_registers, enc.write_register, profile_bank_offset=2)
    assert enc.log == [("read", 0x40, 4)]


@pytest.mark.parametrize("kwargs", [{"slave_id": 8}, {"slave_id": -1},
                                    {"profile_bank_offset": -1}, {"profile_bank_offset": 1.0}])
def test_identify_arguments_checked(kwargs):
    enc = FakeEncoder({3: build_bank()}, pointer=2)
    with pytest.raises(ValueError):
        bp3.identify(enc.read_registers, enc.write_register, **kwargs)
