"""cocotb regression of ``biss_master`` reading a chain of BiSS slaves (issue 26): one Ack, one
Start, one CDS, then every slave's word back to back, each with its own length, nE/nW, CRC
width, polynomial and start value.

Run through pytest (sim/test_regression.py) on the ``chain`` preset's build (three words of up
to 64, 32 and 24 bits, CRC-6 or a custom CRC per word, no register access, no SSI): every
scenario here says ``@only_on_builds("chain")``. The main scenario runs on Verilator and Icarus
in ``make test``; the others on Icarus only in ``make sim-long`` (``@long_on_icarus``).

What a result must show comes from the encoder model (frames.PRESETS["chain_3"]: what each
slave sent) and from the documented contract (master_contract.crc_status: CRC_ERROR_WORD0 when
word 0 fails alone, CRC_ERROR_WORD1 when word 0 passes and any later word fails,
CRC_ERROR_BOTH when word 0 and any later word fail; a disabled word's crc_ok reads 1), never
from the RTL.
"""

import cocotb
from cocotb.triggers import ClockCycles, Edge, Timer

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import STATUS, crc_counters, crc_status
from protocol_facts import CRC16_POLY, CRC16_WIDTH, CRC16_XOR_OUT, CRC_INIT
from sim.shared.discovery import long_on_icarus, only_on_builds
from sim.shared.testbench import Testbench, preset

CHAIN = frames.PRESETS["chain_3"]
#: The chain preset's words (docs: ``--max-data-bits 64,32,24``).
CHAIN_BUILD_WORDS = 3


async def bench(dut, seed, cable_m=20):
    tb = Testbench(dut, seed=seed)
    assert tb.words == CHAIN_BUILD_WORDS, f"a chain build has 3 words, this one {tb.words}"
    await tb.start(cable=Cable(length_m=cable_m))
    return tb


def assert_no_counts(res):
    """A clean line counts nothing: every counter 0."""
    assert not any(res.counters.values()), {k: v for k, v in res.counters.items() if v}


async def frames_ok(tb, n, **check):
    for _ in range(n):
        res = await tb.request()
        tb.check_frame(res, **check)
    return res


async def settle(tb):
    """Wait until the encoder has closed the last cycle, then run the MA-rise checks still
    pending: every checked frame's rises are judged before the scenario ends."""
    await tb.encoder_ready()
    await Timer(1, "us")
    tb.check_pending()
    assert not tb.pending, f"{len(tb.pending)} MA-rise checks never ran"


def corner_values(fmt, ne, nw):
    """Every word at a corner of its range: all ones, zero, a walking pattern."""
    out = []
    for k, pattern in enumerate(("ones", "zero", "alt")):
        words = []
        for w, word in enumerate(fmt.words):
            top = (1 << word.data_bits) - 1
            pos = {"ones": top, "zero": 0, "alt": 0x5555555555 & top}[pattern]
            words.append(frames.WordValue(pos, ne[w] if word.nenw else 1, nw[w] if word.nenw else 1))
        out.append(words)
    return out


@cocotb.test()
@only_on_builds("chain")
async def chain_of_three_frames(dut):
    """The chain of three (26 bits CRC-6; 17 bits CRC-8 start 0xA5 inverted; 12 bits CRC-4
    start 0x9, no nE/nW) read frame after frame at 1, 5 and 10 MHz over 0, 50 and 100 m: every
    word's position, nE, nW and crc_ok as that slave sent it, status OK, valid, exactly the MA
    rises the frame needs, every counter 0."""
    tb = await bench(dut, seed=2601, cable_m=0)
    count = 0
    for cable_m in (0, 50, 100):
        tb.encoder.set_cable(Cable(length_m=cable_m))
        for ma_hz in (1e6, 5e6, 10e6):
            tb.configure(CHAIN, ma_hz)
            # The corners of every word, nE / nW of each slave set differently ...
            for values in corner_values(CHAIN, ne=(1, 0, 1), nw=(0, 1, 1)):
                tb.queue(values=values)
                res = await tb.request()
                tb.check_frame(res)
                assert res.status == STATUS["OK"] and res.valid == 1
                for w, value in enumerate(values):
                    assert res.fields[f"word{w}_position"] == value.position, (w, res.fields)
                    assert res.fields[f"word{w}_crc_ok"] == 1
                assert (res.fields["word0_ne"], res.fields["word0_nw"]) == (1, 0)
                assert (res.fields["word1_ne"], res.fields["word1_nw"]) == (0, 1)
                assert_no_counts(res)
            # ... then random positions, each slave its own.
            res = await frames_ok(tb, 2)
            assert_no_counts(res)
            count += 5
    await settle(tb)
    dut._log.info("%d chain frames decoded and checked", count)


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_crc_error_per_word(dut):
    """A CRC error in each word in turn, in two words at once and in all three: the status by
    the documented rule (word 0 alone: WORD0; any later word with word 0 good: WORD1; word 0
    and a later one: BOTH), crc_ok per word, each word's count_crc_wordN by one when that
    word failed, and the next clean frames UNCONFIRMED (confirmation after a fault) then
    OK."""
    tb = await bench(dut, seed=2602, cable_m=20)
    tb.configure(CHAIN, 5e6)
    await frames_ok(tb, 2)
    offsets = CHAIN.word_offsets()
    cases = [(0,), (1,), (2,), (0, 1), (1, 2), (0, 2), (0, 1, 2)]
    for bad in cases:
        for how in ("crc_xor", "flip_data", "flip_last_crc_bit"):
            if how == "crc_xor":
                faults = frames.FrameFaults(crc_xor=tuple(
                    (1 << CHAIN.words[w].crc_bits) - 1 if w in bad else 0 for w in range(3)))
            elif how == "flip_data":        # a position bit of each bad word (first, middle)
                faults = frames.FrameFaults(flip_bits=tuple(
                    offsets[w] + (w * 5) % CHAIN.words[w].data_bits for w in bad))
            else:                           # the last bit of each bad word's CRC
                faults = frames.FrameFaults(flip_bits=tuple(
                    offsets[w] + CHAIN.words[w].total_bits - 1 for w in bad))
            crc_ok = tuple(w not in bad for w in range(3))
            status = crc_status(crc_ok)
            before = tb.read().counters
            tb.queue(faults=faults)
            res = await tb.request()
            parsed = tb.check_frame(res, status=status)
            assert tuple(bool(w["crc_ok"]) for w in parsed["words"]) == crc_ok, (bad, how)
            assert tuple(res.fields[f"word{w}_crc_ok"] for w in range(3)) == \
                tuple(int(ok) for ok in crc_ok), (bad, how, res.fields)
            counted = crc_counters(crc_ok)
            crc_names = [f"crc_word{w}" for w in range(3)]
            for name in crc_names:
                assert res.counters[name] == before[name] + (name in counted), \
                    (bad, how, name, before[name], res.counters[name])
            others = {k: v for k, v in res.counters.items() if k not in crc_names and v}
            assert not others, (bad, how, others)
            # The next clean frame is UNCONFIRMED (check_frame expects it), the one after OK.
            res = await tb.request()
            tb.check_frame(res)
            assert res.status == STATUS["UNCONFIRMED"] and res.valid == 0, (bad, how, res.status)
            res = await tb.request()
            tb.check_frame(res)
            assert res.status == STATUS["OK"] and res.valid == 1, (bad, how, res.status)
    await settle(tb)


#: The chain with Gray-coded and signed words (the chain preset has both): word 0 signed,
#: word 1 Gray, word 2 Gray and signed (sign-extended to its 24-bit port).
CHAIN_GRAY_SIGNED = frames.FrameFormat("chain_3_gray_signed", (
    frames.WordFormat(26, signed=True),
    frames.WordFormat(17, gray=True, crc=CHAIN.words[1].crc),
    frames.WordFormat(12, nenw=False, gray=True, signed=True, crc=CHAIN.words[2].crc)),
    chain=True)


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_gray_and_signed_words(dut):
    """Each slave's word decoded by its own settings: Gray words reported in binary, signed
    words sign-extended to their port (check_frame compares master_contract.port_position):
    the most negative, -1, 0 and the most positive field of every word, then random ones."""
    tb = await bench(dut, seed=2606, cable_m=20)
    tb.configure(CHAIN_GRAY_SIGNED, 5e6)
    for k in range(4):
        values = []
        for word in CHAIN_GRAY_SIGNED.words:
            n = word.data_bits
            values.append(frames.WordValue((1 << (n - 1), (1 << n) - 1, 0, (1 << (n - 1)) - 1)[k]))
        tb.queue(values=values)
        res = await tb.request()
        tb.check_frame(res)
        assert res.status == STATUS["OK"]
    res = await tb.request()
    tb.check_frame(res)
    # word 2 at its most negative: all ones above its 12 bits in the 24-bit port
    tb.queue(values=[frames.WordValue(0), frames.WordValue(0), frames.WordValue(0x800)])
    res = await tb.request()
    tb.check_frame(res)
    assert res.fields["word2_position"] == 0xFFF800, hex(res.fields["word2_position"])
    await frames_ok(tb, 4)
    await settle(tb)


async def ma_edges_during(dut, seconds):
    """MA edges seen within ``seconds`` from now."""
    edges = 0

    async def count():
        nonlocal edges
        while True:
            await Edge(dut.ma)
            edges += 1

    task = cocotb.start_soon(count())
    await Timer(seconds * 1e9, "ns")
    task.cancel()
    return edges


#: Chain settings the core refuses (BAD_CONFIG, config_error high, nothing on MA), as port
#: overrides on the good chain configuration: word 2 without word 1; the LC on two enabled
#: words (the core tracks one); CRC-16 in a build of CRC-6 words only; a word 2 longer than
#: the build's 24 bits.
CHAIN_BAD_CONFIGS = ({"cfg_w1_enable": 0},
                     {"cfg_w0_lc": 1, "cfg_w2_lc": 1},
                     {"cfg_w1_lc": 1, "cfg_w2_lc": 1},
                     {"cfg_w1_crc": 2},
                     {"cfg_w2_data_bits": 25})


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_bad_configurations(dut):
    """What a chain build refuses (CHAIN_BAD_CONFIGS): status BAD_CONFIG at once, not valid,
    config_error high, no MA edge at all; the good configuration afterwards reads OK. One LC on
    a single word is accepted."""
    tb = await bench(dut, seed=2603)
    tb.configure(CHAIN, 5e6)
    await frames_ok(tb, 1)
    for override in CHAIN_BAD_CONFIGS:
        await tb.encoder_ready()
        tb.configure(CHAIN, 5e6, **override)
        await ClockCycles(dut.clk, 2)
        assert int(dut.config_error.value) == 1, override
        cycles = len(tb.encoder.records)
        res = await tb.request(limit_s=1e-6)
        assert res.status == STATUS["BAD_CONFIG"] and res.valid == 0, (override, res.status)
        assert await ma_edges_during(dut, 20e-6) == 0, f"MA moved with {override}"
        assert int(dut.ma.value) == 1 and len(tb.encoder.records) == cycles, override
    tb.configure(CHAIN, 5e6)
    await ClockCycles(dut.clk, 2)
    assert int(dut.config_error.value) == 0
    await frames_ok(tb, 2)
    # One LC, on the last word: accepted (its LC checked by check_frame, sign of life in order).
    with_lc = frames.FrameFormat("chain_3_lc", CHAIN.words[:2] + (
        frames.WordFormat(12, nenw=False, lc=True, crc=CHAIN.words[2].crc),), chain=True)
    tb.configure(with_lc, 5e6)
    await ClockCycles(dut.clk, 2)
    assert int(dut.config_error.value) == 0
    await frames_ok(tb, 3)
    await settle(tb)


#: BiSS Safety encoders as the chain build reads them: the SPW's CRC-16 given as a custom CRC
#: of the same parameters (docs/protocol.md section 6: the polynomial 0x190D9, start 0, sent
#: inverted), since the chain preset has CRC-6 words only. RESOLUTE FS RSH (CPW 36 + SPW 28)
#: and LMM (32 + 32); RSM (28 + 24).
SPW_CRC16 = frames.CustomCrc(CRC16_WIDTH, CRC16_POLY, CRC_INIT,
                             CRC16_XOR_OUT == (1 << CRC16_WIDTH) - 1)


def custom_crc16(fmt):
    """A BiSS Safety preset with its SPW's CRC-16 as the equivalent custom CRC."""
    cpw, spw = fmt.words
    return frames.FrameFormat(f"{fmt.name}_custom16", (cpw, frames.WordFormat(
        spw.data_bits, nenw=spw.nenw, lc=spw.lc, crc=SPW_CRC16)))


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_build_reads_fewer_words(dut):
    """The chain build reading less than three slaves: a one-word RESOLUTE BiSS C (w1, w2
    disabled) and a chain of two slaves (w2 disabled, no SPW check): every field, the disabled
    words' crc_ok 1, MA making the rises of the shorter frame, counters 0. Then the three
    again. A Safety encoder's named CRC-16 (code 2) is not in this build: BAD_CONFIG."""
    tb = await bench(dut, seed=2604, cable_m=50)
    two = frames.FrameFormat("chain_2", CHAIN.words[1:], chain=True)
    c26 = preset("resolute_c_26")
    for fmt, ma_hz in ((c26, 1e6), (c26, 10e6), (two, 5e6), (CHAIN, 5e6), (c26, 5e6)):
        tb.configure(fmt, ma_hz)
        await ClockCycles(dut.clk, 2)           # (ports written now read back a step later)
        assert int(dut.cfg_w1_enable.value) == int(len(fmt.words) >= 2)
        assert int(dut.cfg_w2_enable.value) == int(len(fmt.words) >= 3)
        assert int(dut.cfg_spw_check.value) == 0
        res = await frames_ok(tb, 3)
        assert res.status == STATUS["OK"] and res.valid == 1
        assert_no_counts(res)
    tb.configure(preset("resolute_fs_rsh"), 5e6)
    res = await tb.request(limit_s=1e-6)
    assert res.status == STATUS["BAD_CONFIG"], res.status
    await settle(tb)


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_build_reads_safety(dut):
    """The chain build reading BiSS Safety encoders (w1 enabled with the SPW check, w2
    disabled): RESOLUTE FS RSM, RSH and LMM with random positions (their CRC-16 as the equal
    custom CRC: the same bits on the line), every frame OK with the LC in sequence; an SPW
    off by 2 is SPW_MISMATCH."""
    tb = await bench(dut, seed=2605, cable_m=50)
    rsh = preset("resolute_fs_rsh")
    values = [frames.WordValue(0x987654321), frames.WordValue(0x9876543, lc=9)]
    assert frames.build_frame(custom_crc16(rsh), values) == frames.build_frame(rsh, values)
    for name in ("resolute_fs_rsm", "resolute_fs_rsh", "resolute_fs_lmm"):
        fmt = custom_crc16(preset(name))
        for ma_hz in (2.5e6, 10e6):
            tb.configure(fmt, ma_hz)
            await ClockCycles(dut.clk, 2)
            assert int(dut.cfg_spw_check.value) == 1 and int(dut.cfg_w2_enable.value) == 0
            res = await frames_ok(tb, 3)
            assert res.status == STATUS["OK"] and res.fields["spw_mismatch"] == 0
            assert_no_counts(res)
    fmt = custom_crc16(rsh)
    tb.configure(fmt, 5e6)
    await frames_ok(tb, 1)
    cpw = 0x123456789
    tb.queue(values=[frames.WordValue(cpw),
                     frames.WordValue((cpw >> fmt.spw_shift) + 2, lc=tb.sign_of_life.next())])
    res = await tb.request()
    tb.check_frame(res, status="SPW_MISMATCH")
    assert res.fields["spw_mismatch"] == 1
    await frames_ok(tb, 2)
    await settle(tb)


@cocotb.test()
@only_on_builds("chain")
@long_on_icarus
async def chain_build_reads_64_bit_words(dut):
    """Words of 64 data bits (the chain preset's word 0, the longest a slave word can have):
    one 64-bit BiSS C encoder with CRC-6, then Gray-coded, then signed, then a 64-bit slave
    chained with a 32-bit one (a custom CRC-16 on the first). The corners (all ones, the top
    bit alone, 1) and random values, every bit of the 64-bit port as sent, status OK, counters
    0; a 65th data bit is BAD_CONFIG."""
    tb = await bench(dut, seed=2607, cable_m=50)
    formats = [
        frames.FrameFormat("w64", (frames.WordFormat(64),)),
        frames.FrameFormat("w64_gray", (frames.WordFormat(64, gray=True),)),
        frames.FrameFormat("w64_signed", (frames.WordFormat(64, signed=True),)),
        frames.FrameFormat("w64_w32", (frames.WordFormat(64, crc=SPW_CRC16),
                                       frames.WordFormat(32, lc=True)), chain=True),
    ]
    for fmt in formats:
        for ma_hz in (1e6, 10e6):
            tb.configure(fmt, ma_hz)
            for top in ((1 << 64) - 1, 1 << 63, 1):
                values = [frames.WordValue(top, 1, 0)]
                if len(fmt.words) == 2:
                    values.append(frames.WordValue(0xA5A5A5A5, 0, 1,
                                                   lc=tb.sign_of_life.next()))
                tb.queue(values=values)
                res = await tb.request()
                tb.check_frame(res)
                assert res.status == STATUS["OK"] and res.valid == 1
                if not fmt.words[0].signed:
                    assert res.fields["word0_position"] == top, hex(res.fields["word0_position"])
            await frames_ok(tb, 2)
            assert_no_counts(res)
    tb.configure(formats[0], 5e6)
    await ClockCycles(dut.clk, 2)
    dut.cfg_w0_data_bits.value = 65
    res = await tb.request(limit_s=1e-6)
    assert res.status == STATUS["BAD_CONFIG"], res.status
    await settle(tb)
