"""WordCrc on Amaranth's simulator: words of the encoder model pass, corrupted ones fail.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

from bissmaster.params import Crc
from bissmaster.core.word_crc import WordCrc
from encoder_model.crc import crc6_biss, crc16_biss, int_to_bits
from encoder_model.frames import CRC6, CRC16, CRC_NONE, WordFormat, WordValue, word_bits
from master_contract import CRC_CODE

from testkit.block_sim import simulate

#: The one ``cfg_wN_crc`` code that names no CRC (2 bits, codes 0..2 used).
UNKNOWN_CRC = 3


def _random_word(rng, crc):
    fmt = WordFormat(rng.randint(1, 55), nenw=rng.random() < 0.7, lc=rng.random() < 0.3, crc=crc)
    value = WordValue(rng.randrange(1 << fmt.data_bits), rng.randrange(2), rng.randrange(2),
                      rng.randint(1, 63) if fmt.lc else None)
    return fmt, word_bits(fmt, value)


def _crc_sim(kinds, jobs, rng):
    """Feed each (kind, bits) job, one bit per 1..3 clocks, start with the first bit, junk on
    ``bit`` between valid strobes. Returns per job (ok one clock after the last bit, ok two
    idle clocks later)."""
    dut = WordCrc(kinds)
    results = []

    async def tb(ctx):
        for kind, bits in jobs:
            ctx.set(dut.kind, kind)
            for i, b in enumerate(bits):
                for _ in range(rng.randrange(3)):
                    ctx.set(dut.valid, 0)
                    ctx.set(dut.start, 0)
                    ctx.set(dut.bit, rng.randrange(2))
                    await ctx.tick()
                ctx.set(dut.valid, 1)
                ctx.set(dut.start, int(i == 0))
                ctx.set(dut.bit, b)
                await ctx.tick()
            ctx.set(dut.valid, 0)
            ctx.set(dut.start, 0)
            ctx.set(dut.bit, rng.randrange(2))
            ok_now = ctx.get(dut.ok)
            await ctx.tick()
            ctx.set(dut.bit, rng.randrange(2))
            await ctx.tick()
            results.append((ok_now, ctx.get(dut.ok)))

    simulate(dut, tb)
    return results


def test_word_crc_encoder_model_words_pass_and_single_flips_fail():
    rng = random.Random(3000)
    jobs, expected = [], []
    for crc in (CRC6, CRC16, CRC_NONE):
        for _ in range(8):
            fmt, bits = _random_word(rng, crc)
            jobs.append((CRC_CODE[crc], bits))
            expected.append((1, 1))
    # Every single-bit flip of short words (data, nE/nW, LC and the CRC itself), a sample of
    # flips in long ones. CRC-6 (x^6+x+1) and CRC-16 both detect every single-bit error.
    for crc in (CRC6, CRC16):
        for data_bits, lc in ((3, False), (6, True), (40, True)):
            fmt = WordFormat(data_bits, nenw=True, lc=lc, crc=crc)
            value = WordValue(rng.randrange(1 << data_bits), 1, 0, rng.randint(1, 63) if lc else None)
            bits = word_bits(fmt, value)
            positions = range(len(bits)) if data_bits < 40 else rng.sample(range(len(bits)), 10)
            for i in positions:
                flipped = list(bits)
                flipped[i] ^= 1
                jobs.append((CRC_CODE[crc], flipped))
                expected.append((0, 0))
            jobs.append((CRC_CODE[crc], bits))      # a good word after bad ones: start resets
            expected.append((1, 1))
    # Without a CRC nothing is checked: a flipped word still reads ok.
    fmt, bits = _random_word(rng, CRC_NONE)
    jobs.append((CRC_CODE[CRC_NONE], [b ^ 1 for b in bits]))
    expected.append((1, 1))
    assert _crc_sim((Crc.CRC6, Crc.CRC16), jobs, rng) == expected


def test_word_crc_matches_encoder_model_crc_functions():
    # The words of the model end with crc6_biss / crc16_biss of everything before the CRC; a CRC
    # of the right function but the wrong neighbour value fails.
    rng = random.Random(3100)
    jobs, expected = [], []
    for _ in range(6):
        payload = [rng.randrange(2) for _ in range(rng.randint(1, 60))]
        for func, width, crc in ((crc6_biss, 6, CRC6), (crc16_biss, 16, CRC16)):
            kind = CRC_CODE[crc]
            good = func(payload)
            jobs.append((kind, payload + int_to_bits(good, width)))
            expected.append((1, 1))
            jobs.append((kind, payload + int_to_bits(good ^ 1, width)))
            expected.append((0, 0))
    assert _crc_sim((Crc.CRC6, Crc.CRC16), jobs, rng) == expected


def test_word_crc_kind_not_built_reads_failed():
    rng = random.Random(3200)
    fmt6, bits6 = _random_word(rng, CRC6)
    fmt16, bits16 = _random_word(rng, CRC16)
    jobs = [(CRC_CODE[CRC6], bits6), (CRC_CODE[CRC16], bits16), (UNKNOWN_CRC, bits6),
            (CRC_CODE[CRC_NONE], bits16)]
    # Only CRC-6 built: a correct CRC-16 word under kind CRC16 fails, the unused code fails,
    # NONE passes.
    assert _crc_sim((Crc.CRC6,), jobs, rng) == [(1, 1), (0, 0), (0, 0), (1, 1)]
    jobs = [(CRC_CODE[CRC6], bits6), (CRC_CODE[CRC16], bits16), (UNKNOWN_CRC, bits16)]
    assert _crc_sim((Crc.CRC16,), jobs, rng) == [(0, 0), (1, 1), (0, 0)]


