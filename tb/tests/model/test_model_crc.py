"""The model's CRCs against references it does not share code with.

Three kinds of reference: amaranth's software CRC model (random messages), published catalogue
check values (other CRC parameter sets through the same generic routine), and a published
CRC-6 (x^6 + x + 1) lookup table.
"""

import random

import pytest
from amaranth.lib import crc as am_crc

import protocol_facts as facts
from encoder_model.crc import bits_to_int, crc6_biss, crc16_biss, crc_msb_first, int_to_bits

N_RANDOM = 500
MAX_RANDOM_BITS = 120       # longer than any BiSS word (BP3 55 + 2, SPW 36 + 2 + 6)
CHECK_MESSAGE = b"123456789"


def _bytes_msb_first(data):
    return [bit for byte in data for bit in int_to_bits(byte, 8)]


def _random_messages(seed):
    rng = random.Random(seed)
    for _ in range(N_RANDOM):
        n = rng.randint(1, MAX_RANDOM_BITS)
        yield [rng.getrandbits(1) for _ in range(n)]


def _amaranth_params(width, poly, xor_out):
    algo = am_crc.Algorithm(crc_width=width, polynomial=poly, initial_crc=0,
                            reflect_input=False, reflect_output=False, xor_output=xor_out)
    return algo(data_width=1)


BISS_CRCS = [
    pytest.param(crc6_biss, 6, 0x03, 0x3F, id="crc6"),
    pytest.param(crc16_biss, 16, 0x90D9, 0xFFFF, id="crc16"),
]


@pytest.mark.parametrize("func, width, poly, xor_out", BISS_CRCS)
def test_biss_crc_matches_amaranth_model(func, width, poly, xor_out):
    # Literal parameters from docs/protocol.md, section 6, not protocol_facts, so a wrong constant there fails.
    params = _amaranth_params(width, poly, xor_out)
    for bits in _random_messages(seed=width):
        assert func(bits) == params.compute(bits), bits


def test_protocol_constants_are_the_spec_values():
    assert (facts.CRC6_WIDTH, facts.CRC6_POLY, facts.CRC6_XOR_OUT) == (6, 0x03, 0x3F)
    assert (facts.CRC16_WIDTH, facts.CRC16_POLY, facts.CRC16_XOR_OUT) == (
        16, 0x90D9, 0xFFFF)
    assert facts.CRC_INIT == 0


@pytest.mark.parametrize("func, width, poly, xor_out", BISS_CRCS)
def test_sent_crc_leaves_constant_residue(func, width, poly, xor_out):
    # Data followed by its (inverted) CRC always leaves the same register value: the residue.
    residue = _amaranth_params(width, poly, xor_out).residue()
    seen = set()
    for bits in _random_messages(seed=width + 1):
        codeword = bits + int_to_bits(func(bits), width)
        seen.add(crc_msb_first(codeword, width=width, poly=poly))
    assert seen == {residue}
    assert residue != 0     # would mean the inversion is missing


# CRC RevEng catalogue (https://reveng.sourceforge.io/crc-catalogue/all.htm), non-reflected
# entries only (refin = refout = false): (width, poly, init, xor_out, check over b"123456789").
# The values of the widths 3..15 and CRC-8/AUTOSAR, CRC-8/I-432-1 were checked against the
# crc-catalog crate's transcription of the catalogue (github.com/akhilles/crc-catalog,
# src/algorithm.rs, commit aec125feebd526b0e42d85550dcfd3e897d5e4c5; docs.rs crc_catalog).
CATALOGUE = {
    "CRC-3/GSM": (3, 0x3, 0x0, 0x7, 0x4),
    "CRC-4/INTERLAKEN": (4, 0x3, 0xF, 0xF, 0xB),
    "CRC-5/EPC-C1G2": (5, 0x09, 0x09, 0x00, 0x00),
    "CRC-6/GSM": (6, 0x2F, 0x00, 0x3F, 0x13),
    "CRC-6/CDMA2000-A": (6, 0x27, 0x3F, 0x00, 0x0D),
    "CRC-6/CDMA2000-B": (6, 0x07, 0x3F, 0x00, 0x3B),
    "CRC-7/MMC": (7, 0x09, 0x00, 0x00, 0x75),
    "CRC-7/UMTS": (7, 0x45, 0x00, 0x00, 0x61),
    "CRC-8/SMBUS": (8, 0x07, 0x00, 0x00, 0xF4),
    "CRC-8/AUTOSAR": (8, 0x2F, 0xFF, 0xFF, 0xDF),
    "CRC-8/I-432-1": (8, 0x07, 0x00, 0x55, 0xA1),
    "CRC-10/ATM": (10, 0x233, 0x000, 0x000, 0x199),
    "CRC-10/CDMA2000": (10, 0x3D9, 0x3FF, 0x000, 0x233),
    "CRC-10/GSM": (10, 0x175, 0x000, 0x3FF, 0x12A),
    "CRC-11/FLEXRAY": (11, 0x385, 0x01A, 0x000, 0x5A3),
    "CRC-11/UMTS": (11, 0x307, 0x000, 0x000, 0x061),
    "CRC-12/CDMA2000": (12, 0xF13, 0xFFF, 0x000, 0xD4D),
    "CRC-12/DECT": (12, 0x80F, 0x000, 0x000, 0xF5B),
    "CRC-12/GSM": (12, 0xD31, 0x000, 0xFFF, 0xB34),
    "CRC-13/BBC": (13, 0x1CF5, 0x0000, 0x0000, 0x04FA),
    "CRC-14/GSM": (14, 0x202D, 0x0000, 0x3FFF, 0x30AE),
    "CRC-15/CAN": (15, 0x4599, 0x0000, 0x0000, 0x059E),
    "CRC-15/MPT1327": (15, 0x6815, 0x0000, 0x0001, 0x2566),
    "CRC-16/XMODEM": (16, 0x1021, 0x0000, 0x0000, 0x31C3),
    "CRC-16/IBM-3740": (16, 0x1021, 0xFFFF, 0x0000, 0x29B1),
    "CRC-16/GENIBUS": (16, 0x1021, 0xFFFF, 0xFFFF, 0xD64E),
    "CRC-16/CDMA2000": (16, 0xC867, 0xFFFF, 0x0000, 0x4C06),
    "CRC-32/BZIP2": (32, 0x04C11DB7, 0xFFFFFFFF, 0xFFFFFFFF, 0xFC891918),
    "CRC-32/MPEG-2": (32, 0x04C11DB7, 0xFFFFFFFF, 0x00000000, 0x0376E6E7),
}
#: The catalogue has no 9-bit CRC: that width is checked against amaranth's model instead
#: (test_every_custom_width_matches_amaranth_model).
NO_CATALOGUE_WIDTH = {9}


def test_catalogue_covers_every_custom_crc_width():
    """Every width a custom CRC may have from 3 to 16 (the master's cfg_wN_crc_width) has a
    published check value here, but the one the catalogue lacks."""
    widths = {entry[0] for entry in CATALOGUE.values()}
    assert set(range(3, 17)) - widths == NO_CATALOGUE_WIDTH


@pytest.mark.parametrize("width", range(1, 17))
def test_every_custom_width_matches_amaranth_model(width):
    """Widths 1..16 with a random polynomial, start value and output XOR each: the model's
    CRC against amaranth's software CRC (a model the test side does not share code with)."""
    rng = random.Random(1000 + width)
    for _ in range(20):
        poly, init, xor_out = (rng.getrandbits(width) | 1, rng.getrandbits(width),
                               rng.getrandbits(width))
        algo = am_crc.Algorithm(crc_width=width, polynomial=poly, initial_crc=init,
                                reflect_input=False, reflect_output=False, xor_output=xor_out)
        params = algo(data_width=1)
        for bits in list(_random_messages(seed=width))[:20]:
            assert crc_msb_first(bits, width=width, poly=poly, init=init,
                                 xor_out=xor_out) == params.compute(bits)


@pytest.mark.parametrize("name", CATALOGUE)
def test_generic_crc_catalogue_check_values(name):
    width, poly, init, xor_out, check = CATALOGUE[name]
    bits = _bytes_msb_first(CHECK_MESSAGE)
    assert crc_msb_first(bits, width=width, poly=poly, init=init, xor_out=xor_out) == check


# Published CRC-6 lookup table for x^6 + x + 1 (0x43), start 0, *not* inverted: entry i is the
# CRC register after feeding the 6-bit value i. The same table appears in iC-Haus' BiSS CRC
# sample code and in the MT6701 sensor datasheet; copied here from
# espressif/esp-iot-solution, components/motor/esp_simplefoc/port/angle_sensor/mt6701.cpp
# (commit 8f2f077e2bdee929b178b227b88c82cafe81bfc1), ``tableCRC6``.
TABLE_CRC6_0X43 = [
    0x00, 0x03, 0x06, 0x05, 0x0C, 0x0F, 0x0A, 0x09,
    0x18, 0x1B, 0x1E, 0x1D, 0x14, 0x17, 0x12, 0x11,
    0x30, 0x33, 0x36, 0x35, 0x3C, 0x3F, 0x3A, 0x39,
    0x28, 0x2B, 0x2E, 0x2D, 0x24, 0x27, 0x22, 0x21,
    0x23, 0x20, 0x25, 0x26, 0x2F, 0x2C, 0x29, 0x2A,
    0x3B, 0x38, 0x3D, 0x3E, 0x37, 0x34, 0x31, 0x32,
    0x13, 0x10, 0x15, 0x16, 0x1F, 0x1C, 0x19, 0x1A,
    0x0B, 0x08, 0x0D, 0x0E, 0x07, 0x04, 0x01, 0x02,
]
TABLE_INDEX_BITS = 6


def test_crc6_matches_published_table():
    for index, expected in enumerate(TABLE_CRC6_0X43):
        bits = int_to_bits(index, TABLE_INDEX_BITS)
        assert crc_msb_first(bits, width=6, poly=0x03) == expected, index
        assert crc6_biss(bits) == expected ^ 0x3F, index


def _table_crc6(value, n_bits):
    """The table-driven algorithm of the same source (CRC6_43_18bit), 6 bits per step."""
    assert n_bits % TABLE_INDEX_BITS == 0
    crc = 0
    for shift in range(n_bits - TABLE_INDEX_BITS, -1, -TABLE_INDEX_BITS):
        crc = TABLE_CRC6_0X43[crc ^ ((value >> shift) & 0x3F)]
    return crc


def test_crc6_matches_published_table_algorithm_on_long_words():
    rng = random.Random(6)
    for n_bits in (18, 24, 36, 42):     # 42 = 36-bit position + nE + nW + 4 leading zeros
        for _ in range(N_RANDOM // 4):
            value = rng.getrandbits(n_bits)
            bits = int_to_bits(value, n_bits)
            assert crc6_biss(bits) == _table_crc6(value, n_bits) ^ 0x3F


def test_hand_computed_crc6():
    # 101010 * x^6 mod (x^6 + x + 1) = x^5 + x^4 + x^3 + x^2 + 1 = 0x3D by long division.
    assert crc_msb_first([1, 0, 1, 0, 1, 0], width=6, poly=0x03) == 0x3D
    assert crc6_biss([1, 0, 1, 0, 1, 0]) == 0x02


def test_leading_zeros_do_not_change_crc_with_zero_start():
    # Start value 0 makes leading zeros invisible: why BP3 right-justified data is unambiguous.
    bits = [1, 1, 0, 1, 0, 0, 1]
    assert crc6_biss([0, 0, 0] + bits) == crc6_biss(bits)
    assert crc16_biss([0] * 5 + bits) == crc16_biss(bits)


def test_bit_conversions():
    assert int_to_bits(0b1011, 4) == [1, 0, 1, 1]
    assert int_to_bits(1, 6) == [0, 0, 0, 0, 0, 1]
    assert int_to_bits(0, 0) == []
    assert bits_to_int([1, 0, 1, 1]) == 0b1011
    assert bits_to_int([]) == 0
    rng = random.Random(1)
    for _ in range(100):
        n = rng.randint(1, 64)
        value = rng.getrandbits(n)
        assert bits_to_int(int_to_bits(value, n)) == value


@pytest.mark.parametrize("value, n", [(16, 4), (-1, 4), (1, 0)])
def test_int_to_bits_rejects_values_that_do_not_fit(value, n):
    with pytest.raises(ValueError):
        int_to_bits(value, n)


def test_non_binary_bits_rejected():
    with pytest.raises(ValueError):
        crc6_biss([0, 1, 2])
    with pytest.raises(ValueError):
        bits_to_int([1, True + 1])


def test_crc_parameters_validated():
    with pytest.raises(ValueError):
        crc_msb_first([1], width=0, poly=0)
    with pytest.raises(ValueError):
        crc_msb_first([1], width=6, poly=0x43)


#: The crc_detection campaign's words (sim/scenarios/campaigns.py): data bits covered by the
#: CRC, and the CRC. BiSS C 36 and the RSH CPW: 36 + nE nW under CRC-6 (44 bits sent); the RSH
#: SPW: 28 + nE nW + LC 6 under CRC-16 (52 bits).
CAMPAIGN_WORDS = [pytest.param(38, crc6_biss, 6, id="crc6-44"),
                  pytest.param(36, crc16_biss, 16, id="crc16-52")]


@pytest.mark.parametrize("data_bits, func, width", CAMPAIGN_WORDS)
def test_every_1_and_2_bit_error_and_short_burst_detected(data_bits, func, width):
    """Every 1- and 2-bit error and every burst up to the CRC's width in a word of the
    crc_detection campaign is seen by the CRC arithmetic (Hamming distance >= 3; a degree-r CRC
    catches bursts <= r). The campaign's slice draws a sample of the 2-bit errors through the
    RTL (every one in make soak); the RTL's crc_ok equals this arithmetic for every input
    (formal decoder_crc_default), so with this test the exhaustive claim holds in make test."""
    rng = random.Random(width)
    data = [rng.getrandbits(1) for _ in range(data_bits)]
    sent = data + int_to_bits(func(data), width)
    n = len(sent)

    def syndrome(flips):
        """0 when the received word passes the check (the CRC is affine: the syndrome of a
        pattern is the XOR of its bits' syndromes, checked below on random patterns)."""
        got = list(sent)
        for i in flips:
            got[i] ^= 1
        return bits_to_int(got[data_bits:]) ^ func(got[:data_bits])

    syn = [syndrome([i]) for i in range(n)]
    for _ in range(50):
        flips = rng.sample(range(n), rng.randint(2, 8))
        want = 0
        for i in flips:
            want ^= syn[i]
        assert syndrome(flips) == want
    missed = [(i,) for i in range(n) if not syn[i]]
    missed += [(i, j) for i in range(n) for j in range(i + 1, n) if syn[i] == syn[j]]
    # Every burst from s to s + length - 1 (both ends flipped, any bits between), length <= width.
    for s in range(n):
        inner = {0}                     # syndromes of every subset of the bits between the ends
        for end in range(s + 1, min(n, s + width)):
            if syn[s] ^ syn[end] in inner:
                missed.append((s, "..", end))
            inner |= {x ^ syn[end] for x in inner}
    assert not missed, f"{len(missed)} patterns not detected, e.g. {missed[:3]}"
