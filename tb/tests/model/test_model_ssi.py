"""The SSI encoder model (tb/encoder_model/ssi.py) against hand-worked examples of the facts in
docs/frames_research.md, section 2, and against frames.to_gray / from_gray."""

import random

import pytest

from encoder_model.crc import bits_to_int, crc6_biss, int_to_bits
from encoder_model.frames import (CRC6, CRC16, CRC_NONE, CustomCrc, WordFormat, WordValue,
                                  from_gray, to_gray, word_bits)
from encoder_model.ssi import (SsiEncoder, SsiFormat, SsiReading, gray_decode_bits,
                               gray_encode_bits, line_high_at, line_levels, parse_ssi,
                               read_at_rising_edges, ssi_bits)

US = 1e-6
N_RANDOM = 300


# -- hand-worked examples ------------------------------------------------------------------------

def test_13_bit_gray_singleturn():
    # 5000 = 4096 + 512 + 256 + 128 + 8 = 1 0011 1000 1000 (13 bits). Gray: keep the MSB, then
    # the XOR of each pair of neighbouring binary bits: 1 1010 0100 1100.
    fmt = SsiFormat(13, gray=True)
    gray = [1, 1, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0]
    assert ssi_bits(fmt, 5000) == gray
    assert fmt.clocks == 14
    # 14 clocks: the MSB at rising edge 1 ... the LSB at edge 13, edge 14 drives the line low.
    assert line_levels(fmt, 5000) == gray + [0]
    assert parse_ssi(fmt, gray) == SsiReading(5000, ())


def test_25_bit_binary_with_an_active_high_error_bit():
    # 0x1234567 = 2**24 + 0x234567: a 1, then 0010 0011 0100 0101 0110 0111; the error bit
    # after the LSB is 1 when active (active high); 27 clocks, the last one drives the line low.
    fmt = SsiFormat(25, error_bits=1, error_polarity=("high",))
    word = [1] + [0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 0, 0, 1, 0, 1, 0, 1, 1, 0, 0, 1, 1, 1]
    assert ssi_bits(fmt, 0x1234567, (True,)) == word + [1]
    assert ssi_bits(fmt, 0x1234567, (False,)) == word + [0]
    assert ssi_bits(fmt, 0x1234567) == word + [0]          # default: no error active
    assert line_levels(fmt, 0x1234567, (True,)) == word + [1, 0]
    assert len(line_levels(fmt, 0x1234567, (True,))) == fmt.clocks == 27
    assert parse_ssi(fmt, word + [1]) == SsiReading(0x1234567, (True,))


def test_active_low_error_bits():
    fmt = SsiFormat(4, error_bits=2, error_polarity=("high", "low"))
    assert ssi_bits(fmt, 0b0110, (False, False)) == [0, 1, 1, 0, 0, 1]
    assert ssi_bits(fmt, 0b0110, (True, True)) == [0, 1, 1, 0, 1, 0]
    assert ssi_bits(fmt, 0b0110, (False, True)) == [0, 1, 1, 0, 0, 0]
    assert parse_ssi(fmt, [0, 1, 1, 0, 1, 1]) == SsiReading(0b0110, (True, False))
    low = SsiFormat(4, error_bits=1, error_polarity=("low",))
    assert ssi_bits(low, 0b0110, (True,))[-1] == 0
    assert ssi_bits(low, 0b0110, (False,))[-1] == 1


def test_error_bit_gray_coded_with_the_data_or_not():
    # 3-bit position 5 = 101, Gray 111. Error active high, active = 1.
    # Not Gray-coded (Leuze): 111 then 1. Gray-coded with the data (SICK DL100): the word
    # 1011 Gray-coded = 1110; inactive: 1010 -> 1111.
    plain = SsiFormat(3, gray=True, error_bits=1)
    joint = SsiFormat(3, gray=True, error_bits=1, gray_errors=True)
    assert ssi_bits(plain, 5, (True,)) == [1, 1, 1, 1]
    assert ssi_bits(plain, 5, (False,)) == [1, 1, 1, 0]
    assert ssi_bits(joint, 5, (True,)) == [1, 1, 1, 0]
    assert ssi_bits(joint, 5, (False,)) == [1, 1, 1, 1]
    assert parse_ssi(joint, [1, 1, 1, 0]) == SsiReading(5, (True,))
    assert parse_ssi(plain, [1, 1, 1, 0]) == SsiReading(5, (False,))


def test_ring_mode_repeats_after_one_zero_bit():
    # iC-MU RSSI = 1: word, one 0, word, one 0, ...; RSSI = 0: zeros after the word.
    ring = SsiFormat(4, repeat="ring")
    assert line_levels(ring, 0b1011, n_clocks=12) == [1, 0, 1, 1, 0, 1, 0, 1, 1, 0, 1, 0]
    double = line_levels(ring, 0b1011, n_clocks=2 * ring.clocks)
    assert double[:4] == double[5:9] == [1, 0, 1, 1] and double[4] == double[9] == 0
    zeros = SsiFormat(4, repeat="zeros")
    assert line_levels(zeros, 0b1011, n_clocks=12) == [1, 0, 1, 1] + [0] * 8
    # A same_value encoder repeats only on a new clock train: one long train reads zeros.
    same = SsiFormat(4, repeat="same_value")
    assert line_levels(same, 0b1011, n_clocks=12) == [1, 0, 1, 1] + [0] * 8


def test_short_trains_and_the_reads_at_rising_edges():
    fmt = SsiFormat(13, gray=True)
    full = line_levels(fmt, 5000)
    for n in range(len(full) + 1):
        assert line_levels(fmt, 5000, n_clocks=n) == full[:n]
    # TR p. 69: read at the rising edges, the idle 1 comes first; one clock more than n + 1
    # brings the 0 after the LSB.
    reads = read_at_rising_edges(line_levels(fmt, 5000, n_clocks=fmt.clocks + 1))
    assert reads == [1] + ssi_bits(fmt, 5000) + [0]
    assert read_at_rising_edges([]) == []


# -- Gray code against frames.to_gray / from_gray ---------------------------------------------

def test_gray_bits_agree_with_frames_gray():
    rng = random.Random(26)
    cases = [(n, 10) for n in range(1 << 10)] + [(rng.getrandbits(64), 64) for _ in range(200)]
    for n, width in cases:
        assert gray_encode_bits(int_to_bits(n, width)) == int_to_bits(to_gray(n), width)
        assert bits_to_int(gray_decode_bits(int_to_bits(n, width))) == from_gray(n)
        assert gray_decode_bits(gray_encode_bits(int_to_bits(n, width))) == int_to_bits(n, width)


def test_gray_word_is_frames_gray_of_the_position():
    rng = random.Random(3)
    for _ in range(N_RANDOM):
        width = rng.randint(1, 64)
        pos = rng.getrandbits(width)
        bits = ssi_bits(SsiFormat(width, gray=True), pos)
        assert bits_to_int(bits) == to_gray(pos)
        assert from_gray(bits_to_int(bits)) == pos
        assert bits_to_int(ssi_bits(SsiFormat(width), pos)) == pos


def test_gray_coded_errors_are_frames_gray_of_the_joint_word():
    rng = random.Random(4)
    for _ in range(N_RANDOM):
        width, n_err = rng.randint(1, 64), rng.randint(1, 2)
        polarity = tuple(rng.choice(("high", "low")) for _ in range(n_err))
        fmt = SsiFormat(width, gray=True, error_bits=n_err, error_polarity=polarity,
                        gray_errors=True)
        pos, errors = rng.getrandbits(width), tuple(rng.random() < 0.5 for _ in range(n_err))
        levels = [int(e) if p == "high" else int(not e) for e, p in zip(errors, polarity)]
        joint = (pos << n_err) | bits_to_int(levels)
        assert bits_to_int(ssi_bits(fmt, pos, errors)) == to_gray(joint)
        # the position bits alone are still the position's Gray code
        assert bits_to_int(ssi_bits(fmt, pos, errors)[:width]) == to_gray(pos)


# -- length, order, polarity, round trip -------------------------------------------------------

@pytest.mark.parametrize("width", [1, 2, 13, 25, 64])
def test_length_and_msb_first(width):
    for n_err in (0, 1, 2):
        fmt = SsiFormat(width, error_bits=n_err)
        assert fmt.total_bits == width + n_err and fmt.clocks == width + n_err + 1
        assert len(ssi_bits(fmt, 0)) == fmt.total_bits
        assert ssi_bits(fmt, 1 << (width - 1))[:width] == [1] + [0] * (width - 1)
        assert ssi_bits(fmt, 1)[:width] == [0] * (width - 1) + [1]
        assert line_levels(fmt, (1 << width) - 1)[-1] == 0


def test_parse_inverts_build_over_random_formats_and_values():
    rng = random.Random(5)
    for _ in range(N_RANDOM):
        width, n_err = rng.randint(1, 64), rng.randint(0, 2)
        gray = rng.random() < 0.5
        fmt = SsiFormat(width, gray=gray, error_bits=n_err,
                        error_polarity=tuple(rng.choice(("high", "low")) for _ in range(n_err)),
                        gray_errors=gray and n_err > 0 and rng.random() < 0.5)
        pos, errors = rng.getrandbits(width), tuple(rng.random() < 0.5 for _ in range(n_err))
        assert parse_ssi(fmt, ssi_bits(fmt, pos, errors)) == SsiReading(pos, errors)


def test_a_flipped_position_bit_changes_the_parsed_value():
    fmt = SsiFormat(13, gray=True, error_bits=1)
    bits = ssi_bits(fmt, 5000, (False,))
    for i in range(fmt.total_bits):
        flipped = bits[:i] + [1 - bits[i]] + bits[i + 1:]
        assert parse_ssi(fmt, flipped) != SsiReading(5000, (False,))


@pytest.mark.parametrize("kwargs", [
    dict(data_bits=0), dict(data_bits=65), dict(data_bits=8, error_bits=3),
    dict(data_bits=8, error_bits=-1), dict(data_bits=8, error_bits=1, error_polarity=("up",)),
    dict(data_bits=8, error_bits=1, error_polarity=("high", "low")),
    dict(data_bits=8, error_polarity=("high",)),
    dict(data_bits=8, error_bits=1, gray_errors=True),           # gray_errors needs gray
    dict(data_bits=8, gray=True, gray_errors=True),              # and an error bit
    dict(data_bits=8, repeat="twice"), dict(data_bits=8, tm_s=0),
    dict(data_bits=8, retrigger="rising")])
def test_format_rejects_bad_values(kwargs):
    with pytest.raises(ValueError):
        SsiFormat(**kwargs)


def test_bad_values_and_bit_counts_are_refused():
    fmt = SsiFormat(4, error_bits=1)
    for bad in (-1, 16):
        with pytest.raises(ValueError):
            ssi_bits(fmt, bad)
    with pytest.raises(ValueError):
        ssi_bits(fmt, 3, (True, True))
    with pytest.raises(ValueError):
        ssi_bits(fmt, 3, (2,))
    with pytest.raises(ValueError):
        parse_ssi(fmt, [0, 0, 1, 1])
    with pytest.raises(ValueError):
        line_levels(fmt, 3, n_clocks=-1)
    assert SsiFormat(4, error_bits=2).error_polarity == ("high", "high")


# -- monoflop timing -------------------------------------------------------------------------

def test_line_high_at_falling_retrigger_and_any_edge():
    fmt = SsiFormat(13)                           # tm 20 us by default
    assert fmt.tm_s == pytest.approx(20 * US)
    # 14 clocks at 1 MHz from t = 0: last fall at 13 us, last rise at 13.5 us.
    assert line_high_at(fmt, 13 * US, 13.5 * US) == pytest.approx(33 * US)
    assert line_high_at(fmt, 13 * US) == pytest.approx(33 * US)
    anyedge = SsiFormat(13, retrigger="any")
    assert line_high_at(anyedge, 13 * US, 13.5 * US) == pytest.approx(33.5 * US)
    with pytest.raises(ValueError):
        line_high_at(anyedge, 13 * US)


def test_line_low_for_tm_after_the_word_then_high():
    fmt = SsiFormat(13, gray=True)
    enc = SsiEncoder(fmt, lambda t: 5000)
    assert enc.level_at(-1 * US) == 1                       # idle
    tr = enc.train(0.0, period_s=1 * US)
    assert tr.new_latch and tr.position == 5000 and tr.levels == line_levels(fmt, 5000)
    assert (tr.t_last_fall_s, tr.t_last_rise_s) == pytest.approx((13 * US, 13.5 * US))
    assert tr.line_high_s == pytest.approx(33 * US)
    assert enc.level_at(0.2 * US) == 1                      # fallen, not yet risen: idle 1
    for k, bit in enumerate(ssi_bits(fmt, 5000), start=1):  # bit k from rising edge k on
        assert enc.level_at(tr.rising_edge_s(k)) == bit
        assert enc.level_at(tr.rising_edge_s(k) + 0.4 * US) == bit
    for t in (13.5, 14, 20, 30, 32.99):
        assert enc.level_at(t * US) == 0
    assert enc.level_at(33.01 * US) == 1


def test_each_falling_edge_retriggers_the_monoflop():
    # 66 clocks at 1 MHz last 65.5 us, over three times tm: the line stays low from the 14th
    # rising edge until tm after the *last* falling edge (65 + 20 us).
    fmt = SsiFormat(13)
    enc = SsiEncoder(fmt, lambda t: 0x1FFF)
    tr = enc.train(0.0, n_clocks=66, period_s=1 * US)
    assert tr.line_high_s == pytest.approx(85 * US)
    assert tr.levels == [1] * 13 + [0] * 53
    for t in (14, 20.5, 33.5, 50, 84.9):
        assert enc.level_at(t * US) == 0
    assert enc.level_at(85.1 * US) == 1
    # a new train at 80 us (within tm of the last fall) latches nothing new
    assert not enc.train(80 * US, period_s=1 * US).new_latch


def test_same_value_within_tm_new_latch_after_tm():
    fmt = SsiFormat(13, gray=True, error_bits=1, repeat="same_value")
    enc = SsiEncoder(fmt, lambda t: round(t / US), errors_at=lambda t: (t > 150 * US,))
    first = enc.train(100 * US, period_s=1 * US)            # last fall 114 us, high at 134 us
    assert first.new_latch and first.position == 100 and first.errors == (False,)
    assert first.line_high_s == pytest.approx(134 * US)
    again = enc.train(120 * US, period_s=1 * US)            # within tm: the same value
    assert not again.new_latch
    assert (again.position, again.errors, again.t_latch_s) == (100, (False,), 100 * US)
    assert again.levels == first.levels == line_levels(fmt, 100, (False,))
    assert again.level_before == 0                          # the line was still low
    assert again.line_high_s == pytest.approx(154 * US)     # retriggered by the new train
    late = enc.train(160 * US, period_s=1 * US)             # after tm: a new latch
    assert late.new_latch and late.position == 160 and late.errors == (True,)
    assert late.levels == line_levels(fmt, 160, (True,))
    assert late.level_before == 1


def test_new_latch_exactly_at_tm_not_before():
    # 9 clocks of 1.5 us: falls at 0, 1.5, ..., 12 us; the line goes high at 12 + 20 = 32 us.
    # A train starting then latches anew; one starting a hair earlier retriggers.
    fmt = SsiFormat(8)
    for nudge, expected in ((0.0, True), (-1e-12, False)):
        enc = SsiEncoder(fmt, lambda t: round(t / US))
        first = enc.train(0.0, period_s=1.5 * US)
        assert first.line_high_s == pytest.approx(32 * US)
        tr = enc.train(first.line_high_s + nudge, period_s=1 * US)
        assert tr.new_latch is expected
        assert tr.position == (32 if expected else 0)


def test_continued_shifting_within_tm_for_ring_and_zeros():
    word = ssi_bits(SsiFormat(4), 0b1011)
    ring = SsiEncoder(SsiFormat(4, repeat="ring"), lambda t: 0b1011)
    ring.train(0.0, n_clocks=7, period_s=1 * US)            # word, 0, then 2 bits of copy 2
    second = ring.train(10 * US, n_clocks=5, period_s=1 * US)
    assert not second.new_latch
    assert second.levels == word[2:] + [0] + word[:2]
    zeros = SsiEncoder(SsiFormat(4, repeat="zeros"), lambda t: 0b1011)
    zeros.train(0.0, n_clocks=5, period_s=1 * US)
    assert zeros.train(10 * US, n_clocks=5, period_s=1 * US).levels == [0] * 5


def test_trains_must_not_overlap_and_clock_must_outrun_tm():
    enc = SsiEncoder(SsiFormat(8), lambda t: 0)
    tr = enc.train(0.0, period_s=1 * US)
    with pytest.raises(ValueError):
        enc.train(tr.t_last_rise_s, period_s=1 * US)
    with pytest.raises(ValueError):
        enc.train(100 * US, period_s=25 * US)               # a period longer than tm
    with pytest.raises(ValueError):
        enc.train(100 * US, n_clocks=0)


# -- extended SSI (iC-MU MODEA 0x7): nE nW and a CRC after the position ------------------------

def test_extended_ssi_is_a_biss_word_without_ack_and_start():
    # Position, nE, nW and a CRC over all of them as sent: bit for bit the BiSS word of the
    # same layout (frames.word_bits, an independent builder).
    rng = random.Random(7)
    for crc in (CRC6, CRC16, CustomCrc(8, 0x07), CRC_NONE):
        for gray in (False, True):
            width = rng.randint(1, 48)
            fmt = SsiFormat(width, gray=gray, nenw=True, crc=crc)
            biss = WordFormat(width, nenw=True, crc=crc, gray=gray)
            assert fmt.total_bits == biss.total_bits
            for _ in range(20):
                pos, ne, nw = rng.getrandbits(width), rng.getrandbits(1), rng.getrandbits(1)
                bits = ssi_bits(fmt, pos, nenw=(ne, nw))
                assert bits == word_bits(biss, WordValue(pos, ne, nw))
                crc_ok = True if crc != CRC_NONE else None
                assert parse_ssi(fmt, bits) == SsiReading(pos, (), ne, nw, crc_ok)


def test_extended_ssi_crc_covers_the_error_bit_and_catches_a_flip():
    fmt = SsiFormat(13, error_bits=1, crc=CRC6)
    assert fmt.total_bits == 13 + 1 + 6 and fmt.flag_bits == 1
    bits = ssi_bits(fmt, 0x1ABC, (True,))
    assert bits[:14] == int_to_bits(0x1ABC, 13) + [1]
    assert bits_to_int(bits[14:]) == crc6_biss(bits[:14])
    assert parse_ssi(fmt, bits) == SsiReading(0x1ABC, (True,), crc_ok=True)
    for i in range(len(bits)):
        flipped = bits[:i] + [1 - bits[i]] + bits[i + 1:]
        assert parse_ssi(fmt, flipped).crc_ok is False


def test_extended_ssi_in_ring_mode_repeats_the_whole_word():
    fmt = SsiFormat(5, nenw=True, crc=CRC6, repeat="ring")
    word = ssi_bits(fmt, 0b10110, nenw=(0, 1))
    assert line_levels(fmt, 0b10110, n_clocks=2 * fmt.clocks, nenw=(0, 1)) == word + [0] + word + [0]
    enc = SsiEncoder(fmt, lambda t: 0b10110, nenw_at=lambda t: (0, 1))
    assert enc.train(0.0, n_clocks=2 * fmt.clocks).levels == word + [0] + word + [0]


def test_extended_ssi_refuses_bad_flags():
    with pytest.raises(ValueError):
        ssi_bits(SsiFormat(4, nenw=True), 3, nenw=(1, 2))
    with pytest.raises(ValueError):
        ssi_bits(SsiFormat(4), 3, nenw=(1, 1))          # no nE / nW in this format
    with pytest.raises(ValueError):
        SsiFormat(4, crc="crc7")
