"""FrameDecoder in SSI mode on Amaranth's simulator (docs/ports.md, "SSI mode").

The word's bits come from the SSI encoder model (tb/encoder_model/ssi.py: position, Gray,
error bits) or, for "extended SSI" (nE, nW and a CRC after the position), from the BiSS
model's word (frames.word_bits): the expected fields are the model's values, never the RTL's.
Cycle conventions: ``testkit/block_sim.py``.
"""

import random

import pytest

from bissmaster.core.frame_decoder import FrameDecoder
from bissmaster.params import MasterParams
from encoder_model.frames import CRC6, WordFormat, WordValue, word_bits
from encoder_model.ssi import ACTIVE_HIGH, ACTIVE_LOW, SsiFormat, ssi_bits
from master_contract import crc_config, crc_settings

from testkit.block_sim import simulate

PARAMS = MasterParams()
FIELDS = ["done", "stopped", "frame_end", "stop_bit", "started", "start_slot", "ne", "nw",
          "crc_ok", "mismatch", "data0"]


def _run(word_cfg, crc, line, *, error=0, error_low=0, double=0, seed=0):
    """Feed ``line`` (every slot of the frame after the latch, the bit after the word included)
    and two idle-high slots, samples 1..4 clocks apart with junk on ``bit`` between; returns
    (trace, sample cycles)."""
    rng = random.Random(seed)
    dut = FrameDecoder(PARAMS)
    trace, samples = [], []

    async def tb(ctx):
        ctx.set(dut.words, [word_cfg, {"data_bits": 0, "nenw": 0, "lc": 0, "crc": 0}])
        # The resolved width; the settings as custom ones (read only with the custom code).
        ctx.set(dut.crc_widths, [crc["width"], 0])
        if PARAMS.custom_crc:
            ctx.set(dut.customs, [crc, crc_settings("none")])
        ctx.set(dut.word_count, 1)
        for name, value in (("ssi_error", error), ("ssi_error_low", error_low),
                            ("ssi_double", double)):
            ctx.set(getattr(dut, name), value)
        # The word settings a clock before ``ssi`` (the decoder's contract: in the master the
        # configuration is latched while idle, before the decoder leaves its reset).
        trace.append({f: ctx.get(getattr(dut, f)) for f in FIELDS})
        await ctx.tick()
        ctx.set(dut.ssi, 1)
        cycle = 1
        for bit in list(line) + [1, 1]:
            for _ in range(rng.randint(1, 4)):
                ctx.set(dut.sample, 0)
                ctx.set(dut.bit, rng.randrange(2))
                trace.append({f: ctx.get(getattr(dut, f)) for f in FIELDS})
                await ctx.tick()
                cycle += 1
            ctx.set(dut.sample, 1)
            ctx.set(dut.bit, bit)
            samples.append(cycle)
            trace.append({f: ctx.get(getattr(dut, f)) for f in FIELDS})
            await ctx.tick()
            cycle += 1
        ctx.set(dut.sample, 0)
        trace.append({f: ctx.get(getattr(dut, f)) for f in FIELDS})

    simulate(dut, tb)
    return trace, samples


def _word(fmt):
    return {"data_bits": fmt.data_bits, "nenw": 0, "lc": 0, "crc": 0, "gray": int(fmt.gray),
            "signed": 0}


def _strobes(trace, name):
    return [c for c, x in enumerate(trace) if x[name]]


SSI_CASES = {
    # name: (SsiFormat, error polarity setting)
    "gray_13": SsiFormat(13, gray=True),
    "binary_25_error_high": SsiFormat(25, error_bits=1, error_polarity=(ACTIVE_HIGH,)),
    "binary_25_error_low": SsiFormat(25, error_bits=1, error_polarity=(ACTIVE_LOW,)),
    "gray_55_error_high": SsiFormat(55, gray=True, error_bits=1),
    "binary_1": SsiFormat(1),
}


@pytest.mark.parametrize("case", list(SSI_CASES))
def test_ssi_word_fields_and_strobes(case):
    """Position (binary, Gray decoded), the error bit as nE (0: active, either polarity), nW 1,
    ``started`` with slot 0's decision, ``done`` after the last word bit, ``stopped`` after
    the bit after it, no mismatch."""
    fmt = SSI_CASES[case]
    rng = random.Random(case)
    low = int(fmt.error_bits == 1 and fmt.error_polarity[0] == ACTIVE_LOW)
    for rep in range(4):
        position = ((1 << fmt.data_bits) - 1, 1 << (fmt.data_bits - 1), 0,
                    rng.randrange(1 << fmt.data_bits))[rep]
        errors = (rep % 2 == 0,) * fmt.error_bits
        line = ssi_bits(fmt, position, errors) + [0]
        trace, samples = _run(_word(fmt), crc_settings("none"), line, error=fmt.error_bits,
                              error_low=low, seed=rep)
        n = fmt.total_bits
        assert _strobes(trace, "done") == [samples[n - 1] + 1]
        assert _strobes(trace, "stopped") == [samples[n] + 1]
        # The frame's end in SSI: the bit after the word (its verdict waits for it).
        assert _strobes(trace, "frame_end") == [samples[n] + 1]
        assert [x["started"] for x in trace] == \
            [0] * (samples[0] + 1) + [1] * (len(trace) - samples[0] - 1)
        for when in (samples[n - 1] + 1, len(trace) - 1):
            x = trace[when]
            assert x["data0"] == position, (rep, when)
            assert x["start_slot"] == 0
            assert (x["ne"] & 1, x["nw"] & 1) == (int(not any(errors)), 1)
            assert x["crc_ok"] & 1 == 1 and x["mismatch"] == 0
        assert trace[-1]["stop_bit"] == 0


def test_ssi_stop_bit_one_is_reported():
    """The bit after the word is reported as ``stop_bit`` (the controller's NO_STOP)."""
    fmt = SsiFormat(13)
    trace, samples = _run(_word(fmt), crc_settings("none"), ssi_bits(fmt, 0x1FFF) + [1])
    assert _strobes(trace, "stopped") == [samples[13] + 1]
    assert trace[samples[13] + 1]["stop_bit"] == 1


def test_ssi_extended_word_crc_and_flags():
    """Extended SSI: position, nE, nW and CRC-6 after it (the BiSS word without its frame):
    the CRC is checked; one flipped bit anywhere fails it."""
    wf = WordFormat(19, nenw=True, crc=CRC6)
    cfg = {"data_bits": 19, "nenw": 1, "lc": 0, "crc": crc_config(CRC6)[0], "gray": 0,
           "signed": 0}
    rng = random.Random(5)
    for rep in range(6):
        value = WordValue(rng.randrange(1 << 19), rng.randrange(2), rng.randrange(2))
        bits = word_bits(wf, value)
        flip = rng.randrange(len(bits)) if rep >= 3 else None
        if flip is not None:
            bits[flip] ^= 1
        trace, samples = _run(cfg, crc_settings(CRC6), bits + [0], seed=rep)
        x = trace[-1]
        assert x["crc_ok"] & 1 == int(flip is None), rep
        if flip is None:
            assert (x["data0"], x["ne"] & 1, x["nw"] & 1) == (value.position, value.ne, value.nw)


@pytest.mark.parametrize("fmt", (SsiFormat(13, gray=True), SsiFormat(25, error_bits=1)),
                         ids=("gray_13", "binary_25_error"))
def test_ssi_double_transmission_compares_every_bit(fmt):
    """Double transmission (word, one 0, word): equal copies give no mismatch; one flipped bit
    of the second copy (each position in turn) or a separator of 1 does; ``done`` comes after
    the second copy, ``stopped`` after the bit that follows it; the position is the first
    copy's."""
    rng = random.Random(fmt.total_bits)
    n = fmt.total_bits
    position = rng.randrange(1 << fmt.data_bits)
    word = ssi_bits(fmt, position, (True,) * fmt.error_bits)
    good = word + [0] + word + [0]
    trace, samples = _run(_word(fmt), crc_settings("none"), good, error=fmt.error_bits,
                          double=1)
    assert _strobes(trace, "done") == [samples[2 * n] + 1]
    assert _strobes(trace, "stopped") == [samples[2 * n + 1] + 1]
    assert _strobes(trace, "frame_end") == [samples[2 * n + 1] + 1]
    assert (trace[-1]["mismatch"], trace[-1]["data0"]) == (0, position)
    for flip in list(range(n + 1, 2 * n + 1)) + [n]:        # each bit of copy 2, the separator
        line = list(good)
        line[flip] ^= 1
        trace, _ = _run(_word(fmt), crc_settings("none"), line, error=fmt.error_bits, double=1,
                        seed=flip)
        assert trace[-1]["mismatch"] == 1, flip
        assert trace[-1]["data0"] == position
    # A flip in the first copy differs from the second as much: a mismatch too.
    line = list(good)
    line[rng.randrange(n)] ^= 1
    trace, _ = _run(_word(fmt), crc_settings("none"), line, error=fmt.error_bits, double=1)
    assert trace[-1]["mismatch"] == 1
