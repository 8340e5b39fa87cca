"""Unit tests of the campaigns' reference model (sim/shared/reference.py) and coverage bins,
against hand-worked cases from docs/ports.md: the model must be right before it judges the RTL."""

import pytest

from encoder_model import frames
from master_contract import STATUS, crc_counters, crc_status
from sim.shared.functional_coverage import LEGAL, Coverage, bins, delay_bin, report
from sim.shared.reference import MasterReference, config_valid

RSH = frames.PRESETS["resolute_fs_rsh"]
C36 = frames.PRESETS["resolute_c_36"]


def rsh_bits(cpw, spw, lc, faults=None):
    return frames.build_frame(RSH, [frames.WordValue(cpw), frames.WordValue(spw, lc=lc)], faults)


def test_good_frame_and_crc_priorities():
    ref = MasterReference()
    assert ref.judge(RSH, rsh_bits(0x123456789, 0x1234567, 5)).status == STATUS["OK"]
    cpw_bit, spw_bit = 2 + 3, 2 + 44 + 3
    for flips, status in (((cpw_bit,), "CRC_ERROR_WORD0"), ((spw_bit,), "CRC_ERROR_WORD1"),
                          ((cpw_bit, spw_bit), "CRC_ERROR_BOTH")):
        v = ref.judge(RSH, rsh_bits(0x123456789, 0x1234567, 6,
                                    frames.FrameFaults(flip_bits=flips)))
        assert v.status == STATUS[status], status
    single = frames.build_frame(C36, [frames.WordValue(7)], frames.FrameFaults(flip_bits=(2,)))
    assert ref.judge(C36, single).status == STATUS["CRC_ERROR_WORD0"]


def test_sign_of_life_rules():
    ref = MasterReference()
    judge = lambda lc: ref.judge(RSH, rsh_bits(0, 0, lc))          # noqa: E731
    assert judge(40).status == STATUS["OK"]          # first after power-up: accepted as is
    assert judge(41).status == STATUS["OK"]
    assert judge(41).lc_repeat == 1
    assert judge(45).lc_skip == 1                    # a skip is stored: 46 is in sequence
    assert judge(46).status == STATUS["OK"]
    assert judge(0).lc_zero == 1                     # zero is not stored
    assert judge(47).status == STATUS["OK"]
    ref.last_lc = 63
    assert judge(1).status == STATUS["OK"]           # 63 wraps to 1, never 0
    ref.resync()
    assert judge(17).status == STATUS["OK"]
    # A bad SPW CRC hides the LC: the next good frame shows the lost one as a skip.
    bad = rsh_bits(0, 0, 18, frames.FrameFaults(crc_xor=(0, 1)))
    assert ref.judge(RSH, bad).status == STATUS["CRC_ERROR_WORD1"]
    assert judge(19).lc_skip == 1


def test_spw_plausibility_and_priority():
    ref = MasterReference()
    cpw = (2**36 - 1)                                # top of the range; SPW wrapped to 0
    v = ref.judge(RSH, rsh_bits(cpw, 0, 1), spw_tolerance=1)
    assert v.status == STATUS["OK"]
    v = ref.judge(RSH, rsh_bits(cpw, 2, 2), spw_tolerance=1)
    assert v.status == STATUS["SPW_MISMATCH"]
    v = ref.judge(RSH, rsh_bits(cpw, 2, 2), spw_tolerance=3)      # repeat beats mismatch
    assert v.status == STATUS["SIGN_OF_LIFE"] and v.lc_repeat
    v = ref.judge(RSH, rsh_bits(0x100, 0x1, 3), spw_check=False)
    assert v.status == STATUS["OK"]


GOOD = {"cfg_ma_half_period": 5, "cfg_delay_limit": 0, "cfg_w1_enable": 1,
        "cfg_spw_check": 1, "cfg_spw_tolerance": 1, "cfg_w0_data_bits": 36, "cfg_w0_nenw": 1,
        "cfg_w0_lc": 0, "cfg_w0_crc": 1, "cfg_w1_data_bits": 28, "cfg_w1_nenw": 1,
        "cfg_w1_lc": 1, "cfg_w1_crc": 2}


@pytest.mark.parametrize("change,valid", [
    ({}, True), ({"cfg_ma_half_period": 1}, False), ({"cfg_ma_half_period": 2}, True),
    ({"cfg_w0_data_bits": 0}, False), ({"cfg_w0_data_bits": 55}, True),
    ({"cfg_w0_data_bits": 56}, False), ({"cfg_w1_data_bits": 41}, False),
    ({"cfg_w0_crc": 3}, False), ({"cfg_w0_lc": 1}, False),
    ({"cfg_w0_lc": 1, "cfg_w1_enable": 0, "cfg_spw_check": 0}, True),
    ({"cfg_w1_data_bits": 37}, False), ({"cfg_w1_crc": 0}, False),
    ({"cfg_w1_crc": 0, "cfg_spw_check": 0}, True),
    ({"cfg_w1_enable": 0, "cfg_w1_crc": 3, "cfg_w1_data_bits": 0, "cfg_spw_check": 0}, True),
])
def test_config_rules(change, valid):
    assert config_valid({**GOOD, **change}) == valid


def test_config_rules_one_word_build():
    one = dict(max_data_bits=(36,), word_crcs=((1,),))
    assert config_valid({**GOOD, "cfg_w0_data_bits": 36}, **one)
    assert not config_valid({**GOOD, "cfg_w0_data_bits": 37}, **one)
    assert not config_valid({**GOOD, "cfg_w0_crc": 2}, **one)     # no CRC-16 in that build


CHAIN = frames.PRESETS["chain_3"]


def test_chain_crc_status_rule():
    """Issue 26's chains: WORD0 when word 0 fails alone, WORD1 when word 0 passes and any later
    word fails, BOTH when word 0 and any later word fail; the counters follow word 0 and 'any
    later word'. One- and two-word frames keep their meaning."""
    ref = MasterReference()
    values = [frames.WordValue(0x1234567), frames.WordValue(0x1ABCD), frames.WordValue(0xABC)]
    starts = CHAIN.word_offsets()
    cases = {(): "OK", (0,): "CRC_ERROR_WORD0", (1,): "CRC_ERROR_WORD1",
             (2,): "CRC_ERROR_WORD1", (1, 2): "CRC_ERROR_WORD1", (0, 1): "CRC_ERROR_BOTH",
             (0, 2): "CRC_ERROR_BOTH", (0, 1, 2): "CRC_ERROR_BOTH"}
    for bad, status in cases.items():
        bits = frames.build_frame(CHAIN, values,
                                  frames.FrameFaults(flip_bits=tuple(starts[w] for w in bad)))
        v = ref.judge(CHAIN, bits)
        assert (v.name, v.crc_ok) == (status, tuple(w not in bad for w in range(3))), bad
        assert v.spw_mismatch == 0                   # a chain has no SPW check
        assert crc_counters(v.crc_ok) == tuple(f"crc_word{w}" for w in sorted(bad))
    assert [crc_status(ok) for ok in ((True,), (False,), (True, False), (False, False))] == [
        None, "CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH"]


CHAIN_GOOD = {"cfg_ma_half_period": 5, "cfg_delay_limit": 0, "cfg_spw_check": 0,
              "cfg_spw_tolerance": 1, **{f"cfg_w{w}_{k}": v for w in range(3) for k, v in (
                  ("data_bits", 8), ("nenw", 1), ("lc", 0), ("crc", 1))},
              "cfg_w1_enable": 1, "cfg_w2_enable": 1}


@pytest.mark.parametrize("change,valid", [
    ({}, True), ({"cfg_w2_enable": 0}, True), ({"cfg_w1_enable": 0, "cfg_w2_enable": 0}, True),
    ({"cfg_w1_enable": 0}, False),                       # word 2 without word 1
    ({"cfg_w2_data_bits": 25}, False), ({"cfg_w2_data_bits": 24}, True),
    ({"cfg_w2_crc": 2}, False),                          # CRC-16: not in this build
    ({"cfg_w0_lc": 1}, True), ({"cfg_w2_lc": 1}, True),
    ({"cfg_w0_lc": 1, "cfg_w2_lc": 1}, False),           # two LCs in one frame
    ({"cfg_w1_lc": 1, "cfg_w2_lc": 1}, False),
    ({"cfg_w0_lc": 1, "cfg_w2_lc": 1, "cfg_w2_enable": 0}, True),   # the disabled word's LC
])
def test_config_rules_chain_build(change, valid):
    chain = dict(max_data_bits=(40, 32, 24), word_crcs=((1,), (1,), (1,)))
    assert config_valid({**CHAIN_GOOD, **change}, **chain) == valid


def test_coverage_bins_and_holes():
    cov = Coverage()
    cov.sample(preset="resolute_c_36", ma_hz=10e6, round_trip_s=2e-6, fault="none",
               status=STATUS["OK"])
    cov.sample(preset=None, ma_hz=None, round_trip_s=None, fault="unplug",
               status=STATUS["CRC_ERROR_WORD0"])           # not legal for an unplug
    lines, illegal = report(cov)
    assert ("setup", "resolute_c_36", "10M", ">8 bits") in cov.hits
    assert illegal == [("fault", "unplug", "CRC_ERROR_WORD0")]
    assert delay_bin(0.04e-6, 10e6) == "<0.5 bit"
    assert sum(len(b) for b in bins().values()) == 16 * 5 * 4 + sum(map(len, LEGAL.values())) + len(STATUS)


def test_ssi_verdict_rules():
    """docs/ports.md, "SSI mode": NO_STOP first, then copy 1's CRC, then the copies compared."""
    from encoder_model.frames import CRC6
    from encoder_model.ssi import SsiFormat, ssi_bits
    from sim.shared.reference import ssi_verdict
    plain, ext = SsiFormat(12, gray=True), SsiFormat(9, nenw=True, crc=CRC6)
    for fmt in (plain, ext):
        word = ssi_bits(fmt, 0x0A5)
        n = len(word)
        flip = lambda bits, i: [b ^ (k == i) for k, b in enumerate(bits)]    # noqa: E731
        assert ssi_verdict(fmt, word + [0], double=False)[0] == "OK"
        assert ssi_verdict(fmt, word + [0] + word + [0], double=True)[0] == "OK"
        assert ssi_verdict(fmt, word + [1], double=False)[0] == "NO_STOP"
        assert ssi_verdict(fmt, flip(word, 3) + [0] + word + [1], double=True)[0] == "NO_STOP"
        # one bit of copy 1 wrong: undetectable without a CRC (a wrong reading), else the CRC
        status, reading = ssi_verdict(fmt, flip(word, 3) + [0], double=False)
        assert status == ("OK" if fmt is plain else "CRC_ERROR_WORD0")
        assert fmt is ext or reading.position != 0x0A5
        status, reading = ssi_verdict(fmt, flip(word, 3) + [0] + word + [0], double=True)
        assert status == ("SPW_MISMATCH" if fmt is plain else "CRC_ERROR_WORD0")
        # copy 2 or the separator wrong: the copies differ, copy 1 reported
        for bad in (word + [0] + flip(word, n - 1) + [0], word + [1] + word + [0]):
            status, reading = ssi_verdict(fmt, bad, double=True)
            assert (status, reading.position) == ("SPW_MISMATCH", 0x0A5)
