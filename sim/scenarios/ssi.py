"""cocotb regression of ``biss_master``'s SSI channel mode (cfg_ssi = 1) against the SSI encoder
model (encoder_model.cocotb_ssi on the pins, encoder_model.ssi for the bits).

Run through pytest (sim/test_regression.py) on Verilator and Icarus, on the default build only:
the builds with the cfg_ssi ports (master_contract.SSI_BUILDS); no marker, so discovery gives
each scenario the default build and nothing else. Every scenario checks each result's status,
``valid``, ``line_delay``, the position / flags against what the encoder latched and sent, and
the MA pulses the encoder saw (sim/shared/ssi_testbench.SsiTestbench.check).
"""

import cocotb
from cocotb.triggers import ClockCycles, RisingEdge, Timer

from encoder_model.cocotb_encoder import Cable
from encoder_model.cocotb_ssi import SsiFaults
from encoder_model.frames import CRC6, CustomCrc
from encoder_model.ssi import SsiFormat
from master_contract import (DEFAULT_TIMEOUT_LIMIT_S, QUIET_TIME_S, SSI_BAD_CONFIGS,
                             ssi_vote_margin)
from sim.shared.ssi_testbench import SsiTestbench
from sim.shared.testbench import CLK_HZ

SHORT = Cable(length_m=5)


async def bench(dut, seed, fmt, ma_hz, *, cable=SHORT, **cfg):
    tb = SsiTestbench(dut, seed=seed)
    await tb.start(cable=cable, fmt=fmt)
    tb.configure_ssi(fmt, ma_hz, **cfg)
    return tb


async def frames_ok(tb, n):
    for _ in range(n):
        tb.check(await tb.request())


@cocotb.test()
async def ssi_gray_singleturn(dut):
    """13-bit Gray singleturn at 1 MHz over a short cable: 20 random positions, reported
    binary."""
    tb = await bench(dut, 101, SsiFormat(13, gray=True), 1e6)
    await frames_ok(tb, 20)
    await tb.finish()


@cocotb.test()
async def ssi_error_bit(dut):
    """25-bit binary with one error bit after the position, active high then active low:
    inactive -> ne 1, active -> ne 0; the frame is OK either way."""
    tb = SsiTestbench(dut, seed=102)
    await tb.start(cable=SHORT)
    for polarity in ("high", "low"):
        tb.configure_ssi(SsiFormat(25, error_bits=1, error_polarity=(polarity,)), 5e6)
        for active in (False, True, True, False):
            tb.errors = (active,)
            res = await tb.request()
            rec = tb.check(res)
            assert rec.errors == (active,)
            # the line level of the error bit, as the polarity says
            assert rec.levels[25] == int(active == (polarity == "high")), rec.levels
            assert res.fields["word0_ne"] == int(not active)
    await tb.finish()


@cocotb.test()
async def ssi_double_transmission(dut):
    """Double transmission (the encoder in ring mode: word, 0, word): OK frames; one bit of
    the second copy flipped, or the separator bit 1 -> SPW_MISMATCH, not valid; recovery
    UNCONFIRMED then OK."""
    tb = await bench(dut, 103, SsiFormat(25), 5e6, double=True)
    await frames_ok(tb, 3)
    for faults in (SsiFaults(flip_copy2=(7,)), SsiFaults(flip_copy2=(24,)),
                   SsiFaults(flip_copy2=(0,)), SsiFaults(separator=1)):
        tb.encoder.queue(faults)
        rec = tb.check(await tb.request(), "SPW_MISMATCH")
        assert rec.faults == faults
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "UNCONFIRMED"
        tb.check(res)
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "OK"
        tb.check(res)
    await tb.finish()


@cocotb.test()
async def ssi_unplugged_encoder(dut):
    """Unplugged encoder behind a fail-safe receiver (SLO stuck high) -> NO_STOP each cycle;
    plugged back -> UNCONFIRMED then OK. SLO shorted low -> SLO_STUCK_LOW after
    cfg_timeout_limit with no MA edge; repaired -> UNCONFIRMED then OK."""
    tb = await bench(dut, 104, SsiFormat(13, gray=True), 2.5e6)
    await frames_ok(tb, 1)
    await tb.wait_idle()
    await tb.encoder_ready()
    tb.encoder.force_slo(1)
    for _ in range(2):
        tb.check(await tb.request(), "NO_STOP")
    tb.encoder.force_slo(None)
    res = await tb.request()
    assert tb.expected_status(res, "OK") == "UNCONFIRMED"
    tb.check(res)
    await frames_ok(tb, 1)
    tb.encoder.force_slo(0)
    edges = tb.encoder.pin_edges
    for _ in range(2):
        res = await tb.request()
        tb.check(res, "SLO_STUCK_LOW", cycle=False)
    assert tb.encoder.pin_edges == edges, "MA moved while SLO was stuck low"
    tb.encoder.force_slo(None)
    res = await tb.request()
    assert tb.expected_status(res, "OK") == "UNCONFIRMED"
    tb.check(res)
    await frames_ok(tb, 1)
    await tb.finish()


@cocotb.test()
async def ssi_long_cable_10mhz(dut):
    """100 m of cable at 10 MHz (a round trip of over 10 MA half periods): cfg_ssi_delay the
    true round trip rounded; then off by half_period // 2 - 1 clocks each way."""
    cable = Cable(length_m=100)
    tb = await bench(dut, 105, SsiFormat(24), 10e6, cable=cable)
    true = tb.true_delay_clocks()
    assert true > 10 * tb.half_period
    await frames_ok(tb, 20)
    off = ssi_vote_margin(tb.half_period)
    assert off >= 1
    for delay in (round(true) - off, round(true) + off):
        tb.configure_ssi(SsiFormat(24), 10e6, delay=delay)
        await frames_ok(tb, 4)
    await tb.finish()


@cocotb.test()
async def ssi_monoflop_periodic(dut):
    """Periodic requests with cfg_request_period shorter than frame + tm: the master waits for
    SLO high (and the quiet time) before each train, so every train latches anew, whatever tm
    is (20 us, then 60 us: still below the 80 us SLO-low limit)."""
    tb = SsiTestbench(dut, seed=106)
    await tb.start(cable=SHORT)
    for tm_s in (20e-6, 60e-6):
        assert tm_s < DEFAULT_TIMEOUT_LIMIT_S
        fmt = SsiFormat(13, tm_s=tm_s)
        tb.configure_ssi(fmt, 10e6, cfg_request_period=round(10e-6 * CLK_HZ))
        first = len(tb.encoder.records)
        dut.periodic.value = 1
        for _ in range(6):
            tb.check(await tb.wait_done())
        dut.periodic.value = 0
        await tb.wait_idle()
        if len(tb.encoder.records) > tb.next_record:    # one more began before periodic fell
            tb.check(tb.read())
        recs = tb.encoder.records[first:]
        assert len(recs) in (6, 7)
        for prev, nxt in zip(recs, recs[1:]):
            # the next train's first fall reached the encoder after its line went high and
            # stayed high (at the master pin) for the quiet time
            assert nxt.t_latch_s >= prev.t_line_high_s + QUIET_TIME_S, (prev, nxt)
        await Timer(round(tm_s * 1e6) + 2, "us")
        tb.check_pending()
    await tb.finish()


@cocotb.test()
async def ssi_bad_configuration(dut):
    """What SSI refuses (master_contract.SSI_BAD_CONFIGS): BAD_CONFIG, config_error high, and
    no MA edge at all; a good configuration afterwards runs."""
    fmt = SsiFormat(13)
    tb = await bench(dut, 107, fmt, 5e6)
    await frames_ok(tb, 1)
    for override in SSI_BAD_CONFIGS:
        tb.configure_ssi(fmt, 5e6, **override)
        await ClockCycles(dut.clk, 2)
        assert int(dut.config_error.value) == 1, override
        edges = tb.encoder.pin_edges
        res = await tb.request(limit_s=1e-6)
        tb.check(res, "BAD_CONFIG", cycle=False)
        await Timer(5, "us")
        assert tb.encoder.pin_edges == edges, f"MA moved with {override}"
        assert int(dut.ma.value) == 1
    tb.configure_ssi(fmt, 5e6)
    await RisingEdge(dut.clk)
    await RisingEdge(dut.clk)
    assert int(dut.config_error.value) == 0
    await frames_ok(tb, 2)
    await tb.finish()


@cocotb.test()
async def ssi_extended_crc(dut):
    """Extended SSI: position, nE nW and a CRC over them (iC-MU MODEA 0x7). CRC-6 with every
    nE / nW combination: OK; one CRC bit flipped -> CRC_ERROR_WORD0 (crc_ok 0, the fields as
    sent). Then a signed Gray word with a custom CRC-8."""
    fmt = SsiFormat(19, nenw=True, crc=CRC6)
    tb = await bench(dut, 108, fmt, 2.5e6)
    for nenw in ((1, 1), (0, 1), (1, 0), (0, 0)):
        tb.nenw = nenw
        rec = tb.check(await tb.request())
        assert rec.nenw == nenw
    tb.nenw = (1, 1)
    for bit in (fmt.total_bits - 1, fmt.total_bits - 6):        # last and first CRC bit
        tb.encoder.queue(SsiFaults(flip=(bit,)))
        res = await tb.request()
        tb.check(res, "CRC_ERROR_WORD0")
        assert res.fields["word0_crc_ok"] == 0
        await frames_ok(tb, 2)                  # UNCONFIRMED, then OK (expected_status)
    fmt = SsiFormat(16, gray=True, nenw=True, crc=CustomCrc(8, 0x2F, start=0x5A))
    tb.configure_ssi(fmt, 2.5e6, signed=True)
    for position in (0x8000, 0xFFFF, 0x7FFF, 0x1234):           # negative ones sign-extended
        tb.position = position
        await frames_ok(tb, 1)
    tb.position = None
    tb.encoder.queue(SsiFaults(flip=(fmt.total_bits - 3,)))
    tb.check(await tb.request(), "CRC_ERROR_WORD0")
    await frames_ok(tb, 2)
    await tb.finish()
