"""FieldEnds on Amaranth's simulator: the current and the following word's field ends,
registered from their settings.

Cycle conventions and where expected values come from: ``block_sim.py``. A word on the line is
its data bits, nE and nW (or, word 0 in SSI mode, one error bit), LC, CRC (docs/ports.md,
docs/frames.md): the bit indices below count from 0 at the word's first data bit, and the
encoder model's ``WordFormat.total_bits`` gives the word's length.
"""

import random

import pytest
from amaranth.hdl import Module, ResetInserter
from amaranth.lib import wiring
from amaranth.lib.wiring import In

from bissmaster.core.field_ends import FIELD_ENDS, FieldEnds
from encoder_model.frames import CRC6, CRC16, CRC_NONE, CustomCrc, WordFormat
from master_contract import crc_config, crc_settings

from testkit.block_sim import run_clocks, unpack

INDEX_MOD = 2**7        # bit indices are 7 bits (the longest word: 63 + 2 + 6 + 16 bits)


def expected(wf, error=0):
    """The field ends of ``wf`` as bit indices (docs/ports.md's word layout)."""
    nenw = 2 * wf.nenw + error                  # nE/nW, or the SSI error bit
    lc = 6 * wf.lc
    return {"data_end_p1": wf.data_bits + 1, "data_end_m1": wf.data_bits - 1,
            "nenw_end_m1": (wf.data_bits + nenw - 1) % INDEX_MOD,
            "lc_end_m1": (wf.data_bits + nenw + lc - 1) % INDEX_MOD,
            "word_end_m1": wf.total_bits + error - 1, "data_at0": 1, "lc_at0": 0}


def _word(wf):
    return {"data_bits": wf.data_bits, "nenw": int(wf.nenw), "lc": int(wf.lc),
            "crc": crc_config(wf.crc)[0]}


def _random_word(rng, top):
    return WordFormat(rng.randint(1, top), nenw=rng.random() < 0.5, lc=rng.random() < 0.4,
                      crc=rng.choice((CRC_NONE, CRC6, CRC16,
                                      CustomCrc(rng.randint(1, 16), 1))))


def _ends(raw):
    return unpack(FIELD_ENDS, raw)


class _ClearedFieldEnds(wiring.Component):
    """FieldEnds with its reset as the input ``clear``: the master holds the decoder, and the
    block in it, in reset before every frame."""

    def __init__(self, *args, **kwargs):
        self.inner = FieldEnds(*args, **kwargs)
        super().__init__({**self.inner.signature.members, "clear": In(1)})

    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = ResetInserter(self.clear)(self.inner)
        for name, member in self.inner.signature.members.items():
            outer, inner = getattr(self, name), getattr(self.inner, name)
            m.d.comb += inner.eq(outer) if member.flow == In else outer.eq(inner)
        return m


def test_field_ends_one_word_one_clock_after_the_settings():
    """One word: ``current`` follows the settings one clock later, in every clock."""
    rng = random.Random(7901)
    steps, wanted = [], []
    for _ in range(80):
        wf = _random_word(rng, 63)
        steps.append({"words": [_word(wf)], "crc_widths": [crc_settings(wf.crc)["width"]]})
        wanted.append(expected(wf))
    trace = run_clocks(FieldEnds(1), steps, ["current"])
    for t in range(1, len(steps)):
        assert _ends(trace[t]["current"]) == wanted[t - 1], t


@pytest.mark.parametrize("words, error_bit", [(2, False), (3, False), (8, False), (2, True)],
                         ids=["two_words", "three_words", "eight_words", "two_words_ssi"])
def test_field_ends_current_and_following_word_through_frames(words, error_bit):
    """More words: ``begin`` (after a reset) loads word 0 and word 1; each ``advance`` moves on
    by one (the block counts the words itself); both hold between, and are valid in
    the clock after, so words may follow each other in consecutive clocks. Random settings per
    frame, frames of 1..``words`` words, 0..2 clocks between events."""
    rng = random.Random(7900 + words + 10 * error_bit)
    dut = _ClearedFieldEnds(words, error_bit=error_bit)
    steps, wanted = [], []          # wanted[t]: (current, following or None) after step t
    for _ in range(40):
        wfs = [_random_word(rng, 63) for _ in range(words)]
        error = int(error_bit and not wfs[0].nenw and rng.random() < 0.5)
        base = {"words": [_word(wf) for wf in wfs],
                "crc_widths": [crc_settings(wf.crc)["width"] for wf in wfs],
                **({"error_bit": error} if error_bit else {}),
                "begin": 0, "advance": 0, "clear": 0}
        ends = [expected(wf, error if w == 0 else 0) for w, wf in enumerate(wfs)]

        def state(k):
            return ends[k], (ends[k + 1] if k + 1 < words else None)

        for _ in range(rng.randrange(3)):       # settings change while no frame runs
            steps.append(dict(base))
            wanted.append(None)
        steps.append(dict(base, clear=1))       # the decoder's reset before the frame
        wanted.append(None)
        steps.append(dict(base, begin=1))
        wanted.append(state(0))
        for k in range(rng.randint(1, words) - 1):
            for _ in range(rng.randrange(3)):
                steps.append(dict(base))
                wanted.append(state(k))
            steps.append(dict(base, advance=1))
            wanted.append(state(k + 1))
    trace = run_clocks(dut, steps, ["current", "following"])
    checked = 0
    for t in range(1, len(steps)):
        if wanted[t - 1] is None:
            continue
        current, following = wanted[t - 1]
        assert _ends(trace[t]["current"]) == current, t
        if following is not None:
            assert _ends(trace[t]["following"]) == following, t
        checked += 1
    assert checked >= 60


def test_field_ends_longest_word_fits_the_index():
    """63 data bits, nE/nW, LC and CRC-16: 87 bits, the last at index 86."""
    wf = WordFormat(63, lc=True, crc=CRC16)
    step = {"words": [_word(wf)], "crc_widths": [crc_settings(CRC16)["width"]]}
    trace = run_clocks(FieldEnds(1), [step] * 2, ["current"])
    assert _ends(trace[1]["current"])["word_end_m1"] == 86 == wf.total_bits - 1
