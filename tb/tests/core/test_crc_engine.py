"""CrcEngine on Amaranth's simulator: one programmable checker for every word of a frame.

Expected values come from two places outside the RTL: published check values of the CRC
catalogue (Greg Cook's "Catalogue of parametrised CRC algorithms", reveng: the CRC of the
ASCII string "123456789", for the non-reflected CRCs whose output is the register or its
complement), and the encoder model's textbook bit-serial CRC (tb/encoder_model/crc.py).
Cycle conventions: ``block_sim.py``.
"""

import random

import pytest
from amaranth.hdl import Elaboratable, Module, Mux, Signal

from bissmaster.core.crc_engine import CrcEngine
from encoder_model.crc import crc_msb_first, int_to_bits

from master_contract import CRC_CODE
from testkit.block_sim import simulate

#: (name, width, poly, init, xorout, check) from the reveng catalogue; xorout 0 or all ones.
CATALOGUE = [
    ("CRC-3/GSM", 3, 0x3, 0x0, 0x7, 0x4),
    ("CRC-4/INTERLAKEN", 4, 0x3, 0xF, 0xF, 0xB),
    ("CRC-5/EPC-C1G2", 5, 0x09, 0x09, 0x00, 0x00),
    ("CRC-6/CDMA2000-A", 6, 0x27, 0x3F, 0x00, 0x0D),
    ("CRC-6/GSM", 6, 0x2F, 0x00, 0x3F, 0x13),
    ("CRC-7/MMC", 7, 0x09, 0x00, 0x00, 0x75),
    ("CRC-8/SMBUS", 8, 0x07, 0x00, 0x00, 0xF4),
    ("CRC-10/ATM", 10, 0x233, 0x000, 0x000, 0x199),
    ("CRC-11/FLEXRAY", 11, 0x385, 0x01A, 0x000, 0x5A3),
    ("CRC-12/DECT", 12, 0x80F, 0x000, 0x000, 0xF5B),
    ("CRC-15/CAN", 15, 0x4599, 0x0000, 0x0000, 0x059E),
    ("CRC-16/XMODEM", 16, 0x1021, 0x0000, 0x0000, 0x31C3),
    ("CRC-16/IBM-3740", 16, 0x1021, 0xFFFF, 0x0000, 0x29B1),
    ("CRC-16/GENIBUS", 16, 0x1021, 0xFFFF, 0xFFFF, 0xD64E),
    ("CRC-16/DECT-X", 16, 0x0589, 0x0000, 0x0000, 0x007F),
    ("CRC-16/CMS", 16, 0x8005, 0xFFFF, 0x0000, 0xAEE7),
]
#: The BiSS CRCs (docs/protocol.md, section 6): CRC-6 0x43 and CRC-16 0x190D9, start 0, inverted.
BISS = [("BiSS CRC-6", 6, 0x03, 0, 0x3F), ("BiSS CRC-16", 16, 0x90D9, 0, 0xFFFF)]
CHECK_MESSAGE = [(byte >> (7 - i)) & 1 for byte in b"123456789" for i in range(8)]


def _settings(width, poly, start, inverted):
    return {"width": width, "poly": poly, "start": start, "inverted": int(inverted)}


#: What a named code runs (the BiSS CRCs above), and code 0: no CRC.
NAMED_SETTINGS = {CRC_CODE["crc6"]: _settings(*BISS[0][1:4], True),
                  CRC_CODE["crc16"]: _settings(*BISS[1][1:4], True),
                  CRC_CODE["none"]: _settings(0, 0, 0, False)}


class _TableRead(Elaboratable):
    """A table of the test's own beside a ``table`` engine: ``entries[w]`` (poly, start,
    inverted) read combinationally at the engine's ``table_index``, as the bus tops' memory
    is (docs/bus.md, "The CRC table")."""

    def __init__(self, engine, words):
        self.engine = engine
        self.entries = [Signal(16 + 16 + 1, name=f"entry{w}") for w in range(words)]

    def elaborate(self, platform):
        m = Module()
        m.submodules.engine = self.engine
        picked = 0
        for w, entry in enumerate(self.entries):
            picked = Mux(self.engine.table_index == w, entry, picked)
        m.d.comb += self.engine.table.as_value().eq(picked)
        return m


def _entry(settings):
    return settings["poly"] | settings["start"] << 16 | settings["inverted"] << 32


def _run(words, jobs, seed, table=False):
    """Each job is (word index, settings, covered bits, received CRC bits); settings are a
    custom CRC (a :func:`_settings` dict: the word's code is "custom") or a named CRC's code
    (a one-word engine gets the CRC resolved: the dict, or the named CRC's settings from
    ``NAMED_SETTINGS``).
    The engine loads the job's word before its first bit, either in a clock of its own or with
    the last bit of the job before (as the decoder does after CDS and between words); the bits
    come one per 1..3 clocks with junk between. The word's code and custom settings are set
    before its load; with more than one word, in about a third of the jobs they are then
    overwritten with junk, which the engine must not read (it takes a word's settings at its
    load; a one-word engine reads its resolved CRC at every bit: the master holds it for the
    cycle).
    Returns per job (ok[word] the clock after its last bit, ok[word] two clocks later)."""
    rng = random.Random(seed)
    dut = CrcEngine(words, table=table)
    top = _TableRead(dut, words) if table else dut
    codes = [CRC_CODE["none"]] * words
    customs = [_settings(0, 0, 0, 0)] * words
    results = []

    def put(ctx, word, settings):
        if words == 1:
            ctx.set(dut.word_crc, settings if isinstance(settings, dict)
                    else NAMED_SETTINGS[settings])
            return
        if isinstance(settings, dict):
            codes[word], customs[word] = CRC_CODE["custom"], settings
        else:
            codes[word], customs[word] = settings, _settings(*_random_crc(rng))
        ctx.set(dut.codes, codes)
        if table:
            # The table holds the custom settings; the width comes resolved (a named CRC's
            # own, the custom one's, 0 for none).
            ctx.set(top.entries[word], _entry(customs[word]))
            ctx.set(dut.widths, [customs[w]["width"] if codes[w] == CRC_CODE["custom"]
                                 else NAMED_SETTINGS[codes[w]]["width"] for w in range(words)])
        else:
            ctx.set(dut.customs, customs)

    async def tb(ctx):
        def drive(**values):
            for name in ("load", "cover", "check", "last"):
                ctx.set(getattr(dut, name), values.get(name, 0))
            ctx.set(dut.bit, values.get("bit", rng.randrange(2)))
            if words > 1:
                ctx.set(dut.index, values.get("word", rng.randrange(words)))
                ctx.set(dut.load_index, values.get("load_word", rng.randrange(words)))

        pending = None          # the last bit of the job before, held back to share a clock
        for word, settings, covered, received in jobs:
            # Sharing a clock needs another word: each word's settings hold through it.
            if pending is not None and pending["word"] != word and rng.random() < 0.7:
                put(ctx, word, settings)
                drive(**pending, load=1, load_word=word)
                await ctx.tick()
                results.append(await _verdict(ctx, pending["word"]))
            else:
                if pending is not None:
                    drive(**pending)
                    await ctx.tick()
                    results.append(await _verdict(ctx, pending["word"]))
                put(ctx, word, settings)
                drive(load=1, load_word=word)
                await ctx.tick()
            if words > 1 and rng.random() < 0.35:
                put(ctx, word, rng.choice([_settings(*_random_crc(rng)), CRC_CODE["crc6"],
                                           CRC_CODE["crc16"], CRC_CODE["none"]]))
            bits = [(b, 1, 0) for b in covered] + [(b, 0, 1) for b in received]
            for i, (b, cover, check) in enumerate(bits):
                step = {"bit": b, "cover": cover, "check": check, "last": 1, "word": word}
                if i == len(bits) - 1:
                    pending = step
                    break
                for _ in range(rng.randrange(3)):
                    drive(word=word)
                    await ctx.tick()
                drive(**dict(step, last=0))
                await ctx.tick()
        drive(**pending)
        await ctx.tick()
        results.append(await _verdict(ctx, pending["word"]))

    async def _verdict(ctx, word):
        # In the clock after the last bit; then two clocks of nothing (junk on bit).
        now = (ctx.get(dut.ok) >> word) & 1
        drive_idle(ctx)
        await ctx.tick()
        await ctx.tick()
        return now, (ctx.get(dut.ok) >> word) & 1

    def drive_idle(ctx):
        for name in ("load", "cover", "check", "last"):
            ctx.set(getattr(dut, name), 0)
        ctx.set(dut.bit, rng.randrange(2))

    simulate(top, tb)
    return results


@pytest.mark.parametrize("name, width, poly, init, xorout, check", CATALOGUE,
                         ids=[c[0] for c in CATALOGUE])
def test_crc_engine_catalogue_check_values(name, width, poly, init, xorout, check):
    """The engine accepts "123456789" followed by the catalogue's check value, and refuses it
    with any one check bit flipped or the check value off by one."""
    assert xorout in (0, 2**width - 1)
    settings = _settings(width, poly, init, xorout != 0)
    good = int_to_bits(check, width)
    jobs = [(0, settings, CHECK_MESSAGE, good)]
    for i in range(width):
        flipped = list(good)
        flipped[i] ^= 1
        jobs.append((0, settings, CHECK_MESSAGE, flipped))
    jobs.append((0, settings, CHECK_MESSAGE, int_to_bits((check + 1) % 2**width, width)))
    assert _run(1, jobs, seed=width) == [(1, 1)] + [(0, 0)] * (width + 1)


def test_crc_engine_model_agrees_with_the_catalogue():
    """The reference the random tests use gives the published values too."""
    for _, width, poly, init, xorout, check in CATALOGUE + [(n, w, p, i, x, None)
                                                              for n, w, p, i, x in BISS]:
        if check is not None:
            assert crc_msb_first(CHECK_MESSAGE, width=width, poly=poly, init=init,
                                 xor_out=xorout) == check


def _random_crc(rng):
    width = rng.randint(1, 16)
    return width, rng.randrange(2**width) | 1, rng.randrange(2**width), rng.random() < 0.5


@pytest.mark.parametrize("words, table", ((1, False), (2, False), (2, True), (8, True)))
def test_crc_engine_random_crcs_and_words_in_turn(words, table):
    """Random CRCs (width 1..16, odd polynomial, any start, inverted or not), random lengths,
    words in turn with their own settings: a correct CRC passes, one flipped bit anywhere
    (covered data or the CRC) fails, and a word's verdict is held while other words run.
    ``table``: the custom settings come from a table read at the engine's ``table_index``,
    the width resolved beside it."""
    rng = random.Random(8100 + words)
    jobs, expected = [], []
    for _ in range(120):
        word = rng.randrange(words)
        width, poly, start, inverted = _random_crc(rng)
        covered = [rng.randrange(2) for _ in range(rng.randint(1, 80))]
        crc = crc_msb_first(covered, width=width, poly=poly, init=start,
                            xor_out=2**width - 1 if inverted else 0)
        received = int_to_bits(crc, width)
        flip = rng.random() < 0.5
        if flip:
            # Any single-bit error: the generator has an x^0 term (odd polynomial) and its top
            # term, so it divides no x^k.
            i = rng.randrange(len(covered) + width)
            if i < len(covered):
                covered = covered[:i] + [covered[i] ^ 1] + covered[i + 1:]
            else:
                j = i - len(covered)
                received = received[:j] + [received[j] ^ 1] + received[j + 1:]
        jobs.append((word, _settings(width, poly, start, inverted), covered, received))
        expected.append((int(not flip),) * 2)
    assert _run(words, jobs, seed=words, table=table) == expected


def test_crc_engine_width_0_word_is_good_and_other_verdicts_hold():
    """A word without CRC (width 0: no check bits) ends good; word 0's failed verdict stays
    while word 1 runs, and word 1's good verdict is its own."""
    rng = random.Random(8200)
    covered = [rng.randrange(2) for _ in range(30)]
    bad = int_to_bits(crc_msb_first(covered, width=6, poly=0x03, xor_out=0x3F) ^ 1, 6)
    dut = CrcEngine(2)
    seen = []

    async def tb(ctx):
        ctx.set(dut.codes, [CRC_CODE["custom"], CRC_CODE["custom"]])
        ctx.set(dut.customs, [_settings(6, 0x03, 0, 1), _settings(0, 0, 0, 0)])
        for word, bits in ((0, [(b, 1, 0) for b in covered] + [(b, 0, 1) for b in bad]),
                           (1, [(b, 1, 0) for b in covered])):
            ctx.set(dut.index, word)
            ctx.set(dut.load, 1)
            ctx.set(dut.load_index, word)
            ctx.set(dut.cover, 0)
            ctx.set(dut.check, 0)
            ctx.set(dut.last, 0)
            await ctx.tick()
            ctx.set(dut.load, 0)
            for i, (b, cover, check) in enumerate(bits):
                ctx.set(dut.cover, cover)
                ctx.set(dut.check, check)
                ctx.set(dut.last, int(i == len(bits) - 1))
                ctx.set(dut.bit, b)
                await ctx.tick()
            for signal in (dut.cover, dut.check, dut.last):
                ctx.set(signal, 0)
            await ctx.tick()
            seen.append(ctx.get(dut.ok))

    simulate(dut, tb)
    assert seen == [0b10, 0b10]


@pytest.mark.parametrize("words", (1, 3))
def test_crc_engine_named_codes_run_the_biss_crcs(words):
    """A named code (``cfg_wN_crc`` 1 and 2) runs the BiSS CRC of docs/protocol.md section 6
    (CRC-6 0x43, CRC-16 0x190D9, start 0, sent inverted: ``BISS`` above, the test's own
    values), and code 0 a word without CRC, mixed with custom CRCs word by word: a correct
    CRC passes and a flipped bit fails."""
    rng = random.Random(8300 + words)
    named = {CRC_CODE["crc6"]: BISS[0], CRC_CODE["crc16"]: BISS[1]}
    jobs, expected = [], []
    for _ in range(90):
        word = rng.randrange(words)
        covered = [rng.randrange(2) for _ in range(rng.randint(1, 64))]
        code = rng.choice([CRC_CODE["crc6"], CRC_CODE["crc16"], CRC_CODE["none"], "custom"])
        if code == CRC_CODE["none"]:
            jobs.append((word, code, covered, []))
            expected.append((1, 1))
            continue
        if code == "custom":
            width, poly, start, inverted = _random_crc(rng)
            settings = _settings(width, poly, start, inverted)
            xorout = 2**width - 1 if inverted else 0
        else:
            _, width, poly, start, xorout = named[code]
            settings = code
        received = int_to_bits(crc_msb_first(covered, width=width, poly=poly, init=start,
                                             xor_out=xorout), width)
        flip = rng.random() < 0.5
        if flip:
            j = rng.randrange(width)
            received = received[:j] + [received[j] ^ 1] + received[j + 1:]
        jobs.append((word, settings, covered, received))
        expected.append((int(not flip),) * 2)
    assert _run(words, jobs, seed=words) == expected
