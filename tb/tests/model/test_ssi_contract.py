"""master_contract's SSI facts are consistent, and the SSI scenarios are wired as they say: in
the regression, on the builds with cfg_ssi only (collected nowhere else, never skipped)."""

import ast

import master_contract as mc
from encoder_model.ssi import SsiFormat
from encoder_model.frames import CRC6
from sim.shared import discovery, runner

from testkit import REPO


def test_ssi_statuses_split_every_status():
    assert set(mc.SSI_STATUSES) | set(mc.SSI_NEVER) == set(mc.STATUS)
    assert not set(mc.SSI_STATUSES) & set(mc.SSI_NEVER)
    assert set(mc.SSI_FIELD_STATUSES) <= set(mc.SSI_STATUSES)
    for name in ("NO_ACK", "NO_START", "DELAY_RANGE", "DELAY_JUMP", "SIGN_OF_LIFE",
                 "CRC_ERROR_WORD1"):
        assert name in mc.SSI_NEVER


def test_pulse_rule_and_word_length():
    assert mc.ssi_word_bits(13, 0, 0, 0) == 13 and mc.ssi_ma_pulses(13, False) == 14
    assert mc.ssi_word_bits(25, 1, 0, 0) == 26 and mc.ssi_ma_pulses(26, True) == 54
    assert mc.ssi_word_bits(19, 0, 1, 6) == 27
    # the contract's N is the model's word length
    for fmt in (SsiFormat(13), SsiFormat(25, error_bits=1), SsiFormat(19, nenw=True, crc=CRC6)):
        assert mc.ssi_word_bits(fmt.data_bits, fmt.error_bits, fmt.nenw,
                                fmt.crc_bits) == fmt.total_bits
        assert mc.ssi_ma_pulses(fmt.total_bits, False) == fmt.clocks


def test_flags_rule():
    assert mc.ssi_ne_nw(error_active=True) == (0, 1)
    assert mc.ssi_ne_nw(error_active=False) == (1, 1)
    assert mc.ssi_ne_nw(nenw=(0, 1)) == (0, 1)
    assert mc.ssi_ne_nw() is None


def test_vote_margin():
    assert mc.ssi_vote_margin(5) == 1 and mc.ssi_vote_margin(50) == 24


def test_bad_configs_are_port_overrides():
    assert all(set(o) <= {"cfg_w0_lc", "cfg_w1_enable", "cfg_spw_check", "cfg_ssi_error",
                          "cfg_w0_nenw"} for o in mc.SSI_BAD_CONFIGS)
    assert len(mc.SSI_BAD_CONFIGS) == 4


def test_ssi_scenarios_run_in_the_regression_on_ssi_builds_only():
    assert runner.SSI_SCENARIOS in runner.REGRESSION_SCENARIOS
    found = discovery.scenarios(runner.SSI_SCENARIOS)
    assert len(found) >= 8
    for s in found:
        assert set(s.builds) <= set(mc.SSI_BUILDS) == {discovery.DEFAULT_BUILD}, s
        assert s.name.startswith("ssi_"), s.name
    # no scenario skips itself at run time
    source = (REPO / "sim" / "scenarios" / "ssi.py").read_text()
    assert "skip" not in source.lower()
    names = {n.id if isinstance(n, ast.Name) else getattr(n, "attr", "")
             for n in ast.walk(ast.parse(source))}
    assert "SkipTest" not in names
