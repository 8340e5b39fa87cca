"""cocotb regression of ``biss_master``'s SSI channel mode (cfg_ssi = 1) against the SSI encoder
model (encoder_model.cocotb_ssi on the pins, encoder_model.ssi for the bits).

Run through pytest (sim/test_regression.py) on Verilator and Icarus, on the default build only:
the builds with the cfg_ssi ports (master_contract.SSI_BUILDS); no marker, so discovery gives
each scenario the default build and nothing else. Every scenario checks each result's status,
``valid``, ``line_delay``, the position / flags against what the encoder latched and sent, and
the MA pulses the encoder saw (sim/shared/ssi_testbench.SsiTestbench.check).
"""

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge, Timer, with_timeout

from encoder_model.cocotb_encoder import BissEncoder, Cable
from encoder_model.cocotb_ssi import SsiFaults
from encoder_model.frames import CRC6, CRC16, CustomCrc
from encoder_model.ssi import SsiFormat
from master_contract import (CA_COUNTERS, CA_STATUS, DEFAULT_TIMEOUT_LIMIT_S, MAX_DATA_BITS,
                             QUIET_TIME_S, SSI_ACCESS_STATUS, SSI_BAD_CONFIGS, SSI_DELAY_MAX,
                             STATUS, STATUS_NAME, ssi_vote_margin)
from protocol_facts import ENCODER_INTERNAL_DELAY_S
from sim.shared.discovery import long_on_icarus
from sim.shared.ssi_testbench import SsiTestbench
from sim.shared.testbench import CLK_HZ, MA_RATES_HZ, preset

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
@long_on_icarus
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
        res = await tb.request()
        rec = tb.check(res, "SPW_MISMATCH")
        assert rec.faults == faults
        # the position reported is the first copy's (master_contract.SSI_DOUBLE_REPORTS)
        assert res.fields["word0_position"] == rec.position
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "UNCONFIRMED"
        tb.check(res)
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "OK"
        tb.check(res)
    # an encoder that sends zeros after its word, read with double transmission: every frame
    # SPW_MISMATCH (a word of zeros alone would match its zeros)
    tb.configure_ssi(SsiFormat(25), 5e6, double=True, repeat="zeros")
    tb.position = 0x1000001
    for _ in range(2):
        res = await tb.request()
        tb.check(res, "SPW_MISMATCH")
        assert res.fields["word0_position"] == 0x1000001
    tb.position = None
    tb.configure_ssi(SsiFormat(25), 5e6, double=True)
    await frames_ok(tb, 2)
    await tb.finish()


@cocotb.test()
async def ssi_unplugged_encoder(dut):
    """Unplugged encoder behind a fail-safe receiver (SLO stuck high) -> NO_STOP each cycle;
    plugged back -> UNCONFIRMED then OK. SLO shorted low -> SLO_STUCK_LOW cfg_timeout_limit
    after MA stopped (80 us by default, then 30 us), with no MA edge; repaired -> UNCONFIRMED
    then OK."""
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
    for limit_s in (DEFAULT_TIMEOUT_LIMIT_S, 30e-6):
        cfg = {} if limit_s == DEFAULT_TIMEOUT_LIMIT_S else {
            "cfg_timeout_limit": round(limit_s * CLK_HZ)}
        tb.configure_ssi(tb.ssi_fmt, 2.5e6, **cfg)
        await frames_ok(tb, 1)
        # MA stopped at its last rise (at the pin: the encoder saw it a cable delay later)
        t_stop = tb.encoder.records[-1].t_rises_s[-1] - tb.cable.m2e_s()
        tb.encoder.force_slo(0)
        edges = tb.encoder.pin_edges
        for i in range(2):
            res = await tb.request()
            tb.check(res, "SLO_STUCK_LOW", cycle=False)
            if i == 0:      # SLO low for cfg_timeout_limit after MA stopped (its last high
                # half period over), + 1 clock and the verdict's few clocks
                late = tb.half_period / CLK_HZ + 10 / CLK_HZ
                assert limit_s <= res.t_done_s - t_stop <= limit_s + late, \
                    f"SLO_STUCK_LOW {(res.t_done_s - t_stop) * 1e6:.3f} us after MA stopped"
        assert tb.encoder.pin_edges == edges, "MA moved while SLO was stuck low"
        tb.encoder.force_slo(None)
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "UNCONFIRMED"
        tb.check(res)
        await frames_ok(tb, 1)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_long_cable_10mhz(dut):
    """100 m of cable at 10 MHz (a round trip of over 10 MA half periods): cfg_ssi_delay the
    true round trip rounded; then off by half_period // 2 - 1 clocks each way (1 clock), and
    at 1 MHz the same (24 clocks)."""
    cable = Cable(length_m=100)
    tb = await bench(dut, 105, SsiFormat(24), 10e6, cable=cable)
    true = tb.true_delay_clocks()
    assert true > 10 * tb.half_period
    await frames_ok(tb, 20)
    for ma_hz in (10e6, 1e6):
        tb.configure_ssi(SsiFormat(24), ma_hz)
        off = ssi_vote_margin(tb.half_period)
        assert off >= 1
        for delay in (round(true) - off, round(true) + off):
            tb.configure_ssi(SsiFormat(24), ma_hz, delay=delay)
            await frames_ok(tb, 4 if ma_hz == 10e6 else 2)
    await tb.finish()


@cocotb.test()
@long_on_icarus
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
@long_on_icarus
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
@long_on_icarus
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


@cocotb.test()
@long_on_icarus
async def ssi_word_lengths(dut):
    """The shortest and the longest words: 1 and 2 position bits, 33 signed, 55 Gray (the
    widest cfg_w0_data_bits of the default build), with an error bit, double transmission and
    a CRC-16 after nE nW: every pulse count N + 1 / 2N + 2 and every field."""
    tb = SsiTestbench(dut, seed=109)
    await tb.start(cable=SHORT)
    cases = [(SsiFormat(1), {}), (SsiFormat(2, error_bits=1), {"double": True}),
             (SsiFormat(33, error_bits=1, error_polarity=("low",)), {"signed": True}),
             (SsiFormat(MAX_DATA_BITS[0], gray=True), {"double": True}),
             (SsiFormat(MAX_DATA_BITS[0], nenw=True, crc=CRC16), {"double": True}),
             (SsiFormat(40, gray=True, error_bits=1), {"signed": True, "double": True})]
    for fmt, cfg in cases:
        tb.configure_ssi(fmt, 5e6, **cfg)
        for position in (None, (1 << fmt.data_bits) - 1, 1 << (fmt.data_bits - 1)):
            tb.position = position
            tb.errors = (position is None,)
            tb.nenw = (0, 1) if position is None else (1, 1)
            await frames_ok(tb, 1)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_ma_rates_with_jitter(dut):
    """Every MA rate of the regression (250 kHz .. 10 MHz) over 0 and 100 m, each edge jittered
    by up to 5 % of the MA period each way: a 17-bit Gray word with an active-low error bit."""
    tb = SsiTestbench(dut, seed=110)
    await tb.start()
    fmt = SsiFormat(17, gray=True, error_bits=1, error_polarity=("low",))
    for cable_m in (0, 100):
        for ma_hz in MA_RATES_HZ:
            tb.set_cable(Cable(length_m=cable_m, jitter_s=0.05 / ma_hz))
            tb.configure_ssi(fmt, ma_hz)
            for active in (False, True):
                tb.errors = (active,)
                await frames_ok(tb, 1)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_round_trip_of_many_periods(dut):
    """cfg_ssi_delay far beyond the frame: 3000 clocks (30 us) and the largest, 4095 clocks,
    at 10 MHz (a round trip of hundreds of MA periods) and at 1 MHz, with double transmission."""
    tb = SsiTestbench(dut, seed=111)
    await tb.start()
    for clocks in (3000, SSI_DELAY_MAX):
        tb.set_cable(Cable(extra_round_trip_s=clocks / CLK_HZ - ENCODER_INTERNAL_DELAY_S))
        assert round(tb.true_delay_clocks()) == clocks
        for ma_hz, double in ((10e6, False), (10e6, True), (1e6, False)):
            tb.configure_ssi(SsiFormat(24, gray=True), ma_hz, double=double)
            await frames_ok(tb, 2)
    await tb.finish()


async def start_and_abort(tb, after_us):
    """One request once the encoder is ready, ``abort_cycle`` for one clock ``after_us`` later:
    the cycle must end ABORTED. Returns the encoder's record of the aborted train."""
    dut = tb.dut
    await tb.wait_idle()
    await tb.encoder_ready()
    await Timer(1.2, "us")
    await RisingEdge(dut.clk)
    dut.start.value = 1
    await RisingEdge(dut.clk)
    dut.start.value = 0
    await Timer(after_us, "us")
    await FallingEdge(dut.clk)
    dut.abort_cycle.value = 1
    done = cocotb.start_soon(tb.wait_done(limit_s=10e-6))
    await FallingEdge(dut.clk)
    dut.abort_cycle.value = 0
    return tb.check(await done, "ABORTED")


@cocotb.test()
@long_on_icarus
async def ssi_abort(dut):
    """abort_cycle in the middle of an SSI train: ABORTED, not valid, MA back high with fewer
    pulses than the word needs; the next cycle waits for the encoder's line (tm) and latches
    anew: OK (ABORTED calls for no confirmation)."""
    fmt = SsiFormat(13, gray=True)
    tb = await bench(dut, 112, fmt, 1e6)
    await frames_ok(tb, 1)
    for delay_us in (4, 9):
        rec = await start_and_abort(tb, delay_us)
        assert rec.ma_rises < tb.pulses, rec
        res = await tb.request()
        assert tb.expected_status(res, "OK") == "OK"
        nxt = tb.check(res)
        assert nxt.t_latch_s >= rec.t_line_high_s, "a train within tm after the abort"
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_and_biss_alternate(dut):
    """cfg_ssi is taken per cycle: SSI frames, then BiSS frames from a BiSS encoder on the same
    pins (the SSI one unplugged), then SSI again; each mode's frames are right."""
    tb = await bench(dut, 113, SsiFormat(20), 5e6)
    ssi_encoder = tb.encoder
    await frames_ok(tb, 2)
    for round_ in range(2):
        await tb.wait_idle()
        await Timer(round(tb.ssi_fmt.tm_s * 1e6) + 2, "us")
        tb.check_pending()
        ssi_encoder.stop()
        tb.encoder = BissEncoder(dut.ma, dut.slo, cable=SHORT, respond=tb._respond,
                                 rng=tb.rng)
        tb.encoder.start()
        tb.configure(preset("resolute_fs_rsh" if round_ else "bp3_24"), 5e6)
        for _ in range(2):
            tb.check_frame(await tb.request())
        await tb.wait_idle()
        await tb.encoder_ready()
        tb.check_pending()
        assert not tb.pending
        tb.encoder.stop()
        tb.encoder = ssi_encoder
        ssi_encoder.start()
        tb.configure_ssi(SsiFormat(20, error_bits=1), 5e6, double=bool(round_))
        await frames_ok(tb, 2)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_stop_bit_high(dut):
    """The encoder's own bit after the word is 1 (the line otherwise fine): NO_STOP, not valid;
    with double transmission the bit after copy 2. Recovery: UNCONFIRMED, then OK."""
    tb = await bench(dut, 114, SsiFormat(21, gray=True), 5e6)
    await frames_ok(tb, 1)
    for double in (False, True):
        tb.configure_ssi(SsiFormat(21, gray=True), 5e6, double=double)
        tb.encoder.queue(SsiFaults(force=((tb.pulses - 1, 1),)))
        rec = tb.check(await tb.request(), "NO_STOP")
        assert rec.levels[-1] == 1 and rec.levels[:rec.fmt.total_bits] == rec.word
        await frames_ok(tb, 2)                  # UNCONFIRMED, then OK (expected_status)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_config_latched_per_cycle(dut):
    """The configuration is latched when the cycle starts: changing the word, the delay and
    cfg_ssi itself during an SSI cycle changes nothing in it."""
    fmt = SsiFormat(30, error_bits=1)
    tb = await bench(dut, 115, fmt, 1e6)
    await frames_ok(tb, 1)
    for change in ({"cfg_w0_data_bits": 12}, {"cfg_ssi": 0}, {"cfg_ssi_double": 1},
                   {"cfg_ssi_delay": 900, "cfg_ma_half_period": 20}):
        await tb.wait_idle()
        await RisingEdge(dut.clk)
        dut.start.value = 1
        await RisingEdge(dut.clk)
        dut.start.value = 0
        await Timer(8, "us")                    # the train is running
        for name, value in change.items():
            getattr(dut, name).value = value
        tb.check(await tb.wait_done())
        tb.configure_ssi(fmt, 1e6)              # back, for the next cycle
    await tb.finish()


@cocotb.test()
async def ssi_abort_with_long_monoflop(dut):
    """An abort leaves the encoder mid-word with its line HIGH (every bit 1) and tm 60 us,
    longer than the break after an abort: the next cycle must still latch anew (the contract:
    tm is always respected, however long), and report that latch's position."""
    fmt = SsiFormat(13, tm_s=60e-6)
    tb = await bench(dut, 116, fmt, 1e6)
    await frames_ok(tb, 1)
    tb.position = (1 << 13) - 1
    rec = await start_and_abort(tb, 6)
    assert rec.levels and rec.levels[-1] == 1, "the line is left high"
    tb.position = 0x0A5A
    res = await tb.request()
    nxt = tb.check(res)
    assert nxt.t_latch_s >= rec.t_line_high_s, "the next train came within tm"
    await tb.finish()


async def glitch_at_bit(tb, k, width=6):
    """SLO inverted at the master pin for ``width`` clocks around the centre vote of bit k
    (MA rising edge k + 1 + cfg_ssi_delay + one half period)."""
    dut = tb.dut
    for _ in range(k + 1):
        await RisingEdge(dut.ma)
    clk_ns = 1e9 / CLK_HZ
    await Timer(round((tb.ssi_delay + tb.half_period - width / 2) * clk_ns * 1000), "ps")
    tb.encoder.force_slo(1 - int(dut.slo.value))
    await Timer(round(width * clk_ns * 1000), "ps")
    tb.encoder.force_slo(None)


@cocotb.test()
@long_on_icarus
async def ssi_noise_glitch(dut):
    """A short glitch on one bit's centre vote: the majority still reads the bit, but it is a
    noise event: NOISY_LINE with cfg_noise_limit 0 (not valid), the frame OK with limit 1;
    then UNCONFIRMED / OK as the confirmation rule says."""
    fmt = SsiFormat(16, error_bits=1)
    tb = await bench(dut, 117, fmt, 1e6)
    await frames_ok(tb, 1)
    for limit, status in ((0, "NOISY_LINE"), (1, "OK"), (0, "NOISY_LINE")):
        tb.configure_ssi(fmt, 1e6, cfg_noise_limit=limit)
        for k in (7, 16):                   # a position bit, the error bit
            glitch = cocotb.start_soon(glitch_at_bit(tb, k))
            res = await tb.request()
            assert glitch.done()
            tb.check(res, status)
            if "noise_events" in res.fields:
                assert res.fields["noise_events"] == 1, res.fields["noise_events"]
            await frames_ok(tb, 2)
    await tb.finish()


@cocotb.test()
async def ssi_glitch_on_the_bit_after_the_word(dut):
    """The bit after the word (after copy 2 with double transmission) is decided by three votes
    like every other: a glitch on its centre vote leaves the 0 read, and is a noise event of
    this frame: NOISY_LINE with cfg_noise_limit 0 (docs/ports.md, "Noise: the line checks":
    events are counted to this frame's end, the decision of its last bit), and the next frame
    has none (UNCONFIRMED, then OK). The campaign ``ssi`` glitches every other bit."""
    fmt = SsiFormat(13)
    tb = await bench(dut, 121, fmt, 5e6)
    for double in (False, True):
        tb.configure_ssi(fmt, 5e6, double=double)
        await frames_ok(tb, 1)
        glitch = cocotb.start_soon(glitch_at_bit(tb, tb.pulses - 1))
        res = await tb.request()
        assert glitch.done()
        assert res.status == STATUS["NOISY_LINE"], \
            (f"double {double}: the glitched frame {STATUS_NAME[res.status]} with noise_events "
             f"{res.fields.get('noise_events')}")
        tb.check(res, "NOISY_LINE")
        nxt = await tb.request()                # clean: no event left over for it
        if "noise_events" in nxt.fields:
            assert nxt.fields["noise_events"] == 0, nxt.fields["noise_events"]
        tb.check(nxt)
        await frames_ok(tb, 1)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_glitch_during_monoflop(dut):
    """A request waits for the encoder's line (tm); a 0.5 us high pulse of noise comes
    meanwhile, shorter than the quiet time: the master does not start on it (the train still
    latches anew after tm), and it is a noise event: NOISY_LINE with cfg_noise_limit 0, OK
    with 1."""
    fmt = SsiFormat(18, gray=True)
    tb = await bench(dut, 118, fmt, 2.5e6)
    for limit, status in ((0, "NOISY_LINE"), (1, "OK")):
        tb.configure_ssi(fmt, 2.5e6, cfg_noise_limit=limit)
        await frames_ok(tb, 2)                  # (UNCONFIRMED after a NOISY_LINE, then OK)
        prev = tb.encoder.records[-1]
        assert not tb.encoder.ready, "the encoder's line should still be low (tm)"

        async def noise():
            await Timer(5, "us")
            tb.encoder.force_slo(1)
            await Timer(500, "ns")
            tb.encoder.force_slo(None)

        pulse = cocotb.start_soon(noise())
        res = await tb.request()
        assert pulse.done()
        rec = tb.check(res, status)
        assert rec.t_latch_s >= prev.t_line_high_s + QUIET_TIME_S, "started within tm"
        if "noise_events" in res.fields:
            assert res.fields["noise_events"] >= 1
    await frames_ok(tb, 2)
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_end_check(dut):
    """cfg_end_check = 1 in SSI: done only once SLO is high again after the frame (the
    encoder's tm over); without it, done right after the bit after the word, SLO still low."""
    fmt = SsiFormat(16, gray=True)
    tb = await bench(dut, 119, fmt, 5e6)
    for end_check in (1, 0, 1):
        tb.configure_ssi(fmt, 5e6, cfg_end_check=end_check)
        for _ in range(2):
            res = await tb.request()
            rec = tb.check(res)
            if end_check:
                assert rec.ended and int(dut.slo.value) == 1, "done before the encoder's tm ended"
                assert res.t_done_s >= rec.t_line_high_s
            else:
                assert not rec.ended and int(dut.slo.value) == 0, "done waited for tm"
    await tb.finish()


@cocotb.test()
@long_on_icarus
async def ssi_register_access_refused(dut):
    """Register access has no channel in SSI: an access started while the channel runs SSI
    ends with DATA_FAULT at its first frame; the frames stay plain SSI (no CDM hold: MA back
    high after exactly the word's pulses)."""
    tb = await bench(dut, 120, SsiFormat(20), 2.5e6)
    await frames_ok(tb, 1)
    counter = CA_COUNTERS[SSI_ACCESS_STATUS]
    before = tb.read().counters[counter]            # the default build counts accesses
    await FallingEdge(dut.clk)
    dut.ca_slave_id.value = 0
    dut.ca_address.value = 0x42
    dut.ca_count.value = 1
    dut.ca_write.value = 0
    ca_done = cocotb.start_soon(RisingEdge(dut.ca_done))
    dut.ca_start.value = 1
    await FallingEdge(dut.clk)
    dut.ca_start.value = 0
    res = await tb.request()
    tb.check(res)
    await with_timeout(ca_done, 1, "us")
    await ReadOnly()
    assert int(dut.ca_status.value) == CA_STATUS[SSI_ACCESS_STATUS], int(dut.ca_status.value)
    await Timer(1, "ps")
    await frames_ok(tb, 2)
    assert tb.read().counters[counter] == before + 1
    await tb.finish()
