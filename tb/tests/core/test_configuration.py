"""Configuration on Amaranth's simulator: the check (every rule of docs/ports.md), the latch while
idle, 0 -> protocol defaults, the NO_START limit and the word count.

Cycle conventions and where expected values come from: ``block_sim.py``. The rules and defaults
are written here from docs/ports.md ("Configuration") and docs/protocol.md (40 us break and
Ack limit, timeout twice the longest static slave timeout of 40 us, delay limit 0 = the most the
build measures).
"""

import random
from dataclasses import replace

import pytest

from bissmaster.core.configuration import Configuration
from bissmaster.layouts import config_layout
from bissmaster.params import Crc, MasterParams
from master_contract import CRC_CODE, CRC_MAX_WIDTH

from testkit.block_sim import pack, protocol_clocks, run_clocks, unpack

BUILDS = {
    "default": MasterParams(),
    # Each word with one CRC kind only; a delay limit port wider than the build's maximum.
    "narrow": MasterParams(sys_clk_hz=33_333_333, word_crcs=((Crc.CRC6,), (Crc.CRC16,)),
                           max_line_delay=1000, timer_width=16),
    "one_word": MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)),
    "no_custom": MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),), custom_crc=False),
    # A chain of three slaves (the chain preset's words).
    "chain": MasterParams(max_data_bits=(64, 32, 24), word_crcs=((Crc.CRC6,),) * 3),
}
#: The CRC codes each build accepts per word (``none`` always).
BUILT_CRCS = {
    "default": ({0, 1, 2}, {0, 1, 2}),
    "narrow": ({0, CRC_CODE["crc6"]}, {0, CRC_CODE["crc16"]}),
    "one_word": ({0, CRC_CODE["crc6"]},),
    "no_custom": ({0, CRC_CODE["crc6"]},),
    "chain": ({0, CRC_CODE["crc6"]},) * 3,
}
#: Builds that accept a custom CRC (code 3 with a width of 1..16).
CUSTOM = {"default", "narrow", "one_word", "chain"}
#: Builds with SSI mode (``cfg_ssi``): every build here (the default).
SSI = {"default", "narrow", "one_word", "no_custom", "chain"}


def reference_ok(build, cfg):
    """docs/ports.md, the "range / validity" column, for the build's limits."""
    p = BUILDS[build]
    crcs = BUILT_CRCS[build]
    cfg = unpack(config_layout(p), pack(config_layout(p), cfg))     # missing fields: 0

    def word_ok(w):
        word = cfg[f"w{w}"]
        custom = (build in CUSTOM and word["crc"] == CRC_CODE["custom"]
                  and 1 <= cfg[f"w{w}_crc"]["width"] <= CRC_MAX_WIDTH)
        return 1 <= word["data_bits"] <= p.max_data_bits[w] and (word["crc"] in crcs[w] or custom)

    ok = cfg["ma_half_period"] >= 2 and word_ok(0) and cfg["delay_limit"] <= p.max_line_delay
    on = enabled(p, cfg)
    if p.words >= 2:
        # Each enabled word valid, none after a disabled one, one LC per frame.
        ok = ok and all(word_ok(w) for w in range(1, p.words) if on[w])
        ok = ok and all(on[w - 1] for w in range(2, p.words) if on[w])
        ok = ok and sum(on[w] and cfg[f"w{w}"]["lc"] for w in range(p.words)) <= 1
        w1 = on[1]
        ok = ok and (not cfg["spw_check"] or (w1 and cfg["w1"]["data_bits"] <= cfg["w0"]["data_bits"]
                                              and cfg["w1"]["crc"] != CRC_CODE["none"]))
    if build in SSI and cfg["ssi"]:
        # docs/ports.md, "SSI mode": one word without LC, the error bit or nE/nW (not both),
        # no SPW check, a round trip up to the build's maximum line delay.
        ok = (ok and not cfg["w0"]["lc"] and not (cfg["ssi_error"] and cfg["w0"]["nenw"])
              and cfg["ssi_delay"] <= p.max_line_delay)
        if p.words >= 2:
            ok = ok and not any(on[1:]) and not cfg["spw_check"]
    return int(ok)


def enabled(p, cfg):
    """Per word: in the frame (word 0 always, word N with ``cfg_wN_enable``)."""
    return [1] + [cfg[f"w{w}_enable"] for w in range(1, p.words)]


def _word(bits, crc, *, nenw=1, lc=0):
    return {"data_bits": bits, "nenw": nenw, "lc": lc, "crc": CRC_CODE[crc]}


#: A valid BiSS Safety configuration (RESOLUTE FS RSH: CPW 36 + CRC-6, SPW 28 + LC + CRC-16).
BASE = {"ma_half_period": 5, "w0": _word(36, "crc6"), "w1_enable": 1,
        "w1": _word(28, "crc16", lc=1), "spw_check": 1, "spw_tolerance": 3}
BASE_ONE_WORD = {"ma_half_period": 5, "w0": _word(36, "crc6")}
#: A valid chain of three (40-bit CRC-6, 24-bit custom CRC-8, 16-bit CRC-6), no SPW check.
CHAIN = {"ma_half_period": 5, "w0": _word(40, "crc6"), "w1_enable": 1,
         "w1": _word(24, "custom"), "w1_crc": {"width": 8, "poly": 0x2F, "start": 0xA5},
         "w2_enable": 1, "w2": _word(16, "crc6")}


def _with(base, **changes):
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    for key, value in changes.items():
        if "__" in key:
            word, name = key.split("__")
            cfg.setdefault(word, {})[name] = value
        else:
            cfg[key] = value
    return cfg


NO_SPW = {"spw_check": 0}
# (case id, build, configuration, valid?)
RULES = [
    ("base", "default", BASE, 1),
    ("half_period_0", "default", _with(BASE, ma_half_period=0), 0),
    ("half_period_1", "default", _with(BASE, ma_half_period=1), 0),
    ("half_period_2", "default", _with(BASE, ma_half_period=2), 1),
    ("half_period_max", "default", _with(BASE, ma_half_period=65535), 1),
    ("w0_bits_0", "default", _with(BASE, w0__data_bits=0), 0),
    ("w0_bits_1", "default", _with(BASE, w0__data_bits=1, **NO_SPW), 1),
    ("w0_bits_55", "default", _with(BASE, w0__data_bits=55), 1),
    ("w0_bits_56", "default", _with(BASE, w0__data_bits=56), 0),
    ("w0_bits_63", "default", _with(BASE, w0__data_bits=63), 0),
    ("w1_bits_0", "default", _with(BASE, w1__data_bits=0, **NO_SPW), 0),
    ("w1_bits_1", "default", _with(BASE, w1__data_bits=1), 1),
    ("w1_bits_40", "default", _with(BASE, w0__data_bits=40, w1__data_bits=40), 1),
    ("w1_bits_41", "default", _with(BASE, w0__data_bits=41, w1__data_bits=41), 0),
    ("w1_bits_0_disabled", "default", _with(BASE, w1_enable=0, w1__data_bits=0, **NO_SPW), 1),
    ("w1_bits_63_disabled", "default", _with(BASE, w1_enable=0, w1__data_bits=63, **NO_SPW), 1),
    ("w0_crc_none", "default", _with(BASE, w0__crc=0), 1),
    ("w0_crc_16", "default", _with(BASE, w0__crc=2), 1),
    ("w0_custom_width_0", "default", _with(BASE, w0__crc=3), 0),
    ("w1_custom_width_0", "default", _with(BASE, w1__crc=3, **NO_SPW), 0),
    ("w0_custom_width_1", "default", _with(BASE, w0__crc=3, w0_crc__width=1), 1),
    ("w0_custom_width_16", "default", _with(BASE, w0__crc=3, w0_crc__width=16), 1),
    ("w0_custom_width_17", "default", _with(BASE, w0__crc=3, w0_crc__width=17), 0),
    ("w0_custom_width_31", "default", _with(BASE, w0__crc=3, w0_crc__width=31), 0),
    ("w1_custom_width_8_spw", "default", _with(BASE, w1__crc=3, w1_crc__width=8), 1),
    ("w1_custom_width_17_disabled", "default",
     _with(BASE, w1_enable=0, w1__crc=3, w1_crc__width=17, **NO_SPW), 1),
    ("narrow_w1_custom_width_6", "narrow", _with(BASE, w1__crc=3, w1_crc__width=6), 1),
    ("one_word_custom_width_5", "one_word", _with(BASE_ONE_WORD, w0__crc=3, w0_crc__width=5), 1),
    ("no_custom_code_3", "no_custom", _with(BASE_ONE_WORD, w0__crc=3, w0_crc__width=5), 0),
    ("no_custom_crc6", "no_custom", BASE_ONE_WORD, 1),
    ("w1_crc_3_disabled", "default", _with(BASE, w1_enable=0, w1__crc=3, **NO_SPW), 1),
    ("w1_crc_none_no_spw", "default", _with(BASE, w1__crc=0, **NO_SPW), 1),
    ("narrow_w0_crc6", "narrow", BASE, 1),
    ("narrow_w0_crc16_not_built", "narrow", _with(BASE, w0__crc=2), 0),
    ("narrow_w0_crc_none", "narrow", _with(BASE, w0__crc=0), 1),
    ("narrow_w1_crc6_not_built", "narrow", _with(BASE, w1__crc=1), 0),
    ("narrow_w1_crc6_disabled", "narrow", _with(BASE, w1_enable=0, w1__crc=1, **NO_SPW), 1),
    ("delay_limit_max_full_port", "default", _with(BASE, delay_limit=4095), 1),
    ("narrow_delay_limit_1000", "narrow", _with(BASE, delay_limit=1000), 1),
    ("narrow_delay_limit_1001", "narrow", _with(BASE, delay_limit=1001), 0),
    ("narrow_delay_limit_1023", "narrow", _with(BASE, delay_limit=1023), 0),
    ("lc_both_words", "default", _with(BASE, w0__lc=1), 0),
    ("lc_both_w1_disabled", "default", _with(BASE, w0__lc=1, w1_enable=0, **NO_SPW), 1),
    ("lc_word0_only", "default", _with(BASE, w0__lc=1, w1__lc=0), 1),
    ("lc_none", "default", _with(BASE, w1__lc=0), 1),
    ("spw_check_w1_disabled", "default", _with(BASE, w1_enable=0), 0),
    ("spw_bits_equal_cpw", "default", _with(BASE, w1__data_bits=36), 1),
    ("spw_bits_over_cpw", "default", _with(BASE, w1__data_bits=37), 0),
    ("spw_over_cpw_no_check", "default", _with(BASE, w1__data_bits=37, **NO_SPW), 1),
    ("spw_crc_none", "default", _with(BASE, w1__crc=0), 0),
    ("spw_crc6", "default", _with(BASE, w1__crc=1), 1),
    ("one_word_base", "one_word", BASE_ONE_WORD, 1),
    ("one_word_bits_36", "one_word", _with(BASE_ONE_WORD, w0__data_bits=36), 1),
    ("one_word_bits_37", "one_word", _with(BASE_ONE_WORD, w0__data_bits=37), 0),
    ("one_word_bits_0", "one_word", _with(BASE_ONE_WORD, w0__data_bits=0), 0),
    ("one_word_crc16_not_built", "one_word", _with(BASE_ONE_WORD, w0__crc=2), 0),
    ("one_word_lc", "one_word", _with(BASE_ONE_WORD, w0__lc=1), 1),
    ("one_word_half_period_1", "one_word", _with(BASE_ONE_WORD, ma_half_period=1), 0),
    ("one_word_delay_limit_4095", "one_word", _with(BASE_ONE_WORD, delay_limit=4095), 1),
    # SSI mode: the Safety base is refused (two words, LC, SPW check); one word is not.
    ("ssi_safety_base", "default", _with(BASE, ssi=1), 0),
    ("ssi_safety_base_off", "default", _with(BASE, ssi=0, ssi_error=1, ssi_delay=4095), 1),
    ("ssi_one_word", "default", _with(BASE, ssi=1, w1_enable=0, w1__lc=0, **NO_SPW), 1),
    ("ssi_w1_enable", "default", _with(BASE, ssi=1, w1__lc=0, **NO_SPW), 0),
    ("ssi_spw_check", "default", _with(BASE, ssi=1, w1_enable=0, w1__lc=0), 0),
    ("ssi_lc", "one_word", _with(BASE_ONE_WORD, ssi=1, w0__lc=1), 0),
    ("ssi_error_bit", "one_word", _with(BASE_ONE_WORD, ssi=1, ssi_error=1, w0__nenw=0), 1),
    ("ssi_error_bit_and_nenw", "one_word", _with(BASE_ONE_WORD, ssi=1, ssi_error=1), 0),
    ("ssi_error_bit_and_nenw_biss", "one_word", _with(BASE_ONE_WORD, ssi_error=1), 1),
    ("ssi_double_error_low", "one_word",
     _with(BASE_ONE_WORD, ssi=1, ssi_double=1, ssi_error=1, ssi_error_low=1, w0__nenw=0), 1),
    ("ssi_delay_4095", "default", _with(BASE_ONE_WORD, ssi=1, ssi_delay=4095), 1),
    ("narrow_ssi_delay_1000", "narrow", _with(BASE_ONE_WORD, ssi=1, ssi_delay=1000), 1),
    ("narrow_ssi_delay_1001", "narrow", _with(BASE_ONE_WORD, ssi=1, ssi_delay=1001), 0),
    ("narrow_ssi_delay_1001_biss", "narrow", _with(BASE_ONE_WORD, ssi_delay=1001), 1),
    # A chain of three: words in order, each within its build maximum, one LC.
    ("chain_base", "chain", CHAIN, 1),
    ("chain_w2_without_w1", "chain", _with(CHAIN, w1_enable=0), 0),
    ("chain_w1_only", "chain", _with(CHAIN, w2_enable=0), 1),
    ("chain_w0_only", "chain", _with(CHAIN, w1_enable=0, w2_enable=0), 1),
    ("chain_w0_bits_64", "chain", _with(CHAIN, w0__data_bits=64), 1),     # a 7-bit field
    ("chain_w0_bits_65", "chain", _with(CHAIN, w0__data_bits=65), 0),
    ("chain_w0_bits_127", "chain", _with(CHAIN, w0__data_bits=127), 0),
    ("chain_w1_bits_33", "chain", _with(CHAIN, w1__data_bits=33), 0),
    ("chain_w2_bits_24", "chain", _with(CHAIN, w2__data_bits=24), 1),
    ("chain_w2_bits_25", "chain", _with(CHAIN, w2__data_bits=25), 0),
    ("chain_w2_bits_25_disabled", "chain", _with(CHAIN, w2__data_bits=25, w2_enable=0), 1),
    ("chain_w2_bits_0", "chain", _with(CHAIN, w2__data_bits=0), 0),
    ("chain_w2_crc16_not_built", "chain", _with(CHAIN, w2__crc=CRC_CODE["crc16"]), 0),
    ("chain_w2_custom_width_17", "chain", _with(CHAIN, w2__crc=3, w2_crc__width=17), 0),
    ("chain_lc_on_w2", "chain", _with(CHAIN, w2__lc=1), 1),
    ("chain_lc_on_w0_and_w2", "chain", _with(CHAIN, w0__lc=1, w2__lc=1), 0),
    ("chain_lc_on_w1_and_w2", "chain", _with(CHAIN, w1__lc=1, w2__lc=1), 0),
    ("chain_lc_on_w0_and_w2_disabled", "chain", _with(CHAIN, w0__lc=1, w2__lc=1, w2_enable=0),
     1),
    ("chain_ssi_w2", "chain", _with(CHAIN, ssi=1, w1_enable=0), 0),
    ("chain_ssi_one_word", "chain", _with(CHAIN, ssi=1, w1_enable=0, w2_enable=0), 1),
]


@pytest.mark.parametrize("build, cfg, valid", [r[1:] for r in RULES], ids=[r[0] for r in RULES])
def test_configuration_rule_registered_one_clock_after_live_input(build, cfg, valid):
    p = BUILDS[build]
    layout = config_layout(p)
    assert reference_ok(build, cfg) == valid          # the table agrees with the reference
    good = {1: BASE_ONE_WORD, 2: BASE, 3: CHAIN}[p.words]
    dut = Configuration(p)
    # The case alone for one clock, between valid configurations; then held for two clocks.
    seq = [good, good, cfg, good, cfg, cfg, good, good]
    trace = run_clocks(dut, [{"live": pack(layout, c)} for c in seq], ["ok"])
    assert [x["ok"] for x in trace[1:]] == [reference_ok(build, c) for c in seq[:-1]]


@pytest.mark.parametrize("build", BUILDS)
def test_configuration_check_random_sweep(build):
    p = BUILDS[build]
    layout = config_layout(p)
    rng = random.Random(7100 + len(build))
    cfgs = []
    for _ in range(600):
        cfg = unpack(layout, rng.getrandbits(layout.size))
        # Make the interesting values frequent: small data bits, valid CRC codes, word 1 on.
        for w in range(p.words):
            word = cfg[f"w{w}"]
            word["data_bits"] = rng.choice((word["data_bits"], rng.randint(0, 3),
                                            rng.randint(1, p.max_data_bits[w]),
                                            p.max_data_bits[w] + rng.randint(-2, 1)))
            word["crc"] = rng.choice((word["crc"], rng.randrange(3)))
            word["lc"] &= rng.randrange(2)          # rarer: two LCs in a frame are refused
            if f"w{w}_crc" in cfg:
                cfg[f"w{w}_crc"]["width"] = rng.choice((cfg[f"w{w}_crc"]["width"], 0, 1, 16, 17))
        cfg["ma_half_period"] = rng.choice((cfg["ma_half_period"], rng.randrange(4)))
        cfg["delay_limit"] = rng.choice((cfg["delay_limit"], p.max_line_delay + rng.randint(-1, 1)))
        if "ssi" in cfg:        # SSI often off (else most random configurations are refused)
            cfg["ssi"] &= rng.randrange(2)
            cfg["ssi_delay"] = rng.choice((cfg["ssi_delay"], p.max_line_delay + rng.randint(-1, 1)))
        cfgs.append(cfg)
    trace = run_clocks(Configuration(p), [{"live": pack(layout, c)} for c in cfgs], ["ok"])
    expected = [reference_ok(build, c) for c in cfgs]
    assert [x["ok"] for x in trace[1:]] == expected[:-1]
    assert 0.05 < sum(expected) / len(expected) < 0.95


#: The protocol defaults of docs/ports.md, per build.
def _defaults(p):
    return {"ack_limit": protocol_clocks(40, p.sys_clk_hz),
            "timeout_limit": protocol_clocks(2 * 40, p.sys_clk_hz),
            "delay_limit": p.max_line_delay}


def test_configuration_defaults_at_100_mhz_are_the_documented_clocks():
    assert _defaults(BUILDS["default"]) == {"ack_limit": 4000, "timeout_limit": 8000,
                                             "delay_limit": 4095}


def _random_steps(p, seed, clocks):
    """Random configurations, one per clock (limits 0 now and then: the defaults; odd half
    periods), idle in runs (a cycle holds the latch for several clocks) and from clock 0."""
    layout = config_layout(p)
    rng = random.Random(seed)
    steps = []
    for t in range(clocks):
        cfg = unpack(layout, rng.getrandbits(layout.size))
        for name in ("ack_limit", "timeout_limit", "delay_limit"):
            if rng.random() < 0.3:
                cfg[name] = 0
        if rng.random() < 0.2:
            cfg["ma_half_period"] = rng.choice((0, 1, 2, 65535))
        if p.timer_width == 16:
            # Keep the Ack limit + one MA period within 17 bits (see the RTL-bug test below).
            cfg["ma_half_period"] &= 0x3FFF
        idle = 1 if t < 3 else int(rng.random() < (0.8 if steps[-1]["idle"] else 0.15))
        steps.append({"live": pack(layout, cfg), "idle": idle})
    return steps


@pytest.mark.parametrize("build", BUILDS)
def test_configuration_latch_while_idle_defaults_no_start_limit_word_count(build):
    p = BUILDS[build]
    layout = config_layout(p)
    defaults = _defaults(p)
    steps = _random_steps(p, 7200 + len(build), 400)
    outputs = ["cycle", "ack_limit", "timeout_limit", "delay_limit", "no_start_limit", "word_count"]
    trace = run_clocks(Configuration(p), steps, outputs)

    assert any(not s["idle"] for s in steps) and any(s["idle"] for s in steps)
    latched = None
    for t in range(1, len(steps)):
        prev = steps[t - 1]
        if prev["idle"]:
            latched = prev["live"]
        got = trace[t]
        assert got["cycle"] == latched, t
        cfg = unpack(layout, latched)
        limits = {name: cfg[name] or defaults[name] for name in defaults}
        assert {name: got[name] for name in defaults} == limits, t
        assert got["word_count"] == sum(enabled(p, cfg)), t
        if t >= 2:
            # Registered from the latched Ack limit and half period of the clock before.
            before = trace[t - 1]
            hp = unpack(layout, before["cycle"])["ma_half_period"]
            assert got["no_start_limit"] == before["ack_limit"] + 2 * hp + 1, t


@pytest.mark.parametrize("build", ["default", "chain"])
def test_configuration_held_build_reads_live_and_latches_the_limits(build):
    """A ``config_hold`` build (the bus tops; docs/bus.md, "Configuration writes") copies
    nothing: ``cycle`` is the live configuration in the same clock (its writer changes it only
    while the core is idle and held), the word count follows it, and the resolved limits are
    still latched while idle."""
    p = replace(BUILDS[build], config_hold=True)
    layout = config_layout(p)
    defaults = _defaults(p)
    steps = _random_steps(p, 7210 + len(build), 200)
    outputs = ["cycle", "ack_limit", "timeout_limit", "delay_limit", "word_count"]
    trace = run_clocks(Configuration(p), steps, outputs)
    latched = None
    for t in range(1, len(steps)):
        got = trace[t]
        assert got["cycle"] == steps[t]["live"], t
        assert got["word_count"] == sum(enabled(p, unpack(layout, steps[t]["live"]))), t
        if steps[t - 1]["idle"]:
            latched = unpack(layout, steps[t - 1]["live"])
        assert {name: got[name] for name in defaults} == {
            name: latched[name] or defaults[name] for name in defaults}, t


def test_configuration_no_start_limit_one_clock_after_the_latch():
    """The block's contract: the Ack limit + one MA period + 1 clock. The clock is not a port
    limit: the controller sees Start one clock later after its decision than it sees the Ack's
    slot-0 decision (the register between sampler and decoder), so the port limit of
    docs/ports.md (Start decided within A + 2 x hp + 1 clocks of slot 0's decision) is kept;
    test_limits.py checks that boundary on the ports."""
    p = BUILDS["default"]
    layout = config_layout(p)
    a = pack(layout, _with(BASE, ack_limit=100, ma_half_period=7))
    b = pack(layout, _with(BASE, ack_limit=0, ma_half_period=65535))
    steps = [{"live": a, "idle": 1}] * 3 + [{"live": b, "idle": 1}] + [{"live": a, "idle": 0}] * 3
    trace = run_clocks(Configuration(p), steps, ["ack_limit", "no_start_limit"])
    assert [x["ack_limit"] for x in trace] == [0, 100, 100, 100, 4000, 4000, 4000]
    assert [x["no_start_limit"] for x in trace] == [0, 1, 115, 115, 115, 4000 + 2 * 65535 + 1,
                                                    4000 + 2 * 65535 + 1]


#: The named CRCs as docs/protocol.md section 6 gives them: (width, register polynomial, start,
#: sent inverted).
NAMED = {CRC_CODE["crc6"]: (6, 0x03, 0, 1), CRC_CODE["crc16"]: (16, 0x90D9, 0, 1)}


@pytest.mark.parametrize("build", BUILDS)
def test_configuration_crc_widths_resolved_from_the_code_and_latched_while_idle(build):
    """``crc_widths``: per word the width of the CRC the engine runs. A named code gives its
    protocol CRC's width, code 3 the word's ``cfg_wN_crc_width`` (in builds with custom CRCs),
    code 0 width 0; latched while idle like ``cycle``. One-word builds: ``crc``, the whole CRC
    resolved (width, polynomial, start, inversion), latched alike. (Builds of more words: the
    engine resolves the rest, test_crc_engine.py.)"""
    p = BUILDS[build]
    layout = config_layout(p)
    rng = random.Random(7300 + len(build))
    steps = []
    for t in range(300):
        cfg = unpack(layout, rng.getrandbits(layout.size))
        for w in range(p.words):
            cfg[f"w{w}"]["crc"] = rng.choice(sorted(BUILT_CRCS[build][w])
                                             + ([CRC_CODE["custom"]] if build in CUSTOM else []))
        idle = 1 if t < 2 else int(rng.random() < 0.6)
        steps.append({"live": pack(layout, cfg), "idle": idle})
    one_word = p.words == 1
    trace = run_clocks(Configuration(p), steps, ["crc_widths"] + (["crc"] if one_word else []))
    latched = None
    for t in range(1, len(steps)):
        if steps[t - 1]["idle"]:
            latched = unpack(layout, steps[t - 1]["live"])
        got = trace[t]["crc_widths"]
        for w in range(p.words):
            code = latched[f"w{w}"]["crc"]
            if code == CRC_CODE["custom"]:
                c = latched[f"w{w}_crc"]
                want = (c["width"], c["poly"], c["start"], c["inverted"])
            else:
                want = NAMED.get(code, (0, 0, 0, 0))
            assert (got >> (5 * w)) & 31 == want[0], (t, w)
            if one_word:
                # The whole CRC, resolved (width, polynomial, start, inverted).
                entry = trace[t]["crc"]
                assert (entry & 31, (entry >> 5) & 0xFFFF, (entry >> 21) & 0xFFFF, entry >> 37) \
                    == want, t


@pytest.mark.parametrize("ack_limit, half_period", ((65535, 65535), (60000, 40000), (1000, 65535)))
def test_configuration_no_start_limit_fits_on_a_16_bit_timer_build(ack_limit, half_period):
    """Fixed RTL bug: ``no_start_limit`` was ``timer_width + 1`` bits, but the Ack limit
    (``timer_width`` bits) plus one MA period (2 x a 16-bit half period) needs
    ``max(timer_width, 17) + 1``. With ``timer_width = 16`` (``--timer-width 16``, the preset
    ``biss-c-lean``) a sum >= 2**17 wraps, and NO_START fires long before the documented
    A + 2 x ``cfg_ma_half_period`` + 1 clocks (docs/ports.md, ``cfg_ack_limit``). (The cycle timer of
    LimitTimers, also ``timer_width + 1`` bits and saturating at 2**17 - 1, could not reach such a
    limit either.)"""
    p = MasterParams(timer_width=16)
    layout = config_layout(p)
    cfg = pack(layout, _with(BASE, ack_limit=ack_limit, ma_half_period=half_period))
    trace = run_clocks(Configuration(p), [{"live": cfg, "idle": 1}] * 3, ["no_start_limit"])
    assert trace[-1]["no_start_limit"] == ack_limit + 2 * half_period + 1
