"""MaStop on Amaranth's simulator: MA has made every rising edge the frame needs.

Cycle conventions and where expected values come from: ``block_sim.py``. The frame needs
``start_slot + frame bits + 4`` rising edges (Start at rise ``start_slot + 2``, CDS, the word bits,
the stop bit: docs/timing.md); a word's bits are counted by the encoder model's
``WordFormat.total_bits`` (data, nE/nW, LC, CRC), a word after word 0 only when it is enabled
(``enables``: bit w for word w). The register
stages of the block's docstring: ``enough`` in clock ``t`` compares ``rises`` of clock ``t - 1``
with the target made from ``started`` / ``start_slot`` of clock ``t - 2``, from a configuration
held since the receiver's clear; ``clear`` in clock ``t - 1`` forces it to 0.
"""

import random

import pytest

from bissmaster.core.ma_stop import MaStop
from encoder_model.frames import CRC6, CRC16, CRC_NONE, PRESETS, CustomCrc, WordFormat
from master_contract import crc_config, crc_settings

from testkit.block_sim import run_clocks

#: Rising edges beyond Start's slot and the words: Start, CDS, the stop bit, and the two MA
#: rises before slot 0 (slot k is sent at rise k + 2).
RISES_AROUND_WORDS = 4


def _word_cfg(wf):
    return {"data_bits": wf.data_bits, "nenw": int(wf.nenw), "lc": int(wf.lc),
            "crc": crc_config(wf.crc)[0]}


RSH = PRESETS["resolute_fs_rsh"].words
# (case id, word formats as configured, word 1 enabled, frame bits)
FRAMES = [
    ("resolute_fs_rsh_both_words", RSH, 1, 96),
    ("resolute_fs_rsh_word0_only", RSH, 0, 44),
    ("cpw55_nenw_crc6_spw40_lc_crc16", (WordFormat(55), WordFormat(40, lc=True, crc=CRC16)), 1,
     63 + 64),
    ("7_bits_no_nenw_no_crc", (WordFormat(7, nenw=False, crc=CRC_NONE), RSH[1]), 0, 7),
]


def frame_bits(words, w1_enable=None, *, enables=None):
    """Bits of the enabled words: word 0 and word 1 if ``w1_enable``, or the words whose bit
    is set in ``enables`` (word 0 always)."""
    if enables is None:
        enables = 1 | w1_enable << 1
    return sum(wf.total_bits for w, wf in enumerate(words) if w == 0 or enables >> w & 1)


def scenario(words, w1_enable, start_slot, *, step, started_at, clears=4, extra=6,
             enables=None):
    """A cycle as the master runs it: the configuration set with the receiver's clear, MA rises
    every ``step`` clocks, Start seen in clock ``started_at``; until ``extra`` clocks past the
    target. ``enables`` (bit w: word w in the frame) replaces ``w1_enable`` for chains."""
    if enables is None:
        enables = 1 | w1_enable << 1
    target = start_slot + frame_bits(words, enables=enables) + RISES_AROUND_WORDS
    cfg = {"words": [_word_cfg(wf) for wf in words], "enables": enables,
           "crc_widths": [crc_settings(wf.crc)["width"] for wf in words]}
    steps = [{**cfg, "clear": 1, "rises": 0, "started": 0, "start_slot": 0}] * clears
    t, end = 0, None
    while end is None or t < end:
        rises = t // step
        started = int(t >= started_at)
        steps.append({**cfg, "clear": 0, "rises": rises, "started": started,
                      "start_slot": start_slot if started else 0})
        if end is None and rises >= target:
            end = max(t, started_at) + extra
        t += 1
    return steps, target


def reference(steps, targets):
    """``enough`` per clock; ``targets[t]`` is the frame's rises beyond Start's slot in clock t."""
    out = [0, 0]
    for t in range(2, len(steps)):
        two, one = steps[t - 2], steps[t - 1]
        out.append(int(two["started"] and not one["clear"]
                       and one["rises"] >= two["start_slot"] + targets[t - 2]))
    return out


def _run(words, steps):
    return [x["enough"] for x in run_clocks(MaStop(words), steps, ["enough"])]


def _first(trace):
    return trace.index(1) if 1 in trace else None


@pytest.mark.parametrize("words, w1_enable, bits", [f[1:] for f in FRAMES],
                         ids=[f[0] for f in FRAMES])
@pytest.mark.parametrize("start_slot", (1, 3, 17))
def test_ma_stop_enough_at_start_slot_plus_frame_bits_plus_4(words, w1_enable, bits, start_slot):
    assert frame_bits(words, w1_enable) == bits           # the cases as the old decoder test had
    # MA rises every clock (the sharpest test of the clock) and every 4 clocks (hp = 2).
    for step in (1, 4):
        steps, target = scenario(words, w1_enable, start_slot, step=step, started_at=5)
        trace = _run(2, steps)
        first_at_target = next(t for t, s in enumerate(steps) if not s["clear"]
                               and s["rises"] >= target)
        assert target == start_slot + bits + 4
        # The compare is registered: one clock after rises reaches the target.
        assert _first(trace) == first_at_target + 1, step
        assert all(trace[first_at_target + 1:]), step


def test_ma_stop_one_word_build():
    words = (WordFormat(36),)
    for start_slot in (1, 2, 9):
        steps, target = scenario(words, 0, start_slot, step=1, started_at=3)
        trace = _run(1, steps)
        assert target == start_slot + 36 + 2 + 6 + 4
        assert _first(trace) == next(t for t, s in enumerate(steps) if s["rises"] >= target) + 1


def test_ma_stop_start_seen_after_the_rises_it_needs():
    # A round trip longer than the frame: the rises are already there when Start is seen.
    # The flag follows Start by the block's two register stages.
    words = (WordFormat(7, nenw=False, crc=CRC_NONE), RSH[1])
    steps, _ = scenario(words, 0, 1, step=1, started_at=40)
    trace = _run(2, steps)
    assert _first(trace) == 4 + 40 + 2


def test_ma_stop_clear_forces_zero_and_restarts_the_sum():
    """A clear forces ``enough`` to 0 from the next clock and, in a build of N >= 2 words,
    restarts the frame's sum: one word per clock, two stages, then one clock for the target,
    so ``enough`` is back N + 4 clocks after the clear (one-word builds: the next clock but
    one)."""
    for n, words in ((2, RSH), (1, RSH[:1])):
        steps, _ = scenario(words, 1 if n == 2 else 0, 2, step=1, started_at=5, extra=14)
        c = len(steps) - 10
        steps[c] = {**steps[c], "clear": 1}
        trace = _run(n, steps)
        back = c + (n + 4 if n > 1 else 2)
        assert trace[c] == 1 and not any(trace[c + 1:back]) and all(trace[back:]), (n, trace[c:])


def test_ma_stop_random_formats_back_to_back():
    rng = random.Random(7500)
    steps, targets, firsts = [], [], []
    for _ in range(40):
        words = tuple(WordFormat(rng.randint(1, top), nenw=rng.random() < 0.5,
                                 lc=rng.random() < 0.3,
                                 crc=rng.choice((CRC_NONE, CRC6, CRC16,
                                                 CustomCrc(rng.randint(1, 16), 1))))
                      for top in (55, 40))
        w1 = rng.randrange(2)
        slot = rng.randint(1, 20)
        part, target = scenario(words, w1, slot, step=rng.choice((1, 2, 4)),
                                started_at=rng.randint(1, 30), clears=rng.randint(4, 6))
        firsts.append((len(steps), target))
        steps += part
        targets += [target - slot] * len(part)
    trace = _run(2, steps)
    assert trace == reference(steps, targets)
    for begin, target in firsts:
        assert trace[begin + 1] == 0                    # cleared in the cycle's first clocks


# -- SSI (docs/ports.md, "SSI mode"): N + 1 rises, 2 N + 2 with the double transmission --------

@pytest.mark.parametrize("bits, error, nenw, crc, double", [
    (13, 0, False, CRC_NONE, 0),            # 13-bit Gray singleturn: 14 rises
    (25, 1, False, CRC_NONE, 0),            # 25 bits and an error bit: 27
    (25, 1, False, CRC_NONE, 1),            # sent twice: 2 x 26 + 2 = 54
    (19, 0, True, CRC6, 0),                 # extended SSI: 19 + nE nW + CRC-6: 28
    (55, 1, False, CustomCrc(16, 0x1021), 1),
])
@pytest.mark.parametrize("step", (1, 4, 10))
def test_ma_stop_ssi_rises_from_the_first_whatever_start_says(bits, error, nenw, crc, double,
                                                              step):
    """SSI: ``enough`` one clock after ``rises`` reaches N + 1 (N: data, error bit, nE/nW,
    CRC) or 2 N + 2, counted from the first rise: ``started`` and ``start_slot`` are not
    waited for. The configuration is set with the receiver's clear, two clocks before it
    drops, as the master's latch is."""
    wf = WordFormat(bits, nenw=nenw, crc=crc)
    n = wf.total_bits + error
    target = 2 * n + 2 if double else n + 1
    cfg = {"words": [_word_cfg(wf), _word_cfg(RSH[1])], "enables": 1,
           "crc_widths": [crc_settings(crc)["width"], crc_settings(CRC16)["width"]], "ssi": 1,
           "ssi_error": error, "ssi_double": double, "started": 0, "start_slot": 0}
    steps = [{**cfg, "clear": 1, "rises": 0}] * 2
    # MA's first rise comes at least 2 clocks after the clear (a low phase of >= 2 clocks).
    steps += [{**cfg, "clear": 0, "rises": (t + 2) // step if t >= 2 else 0}
              for t in range(step * (target + 3))]
    trace = [x["enough"] for x in run_clocks(MaStop(2, ssi=True), steps, ["enough"])]
    first_at_target = next(t for t, s in enumerate(steps) if s["rises"] >= target)
    assert _first(trace) == first_at_target + 1
    assert all(trace[first_at_target + 1:])


# -- Chains: up to 8 words back to back, each counted when it is enabled -----------------------

@pytest.mark.parametrize("enables", (0b111, 0b011, 0b001))
def test_ma_stop_chain_of_three_counts_the_enabled_words(enables):
    """A chain of three slaves (40-bit CRC-6, 24-bit custom CRC-8 with LC, 13 bits without
    nE/nW or CRC): the target is the enabled words' bits, whatever the others hold."""
    words = (WordFormat(40), WordFormat(24, lc=True, crc=CustomCrc(8, 0x2F, start=0x5A)),
             WordFormat(13, nenw=False, crc=CRC_NONE))
    bits = {0b111: 48 + 40 + 13, 0b011: 48 + 40, 0b001: 48}[enables]
    assert frame_bits(words, enables=enables) == bits
    for step in (1, 4):
        steps, target = scenario(words, None, 5, step=step, started_at=7, enables=enables)
        assert target == 5 + bits + 4
        trace = _run(3, steps)
        first_at_target = next(t for t, s in enumerate(steps) if not s["clear"]
                               and s["rises"] >= target)
        assert _first(trace) == first_at_target + 1, step


def test_ma_stop_eight_longest_words():
    """Eight words of the longest kind (63 data bits, nE/nW, LC, CRC-16: 87 bits each): the
    frame's length (696 bits) needs more than the two-word build's 8 bits."""
    words = tuple(WordFormat(63, lc=True, crc=CRC16) for _ in range(8))
    rng = random.Random(8)
    steps, targets = [], []
    for enables in (0xFF, 0x7F, 0x01, 0xFF):
        slot = rng.randint(1, 9)
        part, target = scenario(words, None, slot, step=1, started_at=3, enables=enables)
        steps += part
        targets += [target - slot] * len(part)
    assert max(targets) == 8 * 87 + RISES_AROUND_WORDS
    trace = _run(8, steps)
    assert trace == reference(steps, targets)


@pytest.mark.parametrize("n", (2, 3, 8))
def test_ma_stop_reads_no_partial_sum(n):
    """The frame's length is summed one word per clock after the clear: with every rise
    already there and Start seen from the first clock (not possible on a line: the sum is
    ready long before; docs in MaStop._sum_words), ``enough`` still waits for the whole sum,
    N + 3 clocks after the clear drops, so a partial (shorter) sum never stops MA early."""
    words = tuple(WordFormat(63, lc=True, crc=CRC16) for _ in range(n))
    cfg = {"words": [_word_cfg(wf) for wf in words], "enables": 2**n - 1,
           "crc_widths": [crc_settings(wf.crc)["width"] for wf in words]}
    target = 1 + n * 87 + RISES_AROUND_WORDS
    steps = [{**cfg, "clear": 1, "rises": 0, "started": 0, "start_slot": 0}] * 3
    steps += [{**cfg, "clear": 0, "rises": rises, "started": 1, "start_slot": 1}
              for rises in [target - 1] * (n + 5) + [target] * 4]
    trace = _run(n, steps)
    drop = 3
    # The whole target is one more than the rises until they reach it: never enough before.
    assert not any(trace[:drop + n + 5]), trace
    assert trace[drop + n + 6:] == [1] * 3, trace
    # And with the rises at the target from the start: enough exactly N + 3 clocks after.
    steps = steps[:drop] + [{**s, "rises": target} for s in steps[drop:]]
    trace = _run(n, steps)
    assert trace.index(1) == drop + n + 3, trace
