"""cocotb scenarios of the C driver (sw/) on the AXI4-Lite bus top, two channels.

The driver, built as ``libbissmaster.so`` (path in ``BISS_DRIVER_LIB``), is called through
ctypes as a CPU would call it (sim/shared/c_driver.py); its register reads and writes are
AXI4-Lite transactions of cocotbext-axi's AxiLiteMaster on ``biss_master_axil``. Every
position it returns is checked against what that channel's encoder model sent
(``BusTestbench.check_result``); limits and status names come from the test side's own
tables (tb/master_contract.py) and the register map (sim/shared/regspec.py), never from the
driver. Run by sim/test_driver.py on Verilator and Icarus.
"""

import os
from ctypes import byref
from dataclasses import replace

import cocotb
from cocotb.triggers import ClockCycles, RisingEdge, with_timeout

from encoder_model import frames
from master_contract import CRC_CODE, MA_HALF_PERIOD_MIN, MAX_DATA_BITS, STATUS
from sim.shared.bus_testbench import CLK_HZ, BusTestbench
from sim.shared.c_driver import CDriver, Channel, Config, State

#: Channel 0 reads a RESOLUTE FS (BiSS Safety, 36 + 28 bits), channel 1 a RESOLUTE BiSS C
#: 26-bit: two different presets, configured by name through the driver.
PRESETS = ("resolute_fs_rsh", "resolute_c_26")
CHANNELS = len(PRESETS)
POLLS = 20_000          # biss_wait_done's limit: far beyond a frame (each poll is a bus read)


async def setup(dut, seed, ma_hz=(10_000_000, 5_000_000), **settings):
    """Clock, reset, an encoder model per channel, the driver; both channels configured from
    their presets at the MA rates ``ma_hz`` (biss_configure_preset), or, with ``settings``
    (biss_config_t fields), from the preset's configuration with those changed
    (biss_config_from_preset, biss_configure). Returns (tb, driver, channel handles)."""
    tb = BusTestbench(dut, seed=seed)
    await tb.start([frames.PRESETS[name] for name in PRESETS])
    drv = CDriver(os.environ["BISS_DRIVER_LIB"], tb.bus)
    chans = [await drv.channel(n) for n in range(CHANNELS)]
    for ch, name, ma in zip(chans, PRESETS, ma_hz):
        if not settings:
            await drv.check("biss_configure_preset", byref(ch), name.encode(), int(CLK_HZ), ma)
            continue
        cfg = Config()
        await drv.check("biss_config_from_preset", byref(cfg), name.encode(), int(CLK_HZ), ma)
        for field, value in settings.items():
            setattr(cfg, field, value)
        await drv.check("biss_configure", byref(ch), byref(cfg))
        for path, field in (("cfg_break", "break_time"), ("cfg_ack", "ack_limit")):
            if field in settings:
                assert (await tb.read_fields(path, ch.index))[field] == settings[field]
    await tb.encoders_ready()
    return tb, drv, chans


async def wait_idle(drv, ch, polls=POLLS):
    """Poll ``biss_read_state`` until the channel is idle (a start now is not an overrun)."""
    state = State()
    for _ in range(polls):
        await drv.check("biss_read_state", byref(ch), byref(state))
        if not state.busy:
            return state
    raise AssertionError(f"channel {ch.index} never idle")


async def sample(drv, ch):
    """One request through the driver: start, wait for done, the result."""
    await wait_idle(drv, ch)
    await drv.check("biss_start", byref(ch))
    await drv.check("biss_wait_done", byref(ch), POLLS)
    return await drv.result(ch)


@cocotb.test()
async def driver_reads_two_presets(dut):
    """Two channels configured from two presets by name; single requests, then periodic mode,
    every position checked against its encoder model; no counter moves."""
    tb, drv, chans = await setup(dut, seed=11)
    for n, ch in enumerate(chans):
        assert (ch.index, ch.max_data_bits[0], ch.max_data_bits[1]) == (n, *MAX_DATA_BITS)
    seqs = {n: [] for n in range(CHANNELS)}
    for _ in range(2):
        for n, ch in enumerate(chans):
            res = await sample(drv, ch)
            tb.check_result(n, res, seq=True)
            seqs[n].append(res["seq"])
    assert all(s == [1, 2] for s in seqs.values()), seqs
    # Periodic: every 40 us on channel 0, 50 us on channel 1.
    for ch, period in zip(chans, (4_000, 5_000)):
        await drv.check("biss_set_periodic", byref(ch), True, period)
    for _ in range(3):
        for n, ch in enumerate(chans):
            await drv.check("biss_wait_done", byref(ch), POLLS)
            res = await drv.result(ch)
            tb.check_result(n, res)
            seqs[n].append(res["seq"])
    for ch in chans:
        await drv.check("biss_set_periodic", byref(ch), False, 0)
    for n, ch in enumerate(chans):
        assert seqs[n] == sorted(set(seqs[n])), f"ch{n}: a result read twice: {seqs[n]}"
        assert await drv.counters(ch) == {k: 0 for k in (await drv.counters(ch))}, f"ch{n}"
    dut._log.info("seq per channel %s, %d bus transactions", seqs, drv.transactions)


@cocotb.test()
async def driver_trigger_samples_both_axes_at_once(dut):
    """biss_set_trigger_enable on both channels, one biss_trigger: both start in the same
    clock (equal timestamps, one MA rate), both positions the models'; twice."""
    tb, drv, chans = await setup(dut, seed=12, ma_hz=(10_000_000, 10_000_000))
    for ch in chans:
        await drv.check("biss_set_trigger_enable", byref(ch), True)
    times = []
    for _ in range(2):
        for ch in chans:
            await wait_idle(drv, ch)
        await drv.check("biss_trigger", byref(drv.bus))
        res = []
        for n, ch in enumerate(chans):
            await drv.check("biss_wait_done", byref(ch), POLLS)
            res.append(await drv.result(ch))
            tb.check_result(n, res[-1])
        assert res[0]["time"] == res[1]["time"], \
            f"timestamps {res[0]['time']} != {res[1]['time']}"
        times.append(res[0]["time"])
        await tb.encoders_ready()
    assert times[1] > times[0]
    dut._log.info("trigger timestamps %s", times)


@cocotb.test()
async def driver_handles_the_error_interrupt(dut):
    """Channel 1's encoder does not answer once: the request ends NO_ACK, the error interrupt
    (enabled through the driver) raises `irq`; the driver reads irq_pending, irq_status, the
    result and the no_ack counter, clears the causes, and `irq` falls. The next frame is good.
    Then a CRC error on channel 0 the same way (crc_word0 counter)."""
    # Explicit settings: a shorter Ack limit and break than the defaults (40 us each) keep the
    # faults short; the encoder's timeout (12.5 us) plus the round trip stays inside the break.
    tb, drv, chans = await setup(dut, seed=13, ack_limit=1_000, break_time=2_000)
    irq_masks = {c: tb.map.channel["irq_status"].fields[c].mask for c in ("done", "error")}

    def fail_once(n, make):
        """The next response of channel n's encoder made by ``make(response, t_latch)``."""
        enc = tb.channels[n].encoder
        good = enc.respond

        def respond(t):
            enc.respond = good
            return make(good(t), t)
        enc.respond = respond

    async def error_irq(n, fault_status, counter):
        ch = chans[n]
        await drv.check("biss_irq_enable", byref(ch), irq_masks["error"])
        await wait_idle(drv, ch)
        assert int(dut.irq.value) == 0
        await drv.check("biss_start", byref(ch))
        await with_timeout(RisingEdge(dut.irq), 100, "us")
        assert await drv.call("biss_irq_pending", byref(drv.bus)) == 1 << n
        status = await drv.call("biss_irq_status", byref(ch))
        assert status == irq_masks["done"] | irq_masks["error"], f"irq_status {status:#x}"
        res = await drv.result(ch)
        name = drv.lib.biss_status_name(res["status"]).decode()
        assert (res["status"], name) == (STATUS[fault_status], fault_status), (res, name)
        assert (await drv.counters(ch))[counter] == 1
        await drv.check("biss_irq_clear", byref(ch), status)
        await ClockCycles(dut.clk, 3)                   # irq is registered
        assert int(dut.irq.value) == 0
        assert await drv.call("biss_irq_status", byref(ch)) == 0
        assert await drv.call("biss_irq_pending", byref(drv.bus)) == 0
        await drv.check("biss_irq_enable", byref(ch), 0)
        await tb.encoders_ready()
        tb.check_result(n, await sample(drv, ch))       # and on with good frames
        return res

    fail_once(1, lambda resp, t: replace(resp, fault="no_response"))
    await error_irq(1, "NO_ACK", "no_ack")

    def bad_crc(resp, t):
        bits = list(resp.bits)                          # [Start, CDS, word 0 ..., word 1 ...]
        bits[2 + frames.PRESETS[PRESETS[0]].words[0].total_bits - 1] ^= 1   # word 0's CRC
        return replace(resp, bits=bits)
    fail_once(0, bad_crc)
    res = await error_irq(0, "CRC_ERROR_WORD0", "crc_word0")
    assert res["w0_crc_ok"] == 0 and res["w1_crc_ok"] == 1


@cocotb.test()
async def driver_refuses_bad_settings(dut):
    """Out-of-range settings: each refused with its own error code before anything is
    written (the registers keep the good configuration, the core stays configured); the
    limits are the map's field widths and docs/ports.md's rules, from the test side."""
    tb, drv, chans = await setup(dut, seed=14)
    ch = chans[1]
    good = Config()
    await drv.check("biss_config_from_preset", byref(good), PRESETS[1].encode(), int(CLK_HZ),
                    2_500_000)
    assert good.ma_half_period == CLK_HZ // (2 * 2_500_000)
    w0 = frames.PRESETS[PRESETS[1]].words[0]
    assert (good.word[0].data_bits, good.word[0].crc, good.word1_enable) == \
        (w0.data_bits, CRC_CODE[w0.crc], False)
    field = {f"{r}.{f}": spec for r in ("cfg_ma", "cfg_period", "cfg_words", "cfg_checks")
             for f, spec in tb.map.channel[r].fields.items()}

    def width(path):
        return field[path].width

    def cfg(base=good, word0=None, word1=None, **changes):
        """A copy of ``base`` with some settings (and word formats' fields) changed."""
        c = Config.from_buffer_copy(base)
        for name, value in changes.items():
            setattr(c, name, value)
        for w, fields in enumerate((word0, word1)):
            for name, value in (fields or {}).items():
                setattr(c.word[w], name, value)
        return c

    safety = Config()
    await drv.check("biss_config_from_preset", byref(safety), PRESETS[0].encode(),
                    int(CLK_HZ), 5_000_000)
    cases = [
        ("BISS_ERR_MA_HALF_PERIOD", cfg(ma_half_period=MA_HALF_PERIOD_MIN - 1)),
        ("BISS_ERR_DELAY_LIMIT", cfg(delay_limit=1 << width("cfg_ma.delay_limit"))),
        ("BISS_ERR_TIME_RANGE", cfg(request_period=1 << width("cfg_period.request_period"))),
        ("BISS_ERR_DATA_BITS", cfg(word0={"data_bits": 0})),
        ("BISS_ERR_DATA_BITS", cfg(word0={"data_bits": MAX_DATA_BITS[0] + 1})),
        ("BISS_ERR_CRC", cfg(word0={"crc": 3})),
        ("BISS_ERR_DATA_BITS", cfg(word1_enable=True, word1={"data_bits": MAX_DATA_BITS[1] + 1})),
        ("BISS_ERR_LC", cfg(word1_enable=True, word0={"lc": True},
                            word1={"data_bits": 8, "lc": True})),
        ("BISS_ERR_SPW_CHECK", cfg(spw_check=True)),                # no word 1
        ("BISS_ERR_SPW_CHECK", cfg(safety, word1={"data_bits": safety.word[0].data_bits + 1})),
    ]
    before = {r: await tb.read(r, 1) for r in ("cfg_ma", "cfg_period", "cfg_words", "cfg_checks")}
    for want, bad in cases:
        got = drv.error_name(await drv.call("biss_configure", byref(ch), byref(bad)))
        assert got == want, f"{want} expected, driver said {got}"
    after = {r: await tb.read(r, 1) for r in before}
    assert after == before, "a refused configuration was written"
    assert (await tb.read_fields("state", 1))["config_error"] == 0

    # Names and rates.
    got = await drv.call("biss_configure_preset", byref(ch), b"resolute_c_27", int(CLK_HZ), 2_500_000)
    assert drv.error_name(got) == "BISS_ERR_UNKNOWN_PRESET"
    got = await drv.call("biss_configure_preset", byref(ch), PRESETS[1].encode(), int(CLK_HZ), 20_000_000)
    assert drv.error_name(got) == "BISS_ERR_MA_RATE", "20 MHz is above BiSS C's 10 MHz"
    got = await drv.call("biss_channel_init", byref(Channel()), byref(drv.bus), CHANNELS)
    assert drv.error_name(got) == "BISS_ERR_CHANNEL"
    # Reconfiguring while periodic requests run is refused; stopped, it is accepted.
    await drv.check("biss_set_periodic", byref(ch), True, 20_000)
    got = await drv.call("biss_configure", byref(ch), byref(good))
    assert drv.error_name(got) == "BISS_ERR_RUNNING"
    await drv.check("biss_set_periodic", byref(ch), False, 0)
    await drv.check("biss_configure", byref(ch), byref(good))
    await tb.encoders_ready()
    tb.check_result(1, await sample(drv, ch))
