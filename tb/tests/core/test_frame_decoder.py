"""FrameDecoder on Amaranth's simulator: fields, strobes and per-word CRC verdicts of model frames.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.frame_decoder import FrameDecoder
from bissmaster.params import Crc, MasterParams
from encoder_model.frames import (CRC16, CRC_NONE, PRESETS, CustomCrc, FrameFaults, FrameFormat,
                                  WordFormat, WordValue, to_signed, bp3, build_frame, word_bits)
from master_contract import crc_config, crc_settings

from testkit.block_sim import simulate


def _cfg(wf):
    if wf is None:
        return {"data_bits": 0, "nenw": 0, "lc": 0, "crc": 0}
    return {"data_bits": wf.data_bits, "nenw": int(wf.nenw), "lc": int(wf.lc),
            "crc": crc_config(wf.crc)[0], "gray": int(wf.gray), "signed": int(wf.signed)}


def _crc(wf):
    """The word's CRC as the decoder gets it: its resolved settings (a one-word build's
    ``crc``; the width alone in ``crc_widths``) and its custom settings (``cfg_wN_crc_*``, 0
    for a named CRC)."""
    crc = "none" if wf is None else wf.crc
    return crc_settings(crc), crc_config(crc)[1]


def _random_values(fmt, rng):
    values = []
    cpw = rng.randrange(1 << fmt.words[0].data_bits)
    for i, w in enumerate(fmt.words):
        pos = cpw if i == 0 else (cpw >> fmt.spw_shift)
        values.append(WordValue(pos, rng.randrange(2), rng.randrange(2),
                                rng.randint(1, 63) if w.lc else None))
    return values


def _decode(params, fmt, values, *, acks, faults=None, hw_word1=None, seed=0, frame=None):
    """Feed Ack zeros, the model frame and the stop bit, samples 1..4 clocks apart with junk on
    ``bit`` in between; then two more samples (SLO back high). Returns (trace, sample cycles).
    ``frame``: the bits after Ack, when they are not ``build_frame(fmt, values, faults)`` (a
    chain: ``fmt`` then only needs its ``words``)."""
    rng = random.Random(seed)
    if frame is None:
        frame = build_frame(fmt, values, faults)
    slots = [0] * acks + frame + [0] + [1, 1]
    dut = FrameDecoder(params)
    cfgs = [_cfg(w) for w in fmt.words]
    crcs = [_crc(w) for w in fmt.words]
    if params.words == 2 and len(cfgs) == 1:
        cfgs.append(_cfg(hw_word1))
        crcs.append(_crc(hw_word1))
    fields = ["done", "stopped", "frame_end", "started", "start_slot", "slots", "cds", "ne", "nw", "lc",
              "cpw_top", "crc_ok"] + [f"data{w}" for w in range(params.words)]
    trace, sample_cycles = [], []

    async def tb(ctx):
        ctx.set(dut.words, cfgs)
        ctx.set(dut.crc_widths, [resolved["width"] for resolved, _ in crcs])
        if params.words == 1:
            ctx.set(dut.word0_crc, crcs[0][0])
        elif params.custom_crc:
            ctx.set(dut.customs, [custom for _, custom in crcs])
        ctx.set(dut.word_count, len(fmt.words))
        cycle = 0

        def record():
            trace.append({f: ctx.get(getattr(dut, f)) for f in fields})

        for bit in slots + [None] * 2:
            for _ in range(rng.randrange(4)):
                ctx.set(dut.sample, 0)
                ctx.set(dut.bit, rng.randrange(2))
                record()
                await ctx.tick()
                cycle += 1
            if bit is None:
                continue
            ctx.set(dut.sample, 1)
            ctx.set(dut.bit, bit)
            sample_cycles.append(cycle)
            record()
            await ctx.tick()
            cycle += 1
        ctx.set(dut.sample, 0)
        record()

    simulate(dut, tb)
    return trace, sample_cycles, frame


#: Two words with CRCs of the catalogue kind: CRC-8/SMBUS-like with a start value, sent plain;
#: a 12-bit CRC (0x80F) over a word with LC, with a start value, sent inverted.
CUSTOM_TWO = FrameFormat("custom_two", (WordFormat(30, crc=CustomCrc(8, 0x07, 0xA5, False)),
                                        WordFormat(20, lc=True, crc=CustomCrc(12, 0x80F, 0x123, True))))

DECODER_CASES = {
    # name: (params, format, acks, faults, hw word 1 config when the frame has one word)
    "resolute_fs_rsh": (MasterParams(), PRESETS["resolute_fs_rsh"], 1, None, None),
    "resolute_fs_rsh_cds1_acks3": (MasterParams(), PRESETS["resolute_fs_rsh"], 3,
                                   FrameFaults(cds=1), None),
    "evolute_36_word1_off": (MasterParams(), PRESETS["evolute_36"], 2, None,
                             WordFormat(28, lc=True, crc=CRC16)),
    "bp3_1": (MasterParams(), PRESETS["bp3_1"], 1, None, None),
    "bp3_55": (MasterParams(), bp3(55), 4, None, None),
    "bp3_55_one_word_hw": (MasterParams(max_data_bits=(55,), word_crcs=((Crc.CRC6,),)), bp3(55),
                           2, FrameFaults(cds=1), None),
    "evolute_36_one_word_hw": (MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)),
                               PRESETS["evolute_36"], 1, None, None),
    # Gray-coded words: reported in binary, the CPW's top bits too (the SPW check's input).
    "gray_two_words": (MasterParams(), FrameFormat("gray", (
        WordFormat(36, gray=True), WordFormat(28, lc=True, crc=CRC16, gray=True))), 1, None, None),
    "gray_word0_only_55": (MasterParams(), FrameFormat("gray55", (WordFormat(55, gray=True),)),
                           2, None, WordFormat(20, gray=True)),
    # Custom CRCs: each word its own width, polynomial, start value and inversion.
    "custom_crc_two_words": (MasterParams(), CUSTOM_TWO, 2, None, None),
    "custom_crc16_start_one_word_hw": (
        MasterParams(max_data_bits=(40,), word_crcs=((Crc.CRC6,),)),
        FrameFormat("custom16", (WordFormat(40, crc=CustomCrc(16, 0x1021, 0xFFFF, False)),)),
        1, None, None),
    # Signed words: sign-extended to the register's width (not the CPW's top bits: cpw_top).
    "signed_two_words": (MasterParams(), FrameFormat("signed", (
        WordFormat(36, signed=True), WordFormat(28, lc=True, crc=CRC16, signed=True))), 1, None,
        None),
    "signed_gray_13_one_word_hw": (MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)),
                                   FrameFormat("sgray13", (WordFormat(13, gray=True, signed=True),)),
                                   2, None, None),
    "signed_55_in_55": (MasterParams(), FrameFormat("s55", (WordFormat(55, signed=True),)), 1,
                        None, WordFormat(20, signed=True)),
    "custom_crc3_word1_off": (MasterParams(),
                              FrameFormat("custom3", (WordFormat(9, crc=CustomCrc(3, 0x3, 0, True)),)),
                              1, None, WordFormat(5, crc=CustomCrc(11, 0x385, 0x1A, False))),
}


@pytest.mark.parametrize("case", list(DECODER_CASES))
def test_frame_decoder_fields_and_strobes(case):
    params, fmt, acks, faults, hw_word1 = DECODER_CASES[case]
    rng = random.Random(case)
    for rep in range(3):
        values = _random_values(fmt, rng)
        if rep < 2:         # fixed extremes: all-ones (rep 0) or the top bit alone (rep 1),
            # errors asserted, LC 63
            values = [WordValue((1 << w.data_bits) - 1 if rep == 0 else 1 << (w.data_bits - 1),
                                0, 1, 63 if w.lc else None) for w in fmt.words]
            if fmt.is_safety:
                values[1].position = values[0].position >> fmt.spw_shift
        trace, samples, frame = _decode(params, fmt, values, acks=acks, faults=faults,
                                        hw_word1=hw_word1, seed=rep)
        n_words = len(fmt.words)
        last_bit_sample = samples[acks + len(frame) - 1]
        stop_sample = samples[acks + len(frame)]
        assert [c for c, x in enumerate(trace) if x["done"]] == [last_bit_sample + 1]
        assert [c for c, x in enumerate(trace) if x["stopped"]] == [stop_sample + 1]
        # The frame's end in BiSS: its last word bit (``done``), not the stop bit.
        assert [c for c, x in enumerate(trace) if x["frame_end"]] == [last_bit_sample + 1]
        # started in the cycle after the Start sample, not before.
        start_sample = samples[acks]
        assert [x["started"] for x in trace] == \
            [0] * (start_sample + 1) + [1] * (len(trace) - start_sample - 1)

        for when in (last_bit_sample + 1, len(trace) - 1):    # at done, and held afterwards
            x = trace[when]
            assert x["start_slot"] == acks
            assert x["cds"] == (faults.cds if faults else 0)
            for w, (wf, v) in enumerate(zip(fmt.words, values)):
                # A signed word: its value (the field's two's complement) in the register's
                # whole width; an unsigned one: the field with zeros above it.
                want = (to_signed(v.position, wf.data_bits) if wf.signed else v.position) \
                    % 2**params.max_data_bits[w]
                assert x[f"data{w}"] == want, (when, w)
                assert (x["ne"] >> w) & 1 == v.ne and (x["nw"] >> w) & 1 == v.nw
                if wf.lc:
                    assert x["lc"] == v.lc
            if not any(wf.lc for wf in fmt.words):
                assert x["lc"] == 0
            assert x["crc_ok"] & ((1 << n_words) - 1) == (1 << n_words) - 1
            if params.words == 2:
                if n_words == 2:
                    d1 = fmt.words[1].data_bits
                else:
                    d1 = hw_word1.data_bits if hw_word1 else 0
                expected_top = values[0].position >> max(0, fmt.words[0].data_bits - d1)
                assert x["cpw_top"] == expected_top
        assert trace[-1]["slots"] == acks + len(frame) + 3
        # Nothing that ends the frame happens before its last bit.
        assert not any(x["done"] or x["stopped"] for x in trace[:last_bit_sample + 1])


@pytest.mark.parametrize("fmt", (PRESETS["resolute_fs_rsh"], CUSTOM_TWO), ids=("rsh", "custom"))
@pytest.mark.parametrize("word", (0, 1))
def test_frame_decoder_flipped_bit_fails_only_that_words_crc(word, fmt):
    rng = random.Random(7000 + word)
    values = _random_values(fmt, rng)
    first = 2 + (0 if word == 0 else fmt.words[0].total_bits)
    flip = first + rng.randrange(fmt.words[word].total_bits)
    trace, samples, frame = _decode(MasterParams(), fmt, values, acks=1,
                                    faults=FrameFaults(flip_bits=(flip,)), seed=3)
    done = [c for c, x in enumerate(trace) if x["done"]]
    assert done == [samples[1 + len(frame) - 1] + 1]
    assert trace[done[0]]["crc_ok"] == (0b10 if word == 0 else 0b01)



# -- Chains: the words of several slaves back to back after one Start and CDS -----------------

#: A chain of three (docs/frames.md): a 40-bit word with CRC-6; a 24-bit word with LC and a
#: CRC-8 (0x2F) with a start value, sent inverted; a 13-bit word without nE/nW and a CRC-4
#: (0x3) with a start value, sent plain.
CHAIN_PARAMS = MasterParams(max_data_bits=(40, 32, 24), word_crcs=((Crc.CRC6,),) * 3)
CHAIN = (WordFormat(40), WordFormat(24, lc=True, crc=CustomCrc(8, 0x2F, 0xA5, True)),
         WordFormat(13, nenw=False, crc=CustomCrc(4, 0x3, 0x9, False)))


def _chain_bits(words, values, flip=None):
    """Start, CDS 0, then each word as the model sends it; ``flip``: one bit index inverted."""
    bits = [1, 0]
    for wf, v in zip(words, values):
        bits += word_bits(wf, v)
    if flip is not None:
        bits[flip] ^= 1
    return bits


def _chain_values(words, rng):
    return [WordValue(rng.randrange(1 << wf.data_bits), *((rng.randrange(2), rng.randrange(2))
                      if wf.nenw else (1, 1)), rng.randint(1, 63) if wf.lc else None)
            for wf in words]


def _chain_decode(params, words, values, *, flip=None, seed=0, acks=2):
    frame = _chain_bits(words, values, flip)
    trace, samples, _ = _decode(params, _Words(words), values, acks=acks, seed=seed,
                                frame=frame)
    done = [c for c, x in enumerate(trace) if x["done"]]
    assert done == [samples[acks + len(frame) - 1] + 1]
    return trace[done[0]], trace[-1]


class _Words:
    """What ``_decode`` reads of a frame format when it is given the frame: its words."""
    def __init__(self, words):
        self.words = tuple(words)


@pytest.mark.parametrize("rep", range(4))
def test_frame_decoder_chain_of_three_every_field(rep):
    rng = random.Random(7600 + rep)
    values = _chain_values(CHAIN, rng)
    at_done, held = _chain_decode(CHAIN_PARAMS, CHAIN, values, seed=rep, acks=1 + rep)
    for x in (at_done, held):
        for w, (wf, v) in enumerate(zip(CHAIN, values)):
            assert x[f"data{w}"] == v.position, w
            assert (x["ne"] >> w & 1, x["nw"] >> w & 1) == (v.ne, v.nw), w
        assert x["lc"] == values[1].lc
        assert x["crc_ok"] == 0b111


@pytest.mark.parametrize("word", range(3))
def test_frame_decoder_chain_flipped_bit_fails_only_that_words_crc(word):
    rng = random.Random(7700 + word)
    values = _chain_values(CHAIN, rng)
    first = 2 + sum(wf.total_bits for wf in CHAIN[:word])
    for flip in rng.sample(range(first, first + CHAIN[word].total_bits), 3):
        at_done, _ = _chain_decode(CHAIN_PARAMS, CHAIN, values, flip=flip, seed=flip)
        assert at_done["crc_ok"] == 0b111 & ~(1 << word), flip


def test_frame_decoder_eight_words_random_formats():
    """Eight words of random formats (up to 64 data bits, any CRC of 0..16 bits, LC on one):
    each word's fields and CRC verdict, and a flipped bit failing only its word."""
    params = MasterParams(max_data_bits=(64,) * 8, word_crcs=((Crc.CRC6, Crc.CRC16),) * 8)
    rng = random.Random(7800)
    for rep in range(3):
        lc_word = rng.randrange(8)
        words = tuple(WordFormat(rng.choice((64, rng.randint(1, 64))), nenw=rng.random() < 0.7,
                                 lc=w == lc_word,
                                 crc=rng.choice((CRC_NONE, CRC16, CustomCrc(
                                     rng.randint(1, 16), 1, 0)))
                                 if w % 2 else CustomCrc(6, 0x03, rng.randrange(64), True))
                      for w in range(8))
        values = _chain_values(words, rng)
        at_done, _ = _chain_decode(params, words, values, seed=rep)
        for w, v in enumerate(values):
            assert at_done[f"data{w}"] == v.position, (rep, w)
            assert (at_done["ne"] >> w & 1, at_done["nw"] >> w & 1) == (v.ne, v.nw)
        assert at_done["lc"] == values[lc_word].lc
        assert at_done["crc_ok"] == 0xFF
        word = rng.choice([w for w in range(8) if words[w].crc != CRC_NONE])
        first = 2 + sum(wf.total_bits for wf in words[:word])
        flip = first + rng.randrange(words[word].total_bits)
        at_done, _ = _chain_decode(params, words, values, flip=flip, seed=rep)
        assert at_done["crc_ok"] == 0xFF & ~(1 << word), (rep, word)


def test_frame_decoder_64_bit_words():
    """Words of 64 data bits (iC-MB4's longest; a 7-bit ``data_bits``): two of them with CRC-16
    and CRC-6, the corners (all ones, the top bit alone, 1) and random values, every bit in
    place; a flipped top bit fails only its word."""
    params = MasterParams(max_data_bits=(64, 64), word_crcs=((Crc.CRC6, Crc.CRC16),) * 2)
    words = (WordFormat(64, crc=CRC16), WordFormat(64, lc=True))
    rng = random.Random(7900)
    corners = [(1 << 64) - 1, 1 << 63, 1]
    for rep, position in enumerate(corners + [rng.getrandbits(64) for _ in range(3)]):
        values = [WordValue(position, 1, 0), WordValue(rng.getrandbits(64), 0, 1, rep + 1)]
        at_done, held = _chain_decode(params, words, values, seed=rep)
        for x in (at_done, held):
            assert (x["data0"], x["data1"]) == (values[0].position, values[1].position), rep
            assert x["crc_ok"] == 0b11 and x["lc"] == rep + 1
    for word in (0, 1):
        first = 2 + sum(wf.total_bits for wf in words[:word])
        at_done, _ = _chain_decode(params, words, values, flip=first, seed=word)
        assert at_done["crc_ok"] == 0b11 & ~(1 << word), word
