"""CRC-4 of BiSS control communication against references it shares no code with.

Three kinds of reference: a published CRC-4 lookup table with the published table-driven
formulas that use it (Lenz Encoders' BiSS C master library), values worked by hand with
polynomial long division, and a second bit-by-bit implementation written here (long division on
integers, not a shift register).
"""

import random

import pytest

import protocol_facts as facts
from bissmaster.control_crc import CRC4, crc4, crc4_address, crc4_data

# Published CRC-4 lookup table for x^4 + x + 1, start 0, *not* inverted: entry n is the CRC
# register after feeding the 4-bit value n. Copied from Lenz Encoders' BiSS C master library,
# github.com/lenzencoders/BISS-C, BiSS_C_Master/lib/BiSS_C_Master/biss_c_master.c
# (commit 7bbf407864f1c6dfac3d2937395aed9ce6cd34de), ``tableCRC4``.
TABLE_CRC4 = [0x0, 0x3, 0x6, 0x5, 0xC, 0xF, 0xA, 0x9, 0xB, 0x8, 0xD, 0xE, 0x7, 0x4, 0x1, 0x2]


def lenz_crc4_cts_adr(address):
    """The same file's ``CRC4_CTS_ADR``: CTS = 1, ID = 0 and ADR, as sent (``0xF -`` inverts).

    Its constant 0xC is ``tableCRC4[0b0100]``: the first nibble of 0 CTS ID2 ID1 with CTS = 1.
    """
    return 0xF - TABLE_CRC4[(address & 0xF) ^ TABLE_CRC4[((address >> 4) & 0xF) ^ 0xC]]


def lenz_crc4_data(data):
    """The same file's ``CRC4_DATA``, as sent."""
    return 0xF - TABLE_CRC4[(data & 0xF) ^ TABLE_CRC4[(data >> 4) & 0xF]]


def long_division_crc4(value, n_bits):
    """Remainder of value * x^4 divided by x^4 + x + 1 (0b10011), inverted: written from the
    definition, independently of the module (which uses amaranth's shift-register model)."""
    remainder = value << 4
    for shift in range(n_bits - 1, -1, -1):
        if remainder & (1 << (shift + 4)):
            remainder ^= 0b10011 << shift
    return remainder ^ 0xF


def _bits(value, n):
    return [(value >> (n - 1 - i)) & 1 for i in range(n)]


def test_protocol_constants_are_the_spec_values():
    assert (facts.CRC4_WIDTH, facts.CRC4_POLY, facts.CRC4_XOR_OUT) == (4, 0x03, 0x0F)
    assert facts.CRC_INIT == 0
    assert (CRC4.crc_width, CRC4.polynomial, CRC4.initial_crc, CRC4.xor_output) == (4, 3, 0, 15)
    assert not CRC4.reflect_input and not CRC4.reflect_output


def test_crc4_matches_published_table():
    for n, expected in enumerate(TABLE_CRC4):
        assert crc4(_bits(n, 4)) == expected ^ 0xF, n
        assert crc4_data(n) == expected ^ 0xF, n       # leading zero nibble: same CRC


def test_crc4_address_matches_published_formula_for_every_address():
    for address in range(0x80):
        assert crc4_address(0, address) == lenz_crc4_cts_adr(address), hex(address)


def test_crc4_data_matches_published_formula_for_every_byte():
    for byte in range(0x100):
        assert crc4_data(byte) == lenz_crc4_data(byte), hex(byte)


# Worked by hand, x^k reduced with x^4 = x + 1 (x has order 15 modulo x^4 + x + 1):
#   ADR 0x00, ID 0: message x^10, CRC x^14 = x^3 + 1 = 0b1001, sent 0b0110.
#   ADR 0x42, ID 0: x^10 + x^6 + x, CRC x^14 + x^10 + x^5 = x^3 = 0b1000, sent 0b0111.
#   ADR 0x7F, ID 7: all 11 bits set, CRC x^4 + ... + x^14 = x^3 + x^2 + x + 1 (the sum of all
#   15 powers is 0), sent 0b0000.
#   DATA 0x62: x^6 + x^5 + x, CRC x^10 + x^9 + x^5 = x^3 + x + 1 = 0b1011, sent 0b0100.
#   DATA 0x00: CRC 0, sent 0b1111.
HAND_WORKED = [
    (crc4_address, (0, 0x00), 0x6),
    (crc4_address, (0, 0x42), 0x7),
    (crc4_address, (7, 0x7F), 0x0),
    (crc4_data, (0x62,), 0x4),
    (crc4_data, (0x00,), 0xF),
]


@pytest.mark.parametrize("func, args, expected", HAND_WORKED)
def test_hand_worked_values(func, args, expected):
    assert func(*args) == expected


def test_crc4_address_matches_long_division_for_every_id_and_address():
    for slave_id in range(8):
        for address in range(0x80):
            field = (1 << 10) | (slave_id << 7) | address         # CTS, ID[2:0], ADR[6:0]
            assert crc4_address(slave_id, address) == long_division_crc4(field, 11)


def test_crc4_matches_long_division_on_random_messages():
    rng = random.Random(4)
    for _ in range(500):
        n = rng.randint(1, 40)
        value = rng.getrandbits(n)
        assert crc4(_bits(value, n)) == long_division_crc4(value, n)


def test_sent_crc_leaves_constant_residue():
    # What a receiver checks: data followed by its sent CRC always ends at the same register.
    residue = CRC4(data_width=1).residue()
    for byte in range(0x100):
        codeword = _bits(byte, 8) + _bits(crc4_data(byte), 4)
        assert long_division_crc4(int("".join(map(str, codeword)), 2), 12) ^ 0xF == residue


@pytest.mark.parametrize("call", [
    lambda: crc4_address(8, 0), lambda: crc4_address(-1, 0), lambda: crc4_address(0, 0x80),
    lambda: crc4_address(0, 1.0), lambda: crc4_data(0x100), lambda: crc4_data(-1),
    lambda: crc4([0, 1, 2]),
])
def test_out_of_range_inputs_rejected(call):
    with pytest.raises(ValueError):
        call()
