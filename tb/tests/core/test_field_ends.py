"""FieldEnds on Amaranth's simulator: each word's field ends, registered from its settings.

Cycle conventions and where expected values come from: ``block_sim.py``. A word on the line is
its data bits, nE and nW (or, word 0 in SSI mode, one error bit), LC, CRC (docs/ports.md,
docs/frames.md): the bit indices below count from 0 at the word's first data bit, and the
encoder model's ``WordFormat.total_bits`` gives the word's length.
"""

import random

import pytest

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


@pytest.mark.parametrize("words, error_bit", [(1, False), (3, False), (2, True)],
                         ids=["one_word", "three_words", "two_words_ssi"])
def test_field_ends_one_clock_after_the_settings(words, error_bit):
    rng = random.Random(7900 + words)
    dut = FieldEnds(words, error_bit=error_bit)
    steps, wanted = [], []
    for _ in range(60):
        wfs = [_random_word(rng, 63) for _ in range(words)]
        error = int(error_bit and not wfs[0].nenw and rng.random() < 0.5)
        step = {"words": [_word(wf) for wf in wfs],
                "crc_widths": [crc_settings(wf.crc)["width"] for wf in wfs]}
        if error_bit:
            step["error_bit"] = error
        steps.append(step)
        wanted.append([expected(wf, error if w == 0 else 0) for w, wf in enumerate(wfs)])
    trace = run_clocks(dut, steps, ["ends"])
    for t in range(1, len(steps)):
        raw = trace[t]["ends"]
        got = [unpack(FIELD_ENDS, raw >> (w * FIELD_ENDS.size) & (2**FIELD_ENDS.size - 1))
               for w in range(words)]
        assert got == wanted[t - 1], t


def test_field_ends_longest_word_fits_the_index():
    """63 data bits, nE/nW, LC and CRC-16: 87 bits, the last at index 86."""
    wf = WordFormat(63, lc=True, crc=CRC16)
    step = {"words": [_word(wf)], "crc_widths": [crc_settings(CRC16)["width"]]}
    trace = run_clocks(FieldEnds(1), [step] * 2, ["ends"])
    assert unpack(FIELD_ENDS, trace[1]["ends"])["word_end_m1"] == 86 == wf.total_bits - 1
