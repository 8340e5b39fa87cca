"""FrameVerdict on Amaranth's simulator: exhaustive over its (small) input space.

Cycle conventions and where expected values come from: ``block_sim.py``. The rules (the
block's docstring, docs/ports.md "Status codes"): a frame's status is the lowest code that
applies, CRC (both, word 0, word 1) > sign of life > SPW mismatch > NOISY_LINE > DELAY_JUMP >
UNCONFIRMED > OK (the line checks last, then the confirmation after a fault); word 1 not in the frame
counts as CRC-good; the LC is judged only for a reported frame whose LC-carrying word passed its
CRC; the SPW check only between two CRC-good words with the check and word 1 enabled; without a
frame the controller's fault status passes through; ``valid`` is a reported frame with OK;
``passed`` one with OK or UNCONFIRMED.
"""

import itertools

import pytest

from bissmaster.core.frame_verdict import FrameVerdict
from bissmaster.layouts import config_layout
from bissmaster.params import Crc, MasterParams
from master_contract import STATUS

from testkit.block_sim import pack, run_clocks

TWO = MasterParams()
ONE = MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),))
#: A chain of three slaves: "word 1" in the CRC statuses is any word after word 0.
CHAIN = MasterParams(max_data_bits=(40, 32, 24), word_crcs=((Crc.CRC6,),) * 3)
OUTPUTS = ["doubtful", "lc_check", "report", "status", "valid", "word_crc_ok", "lc_repeat",
           "lc_skip", "lc_zero", "spw_mismatch", "crc_error", "clean", "passed"]
#: The statuses that end a cycle without a frame (docs/ports.md: codes 6..12).
FAULT_NAMES = [name for name, code in STATUS.items()
               if STATUS["NO_ACK"] <= code <= STATUS["NO_STOP"]]


def _inputs(p, *, w0_lc=0, w1_lc=0, w1_enable=0, w2_lc=0, w2_enable=0, spw_check=0, ssi=0,
            report_frame=0, fault=0, fault_status=0, crc_ok=0, seen=(0, 0, 0), spw_match=0,
            noisy=0, delay_jump=0, unconfirmed=0, copy_mismatch=0):
    cfg = {"ma_half_period": 5, "w0": {"data_bits": 20, "lc": w0_lc, "crc": 1}, "ssi": ssi}
    if p.words >= 2:
        cfg.update(w1_enable=w1_enable, spw_check=spw_check,
                   w1={"data_bits": 20, "lc": w1_lc, "crc": 2})
    if p.words >= 3:
        cfg.update(w2_enable=w2_enable, w2={"data_bits": 20, "lc": w2_lc, "crc": 1})
    step = {"cfg": pack(config_layout(p), cfg), "report_frame": report_frame, "fault": fault,
            "fault_status": fault_status, "crc_ok": crc_ok, "lc_repeat_seen": seen[0],
            "lc_skip_seen": seen[1], "lc_zero_seen": seen[2], "noisy": noisy,
            "delay_jump": delay_jump, "unconfirmed": unconfirmed,
            "copy_mismatch": copy_mismatch}
    if p.words >= 2:
        step["spw_match"] = spw_match
    return step


def reference(p, s, cfg):
    """Every output for the inputs ``s`` and the settings ``cfg`` they were made from."""
    two = p.words >= 2
    rf = s["report_frame"]
    on = [1] + [cfg.get(f"w{w}_enable", 0) for w in range(1, p.words)]
    w1 = two and on[1]
    # Per word: CRC good, or not in the frame.
    oks = [int(bool((s["crc_ok"] >> w) & 1 or not on[w])) for w in range(p.words)]
    ok0 = oks[0]
    ok1 = int(all(oks[1:])) if two else ok0         # "word 1": every word after word 0
    lc_words = [w for w in range(p.words) if on[w] and cfg.get(f"w{w}_lc")]
    lc_word_ok = oks[lc_words[0]] if lc_words else None     # None: no LC in the frame
    lc_check = int(bool(rf and lc_word_ok))
    flags = [lc_check & s[f"lc_{f}_seen"] for f in ("repeat", "skip", "zero")]
    # The plausibility fault: the SPW check, or an SSI double transmission's copies differing
    # (docs/ports.md, "SSI mode"), only with the CRCs good.
    spw = int(bool(ok0 and ok1 and (two and cfg.get("spw_check") and w1 and not s["spw_match"]
                                    or cfg.get("ssi") and s["copy_mismatch"])))
    if not ok0 and not ok1:
        status = STATUS["CRC_ERROR_BOTH"] if two else STATUS["CRC_ERROR_WORD0"]
    elif not ok0:
        status = STATUS["CRC_ERROR_WORD0"]
    elif not ok1:
        status = STATUS["CRC_ERROR_WORD1"]
    elif any(flags):
        status = STATUS["SIGN_OF_LIFE"]
    elif spw:
        status = STATUS["SPW_MISMATCH"]
    elif s["noisy"]:
        status = STATUS["NOISY_LINE"]
    elif s["delay_jump"]:
        status = STATUS["DELAY_JUMP"]
    elif s["unconfirmed"]:
        status = STATUS["UNCONFIRMED"]
    else:
        status = STATUS["OK"]
    ok_bits = sum(ok << w for w, ok in enumerate(oks))
    # The frame will not be OK (the pause after it): the same verdict, reported or not.
    seen_any = any(s[f"lc_{f}_seen"] for f in ("repeat", "skip", "zero"))
    doubtful = int(not ok0 or not ok1 or bool(lc_word_ok and seen_any) or bool(spw)
                   or bool(s["noisy"]) or bool(s["delay_jump"]))
    # To the round-trip check: every check but its own passes (the LC flags as reported).
    clean = int(bool(ok0 and ok1 and not spw and not s["noisy"] and not any(flags)))
    out = {"doubtful": doubtful, "clean": clean, "lc_check": lc_check, "report": int(bool(rf or s["fault"])),
           "valid": int(bool(rf and status == STATUS["OK"])), "word_crc_ok": ok_bits,
           "passed": int(bool(rf and status in (STATUS["OK"], STATUS["UNCONFIRMED"]))),
           "lc_repeat": flags[0], "lc_skip": flags[1], "lc_zero": flags[2],
           "crc_error": (~ok_bits & (2**p.words - 1)) if rf else 0}
    if rf:
        out["status"] = status
        out["spw_mismatch"] = spw
    elif s["fault"]:
        out["status"] = s["fault_status"]
    return out


def _settings(p):
    """Every valid combination of the settings the verdict reads (docs/ports.md: one LC per
    frame; the SPW check needs word 1)."""
    ssi = [{"ssi": 1}]              # SSI: one word, no LC, no SPW check
    if p.words == 1:
        return [{"w0_lc": lc} for lc in (0, 1)] + ssi
    out = []
    w2 = (0, 1) if p.words >= 3 else (0,)
    for w0_lc, w1_lc, w1_enable, spw_check, w2_lc, w2_enable in itertools.product(
            (0, 1), (0, 1), (0, 1), (0, 1), w2, w2):
        lcs = w0_lc + (w1_enable and w1_lc) + (w2_enable and w2_lc)
        if lcs > 1 or (spw_check and not w1_enable) or (w2_enable and not w1_enable):
            continue
        cfg = {"w0_lc": w0_lc, "w1_lc": w1_lc, "w1_enable": w1_enable, "spw_check": spw_check}
        if p.words >= 3:
            cfg.update(w2_lc=w2_lc, w2_enable=w2_enable)
        out.append(cfg)
    return out + ssi


def _check(p, cases):
    trace = run_clocks(FrameVerdict(p), [_inputs(p, **cfg, **kw) for cfg, kw in cases], OUTPUTS)
    for (cfg, kw), got in zip(cases, trace):
        s = _inputs(p, **cfg, **kw)
        want = reference(p, s, cfg)
        assert {k: got[k] for k in want} == want, (cfg, kw)


@pytest.mark.parametrize("p", (TWO, ONE, CHAIN), ids=("two_words", "one_word", "chain_of_three"))
@pytest.mark.parametrize("report_frame", (1, 0), ids=("reported", "not_yet_reported"))
def test_frame_verdict_reported_frame_exhaustive(p, report_frame):
    cases = []
    # The line checks, the confirmation and SSI's copies do not depend on the word count:
    # every combination for one and two words; for the chain (what it adds is the CRCs and
    # the LC word) none of them, or one at a time.
    # The same for the three LC flags (judged alike): none, one, all.
    later = (itertools.product((0, 1), repeat=4) if p.words <= 2
             else [(0, 0, 0, 0), (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)])
    seens = (itertools.product((0, 1), repeat=3) if p.words <= 2
             else [(0, 0, 0), (0, 1, 0), (1, 1, 1)])
    for cfg in _settings(p):
        for crc_ok, seen, match, (noisy, jump, unconfirmed, copies) in itertools.product(
                range(2**p.words), list(seens),
                (0, 1) if p.words >= 2 else (0,), list(later)):
            cases.append((cfg, {"report_frame": report_frame, "crc_ok": crc_ok, "seen": seen,
                                "spw_match": match, "noisy": noisy, "delay_jump": jump,
                                "unconfirmed": unconfirmed, "copy_mismatch": copies}))
    _check(p, cases)


@pytest.mark.parametrize("p", (TWO, ONE, CHAIN), ids=("two_words", "one_word", "chain_of_three"))
@pytest.mark.parametrize("name", FAULT_NAMES)
def test_frame_verdict_fault_passes_through(p, name):
    # Whatever the frame inputs say: no LC judged, no CRC event, not valid.
    cases = []
    for cfg in _settings(p):
        for crc_ok, seen, match in itertools.product(range(2**p.words), ((0, 0, 0), (1, 1, 1)),
                                                     (0, 1)):
            cases.append((cfg, {"fault": 1, "fault_status": STATUS[name], "crc_ok": crc_ok,
                                "seen": seen, "spw_match": match, "unconfirmed": 1}))
    _check(p, cases)


def test_frame_verdict_nothing_reported_in_a_quiet_clock():
    cases = [(cfg, {"crc_ok": crc_ok, "seen": (1, 1, 1)}) for cfg in _settings(TWO)
             for crc_ok in range(4)]
    _check(TWO, cases)


# Hand-picked (case id, settings, inputs, status name): the priority, spelled out.
PRIORITY = [
    ("crc_both_over_all", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1},
     {"crc_ok": 0b00, "seen": (1, 1, 1)}, "CRC_ERROR_BOTH"),
    ("crc_word0_over_lc_and_spw", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1},
     {"crc_ok": 0b10, "seen": (1, 0, 0)}, "CRC_ERROR_WORD0"),
    ("crc_word1_over_lc_in_word0", {"w1_enable": 1, "w0_lc": 1, "spw_check": 1},
     {"crc_ok": 0b01, "seen": (0, 1, 0)}, "CRC_ERROR_WORD1"),
    ("word1_off_counts_good", {"w1_enable": 0}, {"crc_ok": 0b01}, "OK"),
    ("word1_off_crc0_bad_is_word0_only", {"w1_enable": 0}, {"crc_ok": 0b00}, "CRC_ERROR_WORD0"),
    ("lc_over_spw", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1},
     {"crc_ok": 0b11, "seen": (0, 0, 1)}, "SIGN_OF_LIFE"),
    ("lc_in_word0_with_bad_word1_not_judged_as_lc", {"w1_enable": 1, "w0_lc": 1},
     {"crc_ok": 0b01, "seen": (1, 0, 0)}, "CRC_ERROR_WORD1"),
    ("spw_mismatch", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1}, {"crc_ok": 0b11},
     "SPW_MISMATCH"),
    ("spw_match_ok", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1},
     {"crc_ok": 0b11, "spw_match": 1}, "OK"),
    ("no_spw_check_ok", {"w1_enable": 1, "w1_lc": 1}, {"crc_ok": 0b11}, "OK"),
    ("lc_seen_but_no_lc_configured", {"w1_enable": 1}, {"crc_ok": 0b11, "seen": (1, 1, 1)}, "OK"),
    ("unconfirmed_only_when_every_check_passes", {"w1_enable": 1, "w1_lc": 1, "spw_check": 1},
     {"crc_ok": 0b11, "spw_match": 1, "unconfirmed": 1}, "UNCONFIRMED"),
    ("delay_jump_over_unconfirmed", {"w1_enable": 1}, {"crc_ok": 0b11, "delay_jump": 1,
                                                       "unconfirmed": 1}, "DELAY_JUMP"),
    ("crc_over_unconfirmed", {"w1_enable": 0}, {"crc_ok": 0b00, "unconfirmed": 1},
     "CRC_ERROR_WORD0"),
    ("ssi_copies_differ", {"ssi": 1}, {"crc_ok": 0b01, "copy_mismatch": 1}, "SPW_MISMATCH"),
    ("ssi_copies_differ_crc_first", {"ssi": 1}, {"crc_ok": 0b00, "copy_mismatch": 1},
     "CRC_ERROR_WORD0"),
    ("copies_ignored_in_biss", {"w1_enable": 0}, {"crc_ok": 0b01, "copy_mismatch": 1}, "OK"),
]


@pytest.mark.parametrize("cfg, kw, name", [c[1:] for c in PRIORITY], ids=[c[0] for c in PRIORITY])
def test_frame_verdict_priority_cases(cfg, kw, name):
    trace = run_clocks(FrameVerdict(TWO), [_inputs(TWO, report_frame=1, **cfg, **kw)], OUTPUTS)
    assert trace[0]["status"] == STATUS[name]
    assert trace[0]["valid"] == int(name == "OK")


# The chain's statuses spelled out: "word 1" is any word after word 0.
CHAIN_CASES = [
    ("word2_bad_is_word1", {"w1_enable": 1, "w2_enable": 1}, {"crc_ok": 0b011},
     "CRC_ERROR_WORD1", 0b011),
    ("word0_and_word2_bad_is_both", {"w1_enable": 1, "w2_enable": 1}, {"crc_ok": 0b010},
     "CRC_ERROR_BOTH", 0b010),
    ("word2_off_counts_good", {"w1_enable": 1}, {"crc_ok": 0b011}, "OK", 0b111),
    ("lc_in_word2_judged_when_word2_good", {"w1_enable": 1, "w2_enable": 1, "w2_lc": 1},
     {"crc_ok": 0b111, "seen": (0, 1, 0)}, "SIGN_OF_LIFE", 0b111),
    ("lc_in_word2_not_judged_when_word1_bad", {"w1_enable": 1, "w2_enable": 1, "w2_lc": 1},
     {"crc_ok": 0b101, "seen": (0, 1, 0)}, "CRC_ERROR_WORD1", 0b101),
]


@pytest.mark.parametrize("cfg, kw, name, word_crc_ok", [c[1:] for c in CHAIN_CASES],
                         ids=[c[0] for c in CHAIN_CASES])
def test_frame_verdict_chain_cases(cfg, kw, name, word_crc_ok):
    trace = run_clocks(FrameVerdict(CHAIN), [_inputs(CHAIN, report_frame=1, **cfg, **kw)],
                       OUTPUTS)
    assert trace[0]["status"] == STATUS[name]
    assert trace[0]["word_crc_ok"] == word_crc_ok
    assert trace[0]["valid"] == int(name == "OK")
