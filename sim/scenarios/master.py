"""cocotb regression of the generated ``biss_master`` against the encoder model.

Run through pytest (sim/test_regression.py) on Verilator and Icarus. Each test builds its
scenario on ``testbench.Testbench`` and checks every decoded field and status, not just the
absence of exceptions. Every ``@cocotb.test`` here runs; markers from sim/shared/discovery.py say
when a scenario needs another build or clock (sim/README.md).
"""

import os
import random

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, Timer

from cocotb.simtime import get_sim_time

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import ENCODER_PRESETS, STATUS, STATUS_NAME, SYS_CLK_HZ
from sim.shared import glitch
from sim.shared.discovery import (also_at_fast_clock, full_in_sim_long, full_run, long_on_icarus,
                                  only_on_builds)
from sim.shared.testbench import CABLES_M, CLK_HZ, MA_RATES_HZ, Testbench, half_period_for, preset

#: Every preset of the issue: BiSS Safety, EVOLUTE, RESOLUTE BiSS C (master_contract) and BP3.
BP3_LENGTHS = [1, 2, 13, 24, 40, 55]
FRAMES_PER_POINT = int(os.environ.get("BISS_FRAMES_PER_POINT", "2"))


async def frames_ok(tb, n, **check):
    for _ in range(n):
        res = await tb.request()
        tb.check_frame(res, **check)
    return res


#: The subset of the matrix at another system clock in make test (full_in_sim_long): MA rates
#: at which the cable matters there. The clock ratio (MA half period in clocks) is set by the
#: rate, the line delay in clocks by the cable: every rate over the longest cable (the largest
#: delay count with every half period, 250 kHz's 400 clocks at 200 MHz the longest), and the
#: other cables at the fast rates, where the round trip is bit periods long.
SUBSET_FAST_RATES_HZ = (5e6, 10e6)


async def matrix(dut, names, subset_slowest=False):
    """Every preset x MA rate x cable length, FRAMES_PER_POINT random frames each (one at a
    system clock other than the default: that run checks the clock-dependent settings and
    limits, which one frame per point does). make test's runs are subsets: at the default
    clock one frame per point at the slowest rate (250 kHz: two thirds of the simulation) with
    ``subset_slowest``, at another clock every preset at every rate over the longest cable, at
    SUBSET_FAST_RATES_HZ over the others; the whole runs with BISS_FULL=1 (make sim-long)."""
    tb = Testbench(dut, seed=hash(tuple(names)) & 0xFFFF)
    per_point = FRAMES_PER_POINT if CLK_HZ == SYS_CLK_HZ else 1
    subset = CLK_HZ != SYS_CLK_HZ and not full_run()
    # Verilator's run in make test (the Icarus run, make sim-long, is whole as before).
    one_at_slowest = (subset_slowest and CLK_HZ == SYS_CLK_HZ and not full_run()
                      and "verilator" in cocotb.SIM_NAME.lower())
    await tb.start()
    count = 0
    for cable_m in CABLES_M:
        tb.encoder.set_cable(Cable(length_m=cable_m))
        for name in names:
            for ma_hz in MA_RATES_HZ:
                if subset and cable_m != max(CABLES_M) and ma_hz not in SUBSET_FAST_RATES_HZ:
                    continue
                tb.configure(preset(name), ma_hz)
                n = 1 if one_at_slowest and ma_hz == min(MA_RATES_HZ) else per_point
                await frames_ok(tb, n)
                count += n
    dut._log.info("%d frames decoded and checked", count)


@cocotb.test()
@also_at_fast_clock
@full_in_sim_long(100_000_000, 200_000_000)
@long_on_icarus
async def safety_and_biss_c_presets(dut):
    await matrix(dut, ENCODER_PRESETS, subset_slowest=True)


@cocotb.test()
@full_in_sim_long(100_000_000)
@long_on_icarus
async def bp3_lengths(dut):
    await matrix(dut, [f"bp3_{n}" for n in BP3_LENGTHS], subset_slowest=True)


@cocotb.test()
@also_at_fast_clock
@long_on_icarus
async def long_round_trip_many_bit_periods(dut):
    """2 us of round trip at 10 MHz (20 bit periods), on the longest and the shortest frame:
    the shortest is over long before the master learns where Start was."""
    tb = Testbench(dut, seed=7)
    await tb.start(cable=Cable(length_m=200))
    for name in ("resolute_fs_rsh", "bp3_1", "evolute_26"):
        tb.configure(preset(name), 10e6)
        res = await frames_ok(tb, 4)
        assert res.fields["line_delay"] >= 200, res.fields["line_delay"]
    # Near the hardware limits: 3000 clocks of round trip (30 us at 100 MHz), inside both the
    # delay counter (4095 clocks) and the default Ack limit (4000 clocks).
    tb.encoder.set_cable(Cable(extra_round_trip_s=3000 / CLK_HZ))
    tb.configure(preset("resolute_fs_rsh"), 2.5e6)
    await frames_ok(tb, 2)


@cocotb.test()
@long_on_icarus
async def edge_jitter(dut):
    """Random jitter on every edge, both directions, 10 % of the MA period each way."""
    tb = Testbench(dut, seed=11)
    await tb.start()
    for ma_hz in (1e6, 5e6, 10e6):
        tb.encoder.set_cable(Cable(length_m=50, jitter_s=0.1 / ma_hz))
        tb.configure(preset("resolute_fs_rsh"), ma_hz)
        for _ in range(4):
            res = await tb.request()
            tb.check_frame(res, check_rises=False)


@cocotb.test()
@long_on_icarus
async def crc_errors_each_word(dut):
    tb = Testbench(dut, seed=3)
    await tb.start(cable=Cable(length_m=20))
    fmt = preset("resolute_fs_rsh")
    tb.configure(fmt, 5e6)
    await frames_ok(tb, 1)
    w0_first = 2                                  # after Start and CDS
    w1_first = 2 + fmt.words[0].total_bits
    cases = [
        ("CRC_ERROR_WORD0", frames.FrameFaults(flip_bits=(w0_first + 5,)), (1, 0)),
        ("CRC_ERROR_WORD0", frames.FrameFaults(crc_xor=(0x01, 0)), (1, 0)),
        ("CRC_ERROR_WORD1", frames.FrameFaults(flip_bits=(w1_first + 30,)), (0, 1)),
        ("CRC_ERROR_WORD1", frames.FrameFaults(crc_xor=(0, 0x8000)), (0, 1)),
        ("CRC_ERROR_BOTH", frames.FrameFaults(flip_bits=(w0_first, w1_first)), (1, 1)),
        # The last CRC bit of the frame: the verdict must still be right.
        ("CRC_ERROR_WORD1", frames.FrameFaults(flip_bits=(2 + fmt.total_bits - 1,)), (0, 1)),
    ]
    for status, faults, (e0, e1) in cases:
        before = tb.read().counters
        tb.queue(faults=faults)
        res = await tb.request()
        tb.check_frame(res, status=status)
        assert res.counters["crc_word0"] == before["crc_word0"] + e0
        assert res.counters["crc_word1"] == before["crc_word1"] + e1
        # The LC of a frame with a bad SPW CRC is not trusted: the next good frame is judged
        # against the last good one and shows the lost frame as a skip.
        res = await tb.request()
        if e1:
            tb.check_frame(res, status="SIGN_OF_LIFE")
            assert res.fields["lc_skip"] == 1
        else:
            tb.check_frame(res)


#: Encoders with CRCs other than BiSS's own (issue 26): per word a width of 1..16, a polynomial,
#: a start value and inversion, as iC-MB4 and BP3's CPOLY / CSTART allow. Catalogue CRCs
#: (reveng): CRC-8/SMBUS sent plain; CRC-16/IBM-3740 (start 0xFFFF); CRC-3/GSM inverted; a
#: 12-bit one with a start value on an SPW with LC.
CUSTOM_CRC_FORMATS = [
    frames.FrameFormat("crc8_smbus_32", (frames.WordFormat(32, crc=frames.CustomCrc(8, 0x07, 0, False)),)),
    frames.FrameFormat("crc16_ibm3740_40", (frames.WordFormat(40, crc=frames.CustomCrc(16, 0x1021, 0xFFFF, False)),)),
    frames.FrameFormat("crc3_gsm_13_no_nenw", (frames.WordFormat(13, nenw=False, crc=frames.CustomCrc(3, 0x3, 0, True)),)),
    frames.FrameFormat("two_custom_words", (
        frames.WordFormat(36, crc=frames.CustomCrc(5, 0x15, 0x1F, True)),
        frames.WordFormat(28, lc=True, crc=frames.CustomCrc(12, 0x80F, 0x5A5, True)))),
    frames.FrameFormat("crc6_cpw_custom_spw", (
        frames.WordFormat(36), frames.WordFormat(28, lc=True, crc=frames.CustomCrc(16, 0x8005, 0x1234, False)))),
]


@cocotb.test()
@long_on_icarus
async def custom_crcs(dut):
    """Custom CRCs per word (cfg_wN_crc = 3 and the cfg_wN_crc_* ports): frames of each format
    at three MA rates over 50 m are OK with every field right; a flipped bit in each word is
    that word's CRC error; the master set to another polynomial or start value than the
    encoder's never reports a frame valid; a width of 0 or 17 is BAD_CONFIG."""
    tb = Testbench(dut, seed=26)
    if not tb.has_custom_crc:
        return
    await tb.start(cable=Cable(length_m=50))
    for fmt in CUSTOM_CRC_FORMATS:
        for ma_hz in (1e6, 5e6, 10e6):
            tb.configure(fmt, ma_hz)
            await frames_ok(tb, 2)
        first = 2
        for w, word in enumerate(fmt.words):
            status = "CRC_ERROR_WORD0" if w == 0 else "CRC_ERROR_WORD1"
            for bit in (0, word.total_bits - 1):        # first data bit, last CRC bit
                tb.queue(faults=frames.FrameFaults(flip_bits=(first + bit,)))
                res = await tb.request()
                tb.check_frame(res, status=status)
            # An LC in a word with a CRC error is not trusted: the next good frame shows the
            # lost frames as a skip (as with the BiSS CRCs, crc_errors_each_word).
            res = await tb.request()
            tb.check_frame(res, status="SIGN_OF_LIFE" if word.lc else "OK")
            await frames_ok(tb, 1)
            first += word.total_bits
    # The master set to a CRC the encoder does not use: the model parses the frame with the
    # master's CRC (``view``), and no frame it fails is valid.
    fmt = CUSTOM_CRC_FORMATS[1]
    wrong = {"poly": frames.CustomCrc(16, 0x8005, 0xFFFF, False),
             "start": frames.CustomCrc(16, 0x1021, 0x0000, False),
             "inverted": frames.CustomCrc(16, 0x1021, 0xFFFF, True)}
    for what, crc in wrong.items():
        view = frames.FrameFormat(f"master_{what}", (frames.WordFormat(40, crc=crc),))
        tb.configure(fmt, 5e6, cfg_w0_crc_poly=crc.poly, cfg_w0_crc_start=crc.start,
                     cfg_w0_crc_inverted=int(crc.inverted))
        for _ in range(3):
            res = await tb.request()
            tb.check_frame(res, status="CRC_ERROR_WORD0", view=view)
    for width in (0, 17, 31):
        tb.configure(fmt, 5e6, cfg_w0_crc_width=width)
        res = await tb.request(limit_s=1e-6)
        assert res.status == STATUS["BAD_CONFIG"] and res.valid == 0, width
    tb.configure(fmt, 5e6)
    await frames_ok(tb, 1)


#: Gray-coded positions (issue 26): a 13-bit single-turn word with CRC-6, a 55-bit one, and a
#: Safety pair with both words Gray-coded under the SPW plausibility check.
GRAY_FORMATS = [
    frames.FrameFormat("gray_13", (frames.WordFormat(13, gray=True),)),
    frames.FrameFormat("gray_55_custom_crc", (frames.WordFormat(55, gray=True,
                                                                 crc=frames.CustomCrc(8, 0x07)),)),
    frames.FrameFormat("gray_safety", (frames.WordFormat(36, gray=True),
                                       frames.WordFormat(28, lc=True, crc=frames.CRC16, gray=True))),
]


@cocotb.test()
@long_on_icarus
async def gray_positions(dut):
    """Gray-coded words are reported in binary, every field right, at three MA rates, with
    the positions moving through many values (the SPW check compares the decoded words); a
    word set Gray while the encoder sends binary reads a different position, so the setting
    is really used."""
    tb = Testbench(dut, seed=27)
    await tb.start(cable=Cable(length_m=20))
    for fmt in GRAY_FORMATS:
        if not tb.has_custom_crc and any(isinstance(w.crc, frames.CustomCrc) for w in fmt.words):
            continue
        if len(fmt.words) > tb.words:
            continue
        for ma_hz in (1e6, 5e6, 10e6):
            tb.configure(fmt, ma_hz)
            await frames_ok(tb, 3)
    binary = frames.FrameFormat("binary_13", (frames.WordFormat(13),))
    tb.configure(binary, 5e6, cfg_w0_gray=1)
    view = frames.FrameFormat("gray_view", (frames.WordFormat(13, gray=True),))
    differ = 0
    for _ in range(4):
        res = await tb.request()
        tb.check_frame(res, view=view)
        differ += res.fields["word0_position"] != frames.parse_frame(
            binary, tb.line_bits(tb.sent[-1], binary))["words"][0]["position"]
    assert differ >= 3


#: Signed positions (issue 26): two's complement words, one Gray-coded, and a Safety pair with
#: both words signed under the SPW plausibility check (it compares the fields modulo their width).
SIGNED_FORMATS = [
    frames.FrameFormat("signed_26", (frames.WordFormat(26, signed=True),)),
    frames.FrameFormat("signed_gray_13", (frames.WordFormat(13, gray=True, signed=True),)),
    frames.FrameFormat("signed_safety", (frames.WordFormat(36, signed=True),
                                         frames.WordFormat(28, lc=True, crc=frames.CRC16,
                                                           signed=True))),
]


@cocotb.test()
async def signed_positions(dut):
    """A word set ``signed`` reads as its two's complement value in the port's whole width
    (check_frame compares signed values): the most negative field, -1, 0 and the most positive,
    then random ones (half of them negative). The same encoder read unsigned has zeros above
    its field, so the setting is really used."""
    tb = Testbench(dut, seed=28)
    if not tb.has_signed:
        dut._log.info("this build has no signed words (biss-c-lean): nothing to read")
        return
    await tb.start(cable=Cable(length_m=20))
    for fmt in SIGNED_FORMATS:
        if len(fmt.words) > tb.words:
            continue
        tb.configure(fmt, 5e6)
        if len(fmt.words) == 1:
            bits = fmt.words[0].data_bits
            for field in (1 << (bits - 1), (1 << bits) - 1, 0, (1 << (bits - 1)) - 1):
                tb.queue(values=[frames.WordValue(field, 1, 1)])
                tb.check_frame(await tb.request())
        await frames_ok(tb, 4)
    fmt = SIGNED_FORMATS[0]
    unsigned = frames.FrameFormat("unsigned_26", (frames.WordFormat(26),))
    tb.configure(fmt, 5e6, cfg_w0_signed=0)
    tb.queue(values=[frames.WordValue((1 << 26) - 5, 1, 1)])
    res = await tb.request()
    tb.check_frame(res, view=unsigned)
    assert res.fields["word0_position"] == (1 << 26) - 5, hex(res.fields["word0_position"])


@cocotb.test()
async def encoder_error_and_warning_bits(dut):
    tb = Testbench(dut, seed=4)
    await tb.start()
    tb.configure(preset("evolute_36"), 2.5e6)
    for ne, nw in ((0, 1), (1, 0), (0, 0), (1, 1)):
        tb.queue(values=[frames.WordValue(0x123456789 & (2**36 - 1), ne, nw)])
        res = await tb.request()
        tb.check_frame(res)                # a transfer can be fine while the encoder says no
        assert (res.fields["word0_ne"], res.fields["word0_nw"]) == (ne, nw)
        assert res.fields["word0_position"] == 0x123456789 & (2**36 - 1)


@cocotb.test()
@long_on_icarus
async def sign_of_life_faults(dut):
    tb = Testbench(dut, seed=5)
    await tb.start()
    tb.configure(preset("resolute_fs_lmm"), 10e6)
    sol = tb.sign_of_life
    await frames_ok(tb, 3)
    expected = {"lc_repeat": 0, "lc_skip": 0, "lc_zero": 0}
    for kind, lc in (("lc_repeat", sol.repeat), ("lc_zero", sol.zero),
                     ("lc_skip", lambda: sol.skip(5)), ("lc_skip", lambda: sol.skip(61)),   # 62 would land on the same value: a repeat
                     ("lc_repeat", sol.repeat)):
        tb.queue(lc=lc())
        res = await tb.request()
        tb.check_frame(res, status="SIGN_OF_LIFE")
        expected[kind] += 1
        flags = {k: res.fields[k] for k in expected}
        assert flags == {k: int(k == kind) for k in expected}, (kind, flags, tb.sent[-3:])
        assert {k: res.counters[k] for k in expected} == expected
        # The next frame is in sequence again (after a zero: judged against the last good LC).
        tb.check_frame(await tb.request())
    # Wrap-around 63 -> 1 is in sequence.
    for _ in range(70):
        res = await tb.request()
        tb.check_frame(res, check_rises=False)


@cocotb.test()
async def spw_plausibility(dut):
    tb = Testbench(dut, seed=6)
    await tb.start()
    fmt = preset("resolute_fs_rsm")          # CPW 28, SPW 24: 4 low bits dropped
    tb.configure(fmt, 2.5e6, spw_tolerance=1)
    sol = tb.sign_of_life
    for offset, status in ((0, "OK"), (1, "OK"), (-1, "OK"), (2, "SPW_MISMATCH"),
                           (-2, "SPW_MISMATCH"), (1 << 20, "SPW_MISMATCH")):
        cpw = tb.rng.getrandbits(28)
        spw = ((cpw >> 4) + offset) % (1 << 24)
        tb.queue(values=[frames.WordValue(cpw), frames.WordValue(spw, lc=sol.next())])
        res = await tb.request()
        tb.check_frame(res, status=status)
        assert res.fields["spw_mismatch"] == int(status != "OK")
    # Wrap-around: CPW at the top of its range, SPW already wrapped to 0.
    tb.queue(values=[frames.WordValue(2**28 - 1), frames.WordValue(0, lc=sol.next())])
    tb.check_frame(await tb.request())
    # Tolerance 0 is exact.
    tb.configure(fmt, 2.5e6, spw_tolerance=0)
    tb.queue(values=[frames.WordValue(0x1230), frames.WordValue(0x124, lc=sol.next())])
    tb.check_frame(await tb.request(), status="SPW_MISMATCH")


@cocotb.test()
@also_at_fast_clock
@long_on_icarus
async def line_faults_and_recovery(dut):
    tb = Testbench(dut, seed=8)
    await tb.start(cable=Cable(length_m=50))
    tb.configure(preset("resolute_fs_rsh"), 5e6)
    await frames_ok(tb, 1)

    async def expect(status, counter):
        before = tb.read().counters[counter]
        res = await tb.request()
        assert res.status == STATUS[status], f"status {res.status}, expected {status}"
        assert res.valid == 0
        assert res.counters[counter] == before + 1, counter
        return res

    # Encoder missing / line broken: SLO stays high.
    tb.queue(fault="no_response")
    await expect("NO_ACK", "no_ack")
    await frames_ok(tb, 1)
    tb.queue(fault="stuck_high")
    await expect("NO_ACK", "no_ack")
    await frames_ok(tb, 1)
    # Ack never ends.
    tb.queue(fault="ack_forever")
    await expect("NO_START", "no_start")
    await frames_ok(tb, 1)
    # Ack longer than the configured limit (20 us) but finite.
    dut.cfg_ack_limit.value = 2000
    tb.queue(processing_time_s=30e-6)
    await expect("NO_START", "no_start")
    dut.cfg_ack_limit.value = 0
    await frames_ok(tb, 1)
    # Timeout never ends after a good frame: that frame is fine, the next request reports it.
    tb.queue(fault="timeout_stuck")
    await frames_ok(tb, 1)
    await expect("SLO_STUCK_LOW", "slo_stuck_low")
    await expect("SLO_STUCK_LOW", "slo_stuck_low")
    tb.encoder.clear_fault()
    res = await tb.request()
    tb.check_frame(res)
    # SLO shorted low on the cable, then repaired.
    tb.encoder.force_slo(0)
    await expect("SLO_STUCK_LOW", "slo_stuck_low")
    tb.encoder.force_slo(None)
    await frames_ok(tb, 1)
    # Cable unplugged (receiver fail-safe high) and plugged back. Unplug between cycles: with
    # SLO forced high the master cannot see that the encoder is still in its timeout.
    await tb.encoder_ready()
    tb.encoder.force_slo(1)
    await expect("NO_ACK", "no_ack")
    tb.encoder.force_slo(None)
    await frames_ok(tb, 1)
    # Round trip beyond the configured limit: reported with the measured delay.
    dut.cfg_delay_limit.value = 40
    res = await expect("DELAY_RANGE", "delay_range")
    rt = tb.clocks(Cable(length_m=50).round_trip_s())
    assert rt <= res.fields["line_delay"] < rt + 1
    dut.cfg_delay_limit.value = 0
    await frames_ok(tb, 1)


@cocotb.test()
@long_on_icarus
async def abort_and_break(dut):
    tb = Testbench(dut, seed=9)
    await tb.start(cable=Cable(length_m=20))
    tb.configure(preset("resolute_fs_rsh"), 1e6)
    await frames_ok(tb, 1)
    for delay_us in (0.5, 3, 20, 60):
        before = tb.read().counters["aborted"]
        await tb.wait_idle()
        await tb.encoder_ready()             # so that the abort hits a clocking cycle: the
        await Timer(1.2, "us")               # encoder ready, SLO high for the quiet time
        await RisingEdge(dut.clk)
        dut.start.value = 1
        await RisingEdge(dut.clk)
        dut.start.value = 0
        await Timer(delay_us, "us")
        await FallingEdge(dut.clk)              # away from the sampling edge
        dut.abort_cycle.value = 1
        done = cocotb.start_soon(tb.wait_done(limit_s=10e-6))
        await FallingEdge(dut.clk)
        dut.abort_cycle.value = 0
        res = await done
        assert res.status == STATUS["ABORTED"] and res.valid == 0
        assert res.counters["aborted"] == before + 1
        # MA stays high for the break (40 us) before anything else.
        await tb.wait_idle()
        # The encoder saw an abort, and the next frame decodes (LC re-synchronised).
        assert tb.encoder.records[-1].aborted, (delay_us, tb.encoder.records[-2:])
        await frames_ok(tb, 2)


@cocotb.test()
async def bad_configuration(dut):
    tb = Testbench(dut, seed=10)
    await tb.start()
    fmt = preset("resolute_fs_rsh")
    bad = [
        {"cfg_ma_half_period": 1}, {"cfg_ma_half_period": 0},
        {"cfg_w0_data_bits": 0}, {"cfg_w0_data_bits": 56}, {"cfg_w1_data_bits": 41},
        {"cfg_w0_crc": 3}, {"cfg_w1_crc": 3},
        {"cfg_w0_lc": 1},                                   # LC in both words
        {"cfg_w1_data_bits": 37},                           # SPW longer than the CPW
        {"cfg_w1_crc": 0},                                  # SPW check without the SPW CRC
    ]
    for override in bad:
        tb.configure(fmt, 5e6, **override)
        await ClockCycles(dut.clk, 2)               # written at the next edge, then seen
        assert int(dut.config_error.value) == 1, override
        cycles = len(tb.encoder.records)
        res = await tb.request(limit_s=1e-6)
        assert res.status == STATUS["BAD_CONFIG"] and res.valid == 0, override
        await Timer(5, "us")
        assert len(tb.encoder.records) == cycles, "a cycle started with a bad configuration"
        assert int(dut.ma.value) == 1
    tb.configure(fmt, 5e6)
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    assert int(dut.config_error.value) == 0
    await frames_ok(tb, 2)


@cocotb.test()
async def config_change_during_a_cycle(dut):
    """The cycle keeps the configuration it started with."""
    tb = Testbench(dut, seed=12)
    await tb.start()
    tb.configure(preset("evolute_36"), 1e6)
    await RisingEdge(dut.clk)
    dut.start.value = 1
    await RisingEdge(dut.clk)
    dut.start.value = 0
    await Timer(10, "us")
    dut.cfg_w0_data_bits.value = 26
    dut.cfg_ma_half_period.value = 20
    res = await tb.wait_done()
    tb.check_frame(res)


@cocotb.test()
async def periodic_requests_and_overrun(dut):
    tb = Testbench(dut, seed=13)
    await tb.start(cable=Cable(length_m=100))
    fmt = preset("resolute_fs_rsh")
    tb.configure(fmt, 10e6)
    # As fast as possible: the encoder's 31.25 us rule sets the pace; no overruns.
    dut.periodic.value = 1
    first = len(tb.encoder.records)
    for _ in range(6):
        res = await tb.wait_done()
        tb.check_frame(res)
    records = tb.encoder.records[first:]
    starts = [r.t_first_fall_s for r in records]
    assert min(b - a for a, b in zip(starts, starts[1:])) >= 31.25e-6 - 1e-9
    # The master's own dead time: from SLO high at its pin to its next MA fall, the quiet time
    # (1 us by default: SLO must stay high that long, docs/ports.md) plus at most one MA period
    # (0.1 us) for the two synchronizer flops and the controller's decisions; with the quiet
    # time at 1 clock (the check off), that MA period alone.
    cable = Cable(length_m=100)

    def dead_times(recs):
        for prev, nxt in zip(recs, recs[1:]):
            slo_high_at_master = prev.t_ready_s + 42.5e-9 + cable.e2m_s()
            yield nxt.t_first_fall_s - slo_high_at_master

    for dead in dead_times(records):
        assert 1e-6 < dead <= 1.1e-6, f"dead time {dead * 1e9:.1f} ns"
    dut.cfg_quiet_time.value = 1
    first = len(tb.encoder.records)
    for _ in range(4):
        res = await tb.wait_done()
        tb.check_frame(res)
    for dead in list(dead_times(tb.encoder.records[first:]))[1:]:
        assert 0 < dead <= 0.1e-6, f"dead time {dead * 1e9:.1f} ns (quiet time 1 clock)"
    dut.cfg_quiet_time.value = 0
    assert res.counters["overrun"] == 0
    assert not tb.encoder.ignored_falls
    # A fixed period of 50 us: one frame per period, start-to-start exact.
    dut.periodic.value = 0
    await tb.wait_idle()
    dut.cfg_request_period.value = 5000
    dut.periodic.value = 1
    first = len(tb.encoder.records)
    for _ in range(5):
        tb.check_frame(await tb.wait_done())
    # The first request of the new period may wait for the encoder (SLO low), and the second
    # for the quiet time after the first's timeout (docs/ports.md): skip them.
    starts = [r.t_first_fall_s for r in tb.encoder.records[first + 2:]]
    gaps = {round((b - a) * 1e9) for a, b in zip(starts, starts[1:])}
    assert gaps == {50_000}, gaps
    # A period shorter than the frame: requests are reported as overruns, not dropped silently.
    dut.periodic.value = 0
    await tb.wait_idle()
    dut.cfg_request_period.value = 500              # 5 us
    dut.periodic.value = 1
    for _ in range(3):
        tb.check_frame(await tb.wait_done())
    dut.periodic.value = 0
    assert tb.read().counters["overrun"] > 0
    # A single-shot start while busy is an overrun too.
    await tb.wait_idle()
    before = tb.read().counters["overrun"]
    await RisingEdge(dut.clk)
    dut.start.value = 1
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)                       # second clock of start: core already busy
    dut.start.value = 0
    tb.check_frame(await tb.wait_done())
    assert tb.read().counters["overrun"] == before + 1
    # Counters clear, one clock after the clear is sampled (docs/ports.md, Counters).
    dut.clear_counters.value = 1
    await RisingEdge(dut.clk)
    dut.clear_counters.value = 0
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    assert all(v == 0 for v in tb.read().counters.values())


@cocotb.test()
async def verdict_latency(dut):
    """done/valid come exactly 3 clocks after the last CRC bit is decided (docs/timing.md: the
    decoder reads each decision one clock after the sampler makes it), for both words' CRCs and
    for a frame whose last CRC bit is corrupted."""
    tb = Testbench(dut, seed=14)
    await tb.start(cable=Cable(length_m=100))
    samples = []

    async def watch():
        while True:
            await RisingEdge(dut.sampler.sample)    # the sampler's decision, one per slot
            samples.append(get_sim_time("step"))

    watcher = cocotb.start_soon(watch())
    clk_steps = round(1e12 / CLK_HZ)
    for name, ma_hz in (("resolute_fs_rsh", 10e6), ("evolute_26", 2.5e6), ("bp3_1", 10e6)):
        fmt = preset(name)
        tb.configure(fmt, ma_hz)
        for faults in (None, frames.FrameFaults(flip_bits=(2 + fmt.total_bits - 1,))):
            tb.queue(faults=faults)
            samples.clear()
            res = await tb.request()
            t_done = round(res.t_done_s * 1e12)      # the done edge (ps steps)
            tb.check_frame(res, status="OK" if faults is None else
                              ("CRC_ERROR_WORD1" if len(fmt.words) == 2 else "CRC_ERROR_WORD0"))
            last_bit = [t for t in samples if t <= t_done][-1]
            assert t_done - last_bit == 3 * clk_steps, \
                f"{name}: done {(t_done - last_bit) / clk_steps} clocks after the last CRC bit"
    watcher.cancel()


@cocotb.test()
@only_on_builds("biss-c", "biss-c-lean")
@long_on_icarus
async def biss_c_only_build(dut):
    """The BiSS-C-only builds (one 36-bit word, CRC-6; the lean one without counters and
    timestamp): single-word presets up to 36 bits at every MA rate over 0 and 100 m, a CRC
    error, and what that build must refuse."""
    tb = Testbench(dut, seed=15)
    assert tb.words == 1, "run this on the one-word build"
    await tb.start()
    names = ["evolute_26", "evolute_32", "evolute_36", "resolute_c_18", "resolute_c_36",
             "bp3_1", "bp3_13", "bp3_36"]
    for cable_m in (0, 100):
        tb.encoder.set_cable(Cable(length_m=cable_m))
        for name in names:
            for ma_hz in MA_RATES_HZ:
                tb.configure(preset(name), ma_hz)
                await frames_ok(tb, 1)
    fmt = preset("evolute_36")
    tb.configure(fmt, 10e6)
    tb.queue(faults=frames.FrameFaults(flip_bits=(2 + fmt.total_bits - 1,)))
    res = await tb.request()
    tb.check_frame(res, status="CRC_ERROR_WORD0")
    if tb.has_counters:
        assert res.counters["crc_word0"] == 1
    else:   # the lean build: no counter ports, no timestamp
        assert res.counters == {} and "timestamp" not in res.fields
    for bad in ({"cfg_w0_data_bits": 37}, {"cfg_w0_crc": 2}, {"cfg_w0_crc": 3}):
        tb.configure(fmt, 10e6, **bad)       # 37 bits, or CRC-16: not in this build
        res = await tb.request(limit_s=1e-6)
        assert res.status == STATUS["BAD_CONFIG"] and res.valid == 0, bad
    tb.configure(fmt, 10e6)
    await frames_ok(tb, 1)


async def stuck_from_stop_bit(tb, level):
    """One request whose line goes to ``level`` (and stays there) as the encoder starts its
    stop bit (the first low after the frame); returns the Result."""
    await tb.wait_idle()
    tb.queue()
    tb.dut.start.value = 1
    done = cocotb.start_soon(tb.wait_done())
    await RisingEdge(tb.dut.clk)
    tb.dut.start.value = 0
    for phase in ("data", "stop"):
        while tb.encoder.phase != phase:
            await RisingEdge(tb.dut.clk)
    # The encoder's output reaches the master pin half a round trip later; the master samples
    # the stop slot later still (near the middle of the bit).
    await Timer(round(tb.encoder.cable.round_trip_s() / 2 * 1e12) + 10_000, "ps")
    tb.encoder.force_slo(level)
    return await done


@cocotb.test()
@long_on_icarus
async def end_check(dut):
    """cfg_end_check: a frame is reported only after the encoder's timeout has ended (SLO back
    high); SLO high at the stop bit is NO_STOP and SLO low past the timeout limit is
    SLO_STUCK_LOW, in the same cycle, without reporting the frame. Without the check the
    same faults let the frame through and show up in the next cycle."""
    tb = Testbench(dut, seed=21)
    await tb.start(cable=Cable(length_m=20))
    count = lambda name: tb.read().counters[name]
    for name, ma_hz in (("resolute_c_36", 5e6), ("resolute_fs_rsh", 10e6), ("evolute_26", 1e6)):
        tb.configure(preset(name), ma_hz, cfg_end_check=1)
        for _ in range(3):
            res = await tb.request()
            tb.check_frame(res)
            assert dut.slo.value == 1 and tb.encoder.ready, "end check: done before the timeout ended"
        tb.configure(preset(name), ma_hz, cfg_end_check=0)
        res = await tb.request()
        tb.check_frame(res)
        assert not tb.encoder.ready, "no end check: done only after the encoder's timeout"

        for level, status, counter in ((1, "NO_STOP", "no_stop"), (0, "SLO_STUCK_LOW", "slo_stuck_low")):
            tb.configure(preset(name), ma_hz, cfg_end_check=1)
            await tb.wait_idle()
            before = count(counter), count("crc_word0")
            res = await stuck_from_stop_bit(tb, level)
            assert res.status == STATUS[status] and res.valid == 0, \
                f"{name}: stuck {level} at the stop bit gave status {res.status}"
            assert (count(counter), count("crc_word0")) == (before[0] + 1, before[1]), counter
            tb.encoder.force_slo(None)
            await frames_ok(tb, 1)

        # Without the check the frame is reported (it was good) before the stop bit.
        tb.configure(preset(name), ma_hz, cfg_end_check=0)
        tb.check_frame(await stuck_from_stop_bit(tb, 1))
        await tb.encoder_ready()         # (the master cannot see the timeout through the short)
        res = await tb.request()
        assert res.status == STATUS["NO_ACK"], res.status
        tb.encoder.force_slo(None)
        await frames_ok(tb, 1)

        # The encoder's timeout never ends: caught in the frame's own cycle.
        tb.configure(preset(name), ma_hz, cfg_end_check=1)
        tb.queue(fault="timeout_stuck")
        res = await tb.request()
        assert res.status == STATUS["SLO_STUCK_LOW"] and res.valid == 0, res.status
        tb.encoder.clear_fault()
        await frames_ok(tb, 1)


@cocotb.test()
async def cds_bit_of_every_frame(dut):
    """The CDS slot of every frame (the encoder's control-channel bit, the seam the control
    channel will read) is reported with that frame, bit for bit, on a BP3 and a Safety frame at
    10 MHz over 100 m, and a CRC error in the same frame does not hide it."""
    tb = Testbench(dut, seed=21)
    await tb.start(cable=Cable(length_m=100))
    pattern = [1, 0, 0, 1, 1, 1, 0, 1]
    for name in ("bp3_24", "resolute_fs_rsh"):
        tb.configure(preset(name), 10e6)
        for bit in pattern:
            tb.queue(faults=frames.FrameFaults(cds=bit))
            res = await tb.request()
            tb.check_frame(res)
            assert res.fields["cds"] == bit, (name, res.fields["cds"], bit)
    tb.queue(faults=frames.FrameFaults(cds=1, crc_xor=(1,)))
    res = await tb.request()
    assert res.status == STATUS["CRC_ERROR_WORD0"] and res.fields["cds"] == 1
# -- Noise immunity: crafted glitches (issue 12) -------------------------------------------------
NOISE_RATE_HZ = 1e6
NOISE_PRESET = "resolute_c_36"


async def glitch_on_ack_sample(tb, values, n_ack, glitch_slot, *, width=0.3, centre=0.0):
    """One request whose frame ``values`` comes after ``n_ack`` Ack slots, with a glitch high
    (``width`` of a bit) centred ``centre`` bits after the middle of Ack slot ``glitch_slot``;
    returns the Result."""
    rt = tb.encoder.cable.round_trip_s()

    async def inject():
        timing = await glitch.cycle_timing(tb.dut, NOISE_RATE_HZ, rt)
        length = round(width * timing.period)
        middle = timing.slot_start(glitch_slot) + timing.period // 2 + round(centre * timing.period)
        await Timer(middle - length // 2 - get_sim_time("step"), "step")
        width_steps = length
        await tb.encoder.glitch_slo(width_steps * 1e-12)

    tb.queue(values=[values], processing_time_s=glitch.processing_for_ack_slots(
        n_ack, NOISE_RATE_HZ))
    task = cocotb.start_soon(inject())
    res = await tb.request()
    await task
    return res


def assert_safe(tb, res, n_sent, what):
    """Not valid, or valid with the position the encoder latched in this very cycle."""
    new = len(tb.sent) == n_sent + 1
    true = frames.parse_frame(tb.fmt, tb.sent[-1].bits)["words"][0]["position"] if new else None
    got = res.fields["word0_position"]
    assert not res.valid or got == true, (
        f"{what}: status {STATUS_NAME[res.status]}, valid {res.valid}, position read {got:#x}, "
        + (f"true {true:#x}" if new else "the encoder latched none in this cycle"))


@cocotb.test()
async def glitch_in_the_ack_slips_the_frame(dut):
    """A glitch high of 30 % of a bit on the middle of Ack slot 1 (of 5). A master that decides
    each bit from one mid-eye sample (this core before issue 12) takes it for Start and reads
    the frame 4 slots early; the position is chosen (the encoder model's CRC) so that the
    slipped bits pass the CRC-6, and it reported a wrong position as valid. The safe outcome:
    not valid, or the true position (with three votes a quarter bit apart, the glitch inverts
    only the middle one)."""
    tb = Testbench(dut, seed=12)
    await tb.start()
    fmt = preset(NOISE_PRESET)
    n_ack, slot = 5, 1
    value, slipped = glitch.search_values(fmt, random.Random(12), lambda bits: (
        r if (r := glitch.slipped_reading(fmt, bits, n_ack, slot))["crc_ok"] else None))
    dut._log.info("sends %#x; the slipped reading is %#x, its CRC good", value.position,
                  slipped["words"][0]["position"])
    for end_check in (0, 1):
        tb.configure(fmt, NOISE_RATE_HZ, cfg_end_check=end_check)
        await frames_ok(tb, 1)
        n_sent = len(tb.sent)
        res = await glitch_on_ack_sample(tb, value, n_ack, slot)
        assert_safe(tb, res, n_sent, f"end check {end_check}")
        await tb.encoder_ready()


@cocotb.test()
async def clean_frame_after_a_slipped_one(dut):
    """A glitch high of 45 % of a bit over two of the three votes of Ack slot 1 (of 12: longer
    than the immunity, so Start is faked) slips the frame by 11 slots: the master reads it as a
    CRC error and stops the clock while the encoder still has 11 bits to send. The next request
    comes as soon as the master takes it, the line clean: it must read a new frame (the encoder's next position) or
    report a fault, never the tail of the old one. The position is chosen so that the tail, read
    as a frame, has a good CRC-6 (sim/shared/glitch.tail_reading)."""
    tb = Testbench(dut, seed=13)
    await tb.start()
    fmt = preset(NOISE_PRESET)
    n_ack, slot = 12, 1

    def accept(bits):
        if glitch.slipped_reading(fmt, bits, n_ack, slot)["crc_ok"]:
            return None                         # the glitched cycle itself must be a CRC error
        r = glitch.tail_reading(fmt, bits, n_ack, slot)
        return r if r is not None and r["crc_ok"] else None

    value, tail = glitch.search_values(fmt, random.Random(13), accept)
    dut._log.info("sends %#x; the next cycle would read its tail as %#x, CRC good",
                  value.position, tail["words"][0]["position"])
    tb.configure(fmt, NOISE_RATE_HZ)
    await frames_ok(tb, 1)
    # [-0.3, +0.15] bit around the middle: the first vote (a quarter bit before it) and the
    # middle one.
    res = await glitch_on_ack_sample(tb, value, n_ack, slot, width=0.45, centre=-0.075)
    assert not res.valid, f"the slipped frame: status {STATUS_NAME[res.status]}"
    n_sent = len(tb.sent)
    tb.queue()
    res = await tb.request()
    assert_safe(tb, res, n_sent, "the cycle after the slipped frame")
