"""Frame layout, round trips and fault injection of the encoder model."""

import random

import pytest
from amaranth.lib import crc as am_crc

import protocol_facts as facts
from encoder_model.crc import bits_to_int
from encoder_model.frames import (CRC6, CRC16, CRC_NONE, MAX_WORDS, PRESETS, CustomCrc,
                                  EncoderFrameSource, FrameFaults, FrameFormat, SignOfLife,
                                  WordFormat, WordValue, bp3, build_frame, parse_frame, word_bits)

HEADER = 2          # Start + CDS
N_RANDOM = 40

# Word sizes from the spec, summed by hand: position + nE/nW (2) [+ LC (6)] + CRC (6 or 16).
EXPECTED_TOTAL_BITS = {
    "resolute_fs_lmm": (32 + 2 + 6) + (32 + 2 + 6 + 16),    # 96
    "resolute_fs_rsm": (28 + 2 + 6) + (24 + 2 + 6 + 16),    # 84
    "resolute_fs_rsh": (36 + 2 + 6) + (28 + 2 + 6 + 16),    # 96
    "fortis_fs_rsh": (36 + 2 + 6) + (28 + 2 + 6 + 16),      # 96
    "evolute_26": 34, "evolute_32": 40, "evolute_36": 44,
    "resolute_c_18": 26, "resolute_c_26": 34, "resolute_c_32": 40, "resolute_c_36": 44,
    "bp3_1": 9, "bp3_24": 32, "bp3_55": 63,
    # chain of three: 26 + nE/nW + CRC-6, 17 + nE/nW + CRC-8, 12 + CRC-4
    "chain_3": (26 + 2 + 6) + (17 + 2 + 8) + (12 + 4),      # 77
}
EXPECTED_SPW_SHIFT = {"resolute_fs_lmm": 0, "resolute_fs_rsm": 4, "resolute_fs_rsh": 8,
                      "fortis_fs_rsh": 8}
CHAIN_PRESETS = ("chain_3",)
ALL_FORMATS = list(PRESETS.values()) + [bp3(n) for n in range(1, 56)]


def _ref_crc(bits, width, poly, xor_out):
    algo = am_crc.Algorithm(crc_width=width, polynomial=poly, initial_crc=0,
                            reflect_input=False, reflect_output=False, xor_output=xor_out)
    return algo(data_width=1).compute(bits)


def _random_values(fmt, rng):
    values = []
    for w in fmt.words:
        lc = rng.randint(1, 63) if w.lc else None
        values.append(WordValue(rng.getrandbits(w.data_bits), rng.getrandbits(1),
                                rng.getrandbits(1), lc))
    return values


# -- formats -------------------------------------------------------------------------------

def test_preset_keys_exact():
    assert set(PRESETS) == set(EXPECTED_TOTAL_BITS)


@pytest.mark.parametrize("name", sorted(EXPECTED_TOTAL_BITS))
def test_preset_total_bits(name):
    fmt = PRESETS[name]
    assert fmt.name == name
    assert fmt.total_bits == EXPECTED_TOTAL_BITS[name]
    assert fmt.is_safety == (name in EXPECTED_SPW_SHIFT)


@pytest.mark.parametrize("name", sorted(EXPECTED_SPW_SHIFT))
def test_safety_presets_layout(name):
    cpw, spw = PRESETS[name].words
    assert (cpw.nenw, cpw.lc, cpw.crc) == (True, False, CRC6)
    assert (spw.nenw, spw.lc, spw.crc) == (True, True, CRC16)
    assert PRESETS[name].spw_shift == EXPECTED_SPW_SHIFT[name]


def test_single_word_presets_layout():
    for name, fmt in PRESETS.items():
        if name not in EXPECTED_SPW_SHIFT and name not in CHAIN_PRESETS:
            (word,) = fmt.words
            assert (word.nenw, word.lc, word.crc) == (True, False, CRC6)
            assert fmt.spw_shift == 0


def test_bp3_range():
    for n in range(1, 56):
        fmt = bp3(n)
        assert fmt.name == f"bp3_{n}"
        assert fmt.total_bits == n + 2 + 6
    for bad in (0, 56, -1):
        with pytest.raises(ValueError):
            bp3(bad)


def test_word_format_total_bits_variants():
    assert WordFormat(10, nenw=False, crc=CRC_NONE).total_bits == 10
    assert WordFormat(10, nenw=False, lc=True, crc=CRC16).total_bits == 10 + 6 + 16
    assert WordFormat(64).total_bits == 64 + 2 + 6


@pytest.mark.parametrize("kwargs", [dict(data_bits=0), dict(data_bits=65),
                                    dict(data_bits=8, crc="crc8"), dict(data_bits=8, crc=6)])
def test_word_format_rejects_bad_values(kwargs):
    with pytest.raises(ValueError):
        WordFormat(**kwargs)


def test_frame_format_rejects_bad_word_counts():
    w = WordFormat(8)
    with pytest.raises(ValueError):
        FrameFormat("none", ())
    with pytest.raises(ValueError):
        FrameFormat("nine", (w,) * (MAX_WORDS + 1))
    with pytest.raises(ValueError):
        FrameFormat("nine_chain", (w,) * (MAX_WORDS + 1), chain=True)
    with pytest.raises(ValueError):
        FrameFormat("not_a_word", (w, w, 8))
    with pytest.raises(ValueError):
        FrameFormat("finer_spw", (WordFormat(8), WordFormat(12, lc=True, crc=CRC16)))


# -- word and frame bits -------------------------------------------------------------------

def test_word_bits_hand_example():
    # 4-bit position 1010, nE = 1, nW = 0; CRC register over 101010 is 0x3D (long division,
    # see test_model_crc), sent inverted: 0x02 = 000010.
    bits = word_bits(WordFormat(4), WordValue(0b1010, ne=1, nw=0))
    assert bits == [1, 0, 1, 0, 1, 0, 0, 0, 0, 0, 1, 0]


def test_word_bits_spw_fields():
    fmt = WordFormat(28, lc=True, crc=CRC16)
    value = WordValue(0xABCDEF1, ne=0, nw=1, lc=42)
    bits = word_bits(fmt, value)
    assert len(bits) == 28 + 2 + 6 + 16
    assert bits_to_int(bits[:28]) == 0xABCDEF1
    assert bits[28:30] == [0, 1]
    assert bits_to_int(bits[30:36]) == 42
    assert bits_to_int(bits[36:]) == _ref_crc(bits[:36], 16, 0x90D9, 0xFFFF)


def test_word_bits_without_optional_fields():
    assert word_bits(WordFormat(5, nenw=False, crc=CRC_NONE), WordValue(0b10011)) == [
        1, 0, 0, 1, 1]


def test_build_frame_layout():
    fmt = PRESETS["resolute_fs_rsh"]
    values = [WordValue(0x123456789, 1, 1), WordValue(0x1234567, 1, 0, lc=7)]
    bits = build_frame(fmt, values)
    assert len(bits) == HEADER + 96
    assert bits[:HEADER] == [facts.START_BIT, 0]
    cpw = bits[HEADER:HEADER + 44]
    spw = bits[HEADER + 44:]
    assert cpw == word_bits(fmt.words[0], values[0])
    assert spw == word_bits(fmt.words[1], values[1])
    assert bits_to_int(cpw[38:]) == _ref_crc(cpw[:38], 6, 0x03, 0x3F)
    assert bits_to_int(spw[36:]) == _ref_crc(spw[:36], 16, 0x90D9, 0xFFFF)


@pytest.mark.parametrize("fmt", ALL_FORMATS, ids=lambda f: f.name)
def test_round_trip(fmt):
    rng = random.Random(fmt.name)
    for _ in range(N_RANDOM):
        values = _random_values(fmt, rng)
        parsed = parse_frame(fmt, build_frame(fmt, values))
        assert parsed["start"] == 1 and parsed["cds"] == 0 and parsed["crc_ok"]
        for word, value, wfmt in zip(parsed["words"], values, fmt.words):
            flags = (value.ne, value.nw) if wfmt.nenw else (None, None)
            assert (word["position"], word["ne"], word["nw"], word["lc"]) == (
                value.position, *flags, value.lc)
            assert word["crc_ok"]


@pytest.mark.parametrize("fmt", list(PRESETS.values()), ids=lambda f: f.name)
def test_every_single_bit_flip_in_a_word_is_caught(fmt):
    rng = random.Random(fmt.name + "flip")
    values = _random_values(fmt, rng)
    clean = parse_frame(fmt, build_frame(fmt, values))
    start = HEADER
    for word_index, wfmt in enumerate(fmt.words):
        for i in range(start, start + wfmt.total_bits):
            parsed = parse_frame(fmt, build_frame(fmt, values, FrameFaults(flip_bits=(i,))))
            assert not parsed["words"][word_index]["crc_ok"], i
            assert not parsed["crc_ok"]
            others = [w for k, w in enumerate(parsed["words"]) if k != word_index]
            assert all(w["crc_ok"] for w in others)
        start += wfmt.total_bits
    assert clean["crc_ok"]


def test_header_flips_are_not_crc_covered():
    fmt = PRESETS["evolute_26"]
    values = [WordValue(12345)]
    parsed = parse_frame(fmt, build_frame(fmt, values, FrameFaults(flip_bits=(0, 1))))
    assert (parsed["start"], parsed["cds"], parsed["crc_ok"]) == (0, 1, True)


def test_cds_fault():
    fmt = PRESETS["resolute_c_32"]
    bits = build_frame(fmt, [WordValue(7)], FrameFaults(cds=1))
    assert bits[:HEADER] == [1, 1]
    assert parse_frame(fmt, bits)["cds"] == 1


@pytest.mark.parametrize("name", sorted(EXPECTED_SPW_SHIFT))
def test_crc_xor_corrupts_only_its_word(name):
    fmt = PRESETS[name]
    values = _random_values(fmt, random.Random(name))
    for word_index, xor in ((0, 0x01), (1, 0x8000), (1, 0xFFFF)):
        crc_xor = (0, xor) if word_index else (xor,)
        parsed = parse_frame(fmt, build_frame(fmt, values, FrameFaults(crc_xor=crc_xor)))
        assert [w["crc_ok"] for w in parsed["words"]] == [word_index != 0, word_index != 1]
        clean = parse_frame(fmt, build_frame(fmt, values))["words"][word_index]["crc"]
        assert parsed["words"][word_index]["crc"] == clean ^ xor


def test_word_value_validation():
    fmt = WordFormat(8)
    spw = WordFormat(8, lc=True, crc=CRC16)
    for bad in (WordValue(256), WordValue(-1), WordValue(1, ne=2), WordValue(1, nw=-1),
                WordValue(1, lc=3)):
        with pytest.raises(ValueError):
            word_bits(fmt, bad)
    for bad in (WordValue(1), WordValue(1, lc=64), WordValue(1, lc=-1)):
        with pytest.raises(ValueError):
            word_bits(spw, bad)
    assert word_bits(spw, WordValue(1, lc=0))      # 0 is encodable (the zero fault)


def test_build_and_parse_validation():
    fmt = PRESETS["evolute_32"]
    ok = [WordValue(1)]
    with pytest.raises(ValueError):
        build_frame(fmt, ok + ok)
    with pytest.raises(ValueError):
        build_frame(fmt, ok, FrameFaults(flip_bits=(HEADER + 40,)))
    with pytest.raises(ValueError):
        build_frame(fmt, ok, FrameFaults(crc_xor=(1, 1)))
    with pytest.raises(ValueError):
        build_frame(fmt, ok, FrameFaults(crc_xor=(0x40,)))
    with pytest.raises(ValueError):
        build_frame(fmt, ok, FrameFaults(cds=2))
    with pytest.raises(ValueError):
        word_bits(WordFormat(4, crc=CRC_NONE), WordValue(1), crc_xor=1)
    with pytest.raises(ValueError):
        parse_frame(fmt, build_frame(fmt, ok)[:-1])


# -- sign of life --------------------------------------------------------------------------

def test_sign_of_life_sequence_wraps_and_skips_zero():
    sol = SignOfLife()
    seq = [sol.next() for _ in range(200)]
    assert seq[:3] == [1, 2, 3]
    assert seq[62:65] == [63, 1, 2]
    assert 0 not in seq
    assert seq == [(i % 63) + 1 for i in range(200)]
    assert facts.LC_FIRST == 1 and facts.LC_MAX == 63


def test_sign_of_life_faults():
    sol = SignOfLife()
    with pytest.raises(ValueError):
        sol.repeat()
    assert [sol.next(), sol.next()] == [1, 2]
    assert sol.repeat() == 2
    assert sol.next() == 3
    assert sol.zero() == 0
    assert sol.next() == 4
    assert sol.skip(2) == 7
    assert sol.next() == 8
    with pytest.raises(ValueError):
        sol.skip(-1)
    late = SignOfLife(first=62)
    assert [late.next(), late.skip(1), late.next()] == [62, 1, 2]


# -- encoder frame source ------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(EXPECTED_SPW_SHIFT))
def test_source_spw_is_cpw_with_low_bits_dropped(name):
    fmt = PRESETS[name]
    shift = EXPECTED_SPW_SHIFT[name]
    speed = 123_456_789.0      # counts per second, arbitrary
    src = EncoderFrameSource(fmt, lambda t: int(speed * t))
    for k in range(50):
        t = k * facts.MIN_CYCLE_PERIOD_S
        bits, values = src.frame_at(t)
        cpw_bits = fmt.words[0].data_bits
        expected = int(speed * t) % (1 << cpw_bits)
        assert values[0].position == expected
        assert values[1].position == expected >> shift
        assert values[1].lc == (k % 63) + 1 and values[0].lc is None
        parsed = parse_frame(fmt, bits)
        assert parsed["crc_ok"]
        assert parsed["words"][1]["position"] == parsed["words"][0]["position"] >> shift


def test_source_wraps_position_and_applies_status():
    fmt = PRESETS["resolute_c_18"]
    src = EncoderFrameSource(fmt, lambda t: -1 if t < 0 else (1 << 18) + 5, ne=0, nw=0)
    assert src.values_at(-1.0)[0] == WordValue((1 << 18) - 1, 0, 0, None)
    assert src.values_at(1.0)[0].position == 5


def test_source_lc_override_does_not_advance_counter():
    fmt = PRESETS["resolute_fs_lmm"]
    src = EncoderFrameSource(fmt, lambda t: 0)
    assert src.values_at(0)[1].lc == 1
    assert src.values_at(0, lc=src.sign_of_life.zero())[1].lc == 0
    assert src.values_at(0, lc=src.sign_of_life.repeat())[1].lc == 1
    assert src.values_at(0)[1].lc == 2


def test_source_single_word_does_not_touch_counter():
    src = EncoderFrameSource(PRESETS["evolute_26"], lambda t: 99)
    bits, values = src.frame_at(0.0, FrameFaults(crc_xor=(1,)))
    assert values == [WordValue(99)]
    assert not parse_frame(PRESETS["evolute_26"], bits)["crc_ok"]
    assert src.sign_of_life.next() == 1


def test_gray_code_published_sequence_and_round_trip():
    """The reflected binary code of 0..15 as tabulated (Gray's patent; OEIS A003188), and
    from_gray its inverse."""
    from encoder_model.frames import from_gray, to_gray
    assert [to_gray(n) for n in range(16)] == [0, 1, 3, 2, 6, 7, 5, 4, 12, 13, 15, 14, 10, 11, 9, 8]
    rng = random.Random(2600)
    for n in [0, 1, 2**55 - 1] + [rng.getrandbits(55) for _ in range(200)]:
        assert from_gray(to_gray(n)) == n
        assert bin(to_gray(n) ^ to_gray(n + 1)).count("1") == 1


def test_to_signed_is_twos_complement():
    """to_signed against Python's own two's complement reading of the same bytes
    (int.from_bytes(signed=True)) at byte widths, and hand values at odd ones."""
    from encoder_model.frames import to_signed
    rng = random.Random(2601)
    for bits in (8, 16, 32, 56, 64):
        for field in [0, 1, (1 << bits) - 1, 1 << (bits - 1)] + [rng.getrandbits(bits)
                                                                 for _ in range(50)]:
            assert to_signed(field, bits) == int.from_bytes(
                field.to_bytes(bits // 8, "big"), "big", signed=True)
    assert [to_signed(f, 3) for f in range(8)] == [0, 1, 2, 3, -4, -3, -2, -1]
    assert to_signed(1, 1) == -1 and to_signed(0, 1) == 0
    with pytest.raises(ValueError):
        to_signed(8, 3)


def test_gray_word_sends_gray_and_parses_binary():
    fmt = FrameFormat("g", (WordFormat(13, gray=True),))
    bits = build_frame(fmt, [WordValue(0b1000000000000, 1, 1)])
    assert bits[2:15] == [1, 1] + [0] * 11             # 4096 -> Gray 0b1100000000000
    assert parse_frame(fmt, bits)["words"][0]["position"] == 4096
    assert parse_frame(fmt, bits)["crc_ok"]


# -- chains of slaves (issue 26): 1..8 words, not BiSS Safety ---------------------------------

def _crc_ref(bits, width, poly, init, xor_out):
    """amaranth's CRC model with a start value: a reference the model shares no code with."""
    algo = am_crc.Algorithm(crc_width=width, polynomial=poly, initial_crc=init,
                            reflect_input=False, reflect_output=False, xor_output=xor_out)
    return algo(data_width=1).compute(bits)


def test_chain_3_layout():
    fmt = PRESETS["chain_3"]
    assert fmt.chain and fmt.is_chain and not fmt.is_safety and fmt.spw_shift == 0
    w0, w1, w2 = fmt.words
    assert (w0.data_bits, w0.nenw, w0.lc, w0.crc) == (26, True, False, CRC6)
    assert (w1.data_bits, w1.nenw, w1.lc, w1.crc) == (17, True, False, CustomCrc(8, 0x2F, 0xA5, True))
    assert (w2.data_bits, w2.nenw, w2.lc, w2.crc) == (12, False, False, CustomCrc(4, 0x3, 0x9, False))
    # different lengths, CRC widths, polynomials and start values
    assert len({w.data_bits for w in fmt.words}) == 3
    assert len({w.crc_bits for w in fmt.words}) == 3
    assert fmt.word_offsets() == [HEADER, HEADER + 34, HEADER + 34 + 27]


def test_chain_3_frame_by_hand():
    """Every word where its offset says, each CRC against amaranth's model with the word's own
    polynomial, start value and inversion; parse_frame gives the values back."""
    fmt = PRESETS["chain_3"]
    values = [WordValue(0x2ABCDEF, 1, 0), WordValue(0x1F0F1, 0, 1), WordValue(0xA5C)]
    bits = build_frame(fmt, values)
    assert len(bits) == HEADER + 77 and bits[:HEADER] == [facts.START_BIT, 0]
    o0, o1, o2 = fmt.word_offsets()
    w0, w1, w2 = bits[o0:o1], bits[o1:o2], bits[o2:]
    assert bits_to_int(w0[:26]) == 0x2ABCDEF and w0[26:28] == [1, 0]
    assert bits_to_int(w0[28:]) == _crc_ref(w0[:28], 6, 0x03, 0, 0x3F)
    assert bits_to_int(w1[:17]) == 0x1F0F1 and w1[17:19] == [0, 1]
    assert bits_to_int(w1[19:]) == _crc_ref(w1[:19], 8, 0x2F, 0xA5, 0xFF)
    assert bits_to_int(w2[:12]) == 0xA5C and len(w2) == 16
    assert bits_to_int(w2[12:]) == _crc_ref(w2[:12], 4, 0x3, 0x9, 0)
    parsed = parse_frame(fmt, bits)
    assert parsed["crc_ok"]
    assert [(w["position"], w["ne"], w["nw"]) for w in parsed["words"]] == [
        (0x2ABCDEF, 1, 0), (0x1F0F1, 0, 1), (0xA5C, None, None)]
    # The start value matters: the same word with start 0 has another CRC (for most data).
    assert _crc_ref(w1[:19], 8, 0x2F, 0, 0xFF) != bits_to_int(w1[19:])


@pytest.mark.parametrize("word", range(3))
def test_chain_3_crc_error_in_one_word_only(word):
    fmt = PRESETS["chain_3"]
    rng = random.Random(word)
    values = _random_values(fmt, rng)
    for xor in (1, (1 << fmt.words[word].crc_bits) - 1):
        crc_xor = tuple(xor if k == word else 0 for k in range(3))
        parsed = parse_frame(fmt, build_frame(fmt, values, FrameFaults(crc_xor=crc_xor)))
        assert [w["crc_ok"] for w in parsed["words"]] == [k != word for k in range(3)]
        assert not parsed["crc_ok"]


def test_two_words_are_safety_unless_a_chain():
    """Every existing two-word format stays BiSS Safety; chain=True says two slaves: no SPW
    relation, so a second word longer than the first is fine."""
    for name in EXPECTED_SPW_SHIFT:
        assert PRESETS[name].is_safety and not PRESETS[name].is_chain
    pair = (WordFormat(8), WordFormat(12, lc=True, crc=CRC16))
    with pytest.raises(ValueError):
        FrameFormat("finer_spw", pair)
    two = FrameFormat("two_slaves", pair, chain=True)
    assert not two.is_safety and two.is_chain and two.spw_shift == 0
    for n in (1, 3, MAX_WORDS):
        fmt = FrameFormat(f"w{n}", (WordFormat(8),) * n)
        assert not fmt.is_safety and fmt.is_chain == (n > 2)


def test_eight_word_chain_round_trip():
    fmt = FrameFormat("eight", tuple(WordFormat(n, nenw=n % 2 == 0,
                                                crc=CustomCrc(n % 16 + 1, 1, n % 2))
                                     for n in range(3, 3 + MAX_WORDS)), chain=True)
    rng = random.Random(8)
    for _ in range(N_RANDOM):
        values = _random_values(fmt, rng)
        parsed = parse_frame(fmt, build_frame(fmt, values))
        assert parsed["crc_ok"]
        assert [w["position"] for w in parsed["words"]] == [v.position for v in values]


def test_chain_source_positions_per_word():
    fmt = PRESETS["chain_3"]
    src = EncoderFrameSource(fmt, lambda t: 0,
                             chain_positions_at=lambda t: ((1 << 26) + 5, (1 << 17) + 6, 0xFFFF))
    assert [v.position for v in src.values_at(0.0)] == [5, 6, 0xFFF]
    # without per-word positions every slave shows position_at, wrapped to its word
    src = EncoderFrameSource(fmt, lambda t: 0x3FFFFFF)
    assert [v.position for v in src.values_at(0.0)] == [0x3FFFFFF, 0x1FFFF, 0xFFF]
    # a Safety source is unchanged: SPW = CPW >> spw_shift
    rsh = PRESETS["resolute_fs_rsh"]
    src = EncoderFrameSource(rsh, lambda t: 0x123456789, chain_positions_at=lambda t: (1, 2))
    assert [v.position for v in src.values_at(0.0)] == [0x123456789, 0x123456789 >> 8]
