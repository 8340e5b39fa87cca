"""cocotb scenarios of the C driver (sw/) reading a chain of slaves (words 2..7 of the register
map) on the ``axil_chain`` bus top: an AXI4-Lite top (module biss_master_axil) of one channel
whose core decodes four words of up to master_contract.CHAIN_BUS_DATA_BITS = 64, 64, 64, 16
bits (sim/shared/runner.py builds it).

As in sim/scenarios/driver.py the driver, ``libbissmaster.so`` (path in ``BISS_DRIVER_LIB``),
is called through ctypes as a CPU would call it (sim/shared/c_driver.py), its reads and writes
AXI4-Lite transactions. Every word it returns is checked against the frame the encoder model
sent (looked up by the result's timestamp, parsed by encoder_model.frames, the port value by
master_contract.port_position); limits come from master_contract and the register map
(sim/shared/regspec.py), never from the driver or the RTL. Run by sim/test_driver.py on
Verilator and Icarus.
"""

import os
from ctypes import byref
from dataclasses import replace

import cocotb
from cocotb.triggers import ClockCycles, Timer

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import (CHAIN_BUS_DATA_BITS, STATUS_NAME, crc_config,
                             crc_counters, crc_status, port_position)
from sim.shared.bus_testbench import CHAIN_64, CLK_HZ, BusTestbench, Encoder
from sim.shared.c_driver import CHAIN_WORDS, CDriver, Config, Result, State

POLLS = 20_000          # biss_wait_done's limit: far beyond a frame (each poll is a bus read)
MA_HZ = 10_000_000
#: The chain of four slaves (issue 26): a RESOLUTE-like 26-bit word with CRC-6; a 17-bit
#: sensor with a CRC-8 of its own (x^8 + x^5 + x^3 + x^2 + x + 1, start 0xA5, sent
#: inverted); a 12-bit signed sensor without nE/nW with a CRC-4 (x^4 + x + 1, start 0x9, sent
#: plain; sign-extended to the build's 64 bits); a 16-bit Gray-coded sensor with CRC-16.
CHAIN_4 = frames.FrameFormat("chain_4", (
    frames.WordFormat(26),
    frames.WordFormat(17, crc=frames.CustomCrc(8, 0x2F, 0xA5, True)),
    frames.WordFormat(12, nenw=False, signed=True, crc=frames.CustomCrc(4, 0x3, 0x9, False)),
    frames.WordFormat(16, gray=True, crc=frames.CRC16),
), chain=True)
#: Three of the build's four words: issue 26's chain of three.
CHAIN_3 = frames.PRESETS["chain_3"]


def fast_encoder(fmt):
    """An encoder model that answers quickly (a short timeout, processing under a
    microsecond, no 31.25 us rule): frames back to back for the periodic scenario."""
    return Encoder(fmt, Cable(length_m=10), timeout_s=1.5 / MA_HZ,
                   processing_s=(0.3e-6, 0.8e-6), min_cycle_s=0)


async def setup(dut, seed, fmt, spec=None):
    """Clock, reset, the encoder model of ``fmt`` on channel 0 (each slave its own random
    position), the driver and its channel handle. Returns (tb, driver, channel)."""
    tb = BusTestbench(dut, seed=seed)
    await tb.start([spec or Encoder(fmt, Cable(length_m=10))])
    chan = tb.channels[0]
    chan.source.chain_positions_at = lambda t: [tb.rng.getrandbits(w.data_bits)
                                                for w in fmt.words]
    drv = CDriver(os.environ["BISS_DRIVER_LIB"], tb.bus)
    ch = await drv.channel(0)
    return tb, drv, ch


def set_word(cw, fw):
    """A biss_word_format_t from an encoder model's word format."""
    code, crc = crc_config(fw.crc)
    cw.data_bits, cw.nenw, cw.lc, cw.crc = fw.data_bits, fw.nenw, fw.lc, code
    cw.crc_width, cw.crc_poly, cw.crc_start = crc["width"], crc["poly"], crc["start"]
    cw.crc_inverted, cw.gray, cw.is_signed = bool(crc["inverted"]), fw.gray, fw.signed


async def chain_config(drv, fmt, **settings):
    """A configuration for ``fmt`` at MA_HZ (the preset's times, ``settings`` changed)."""
    cfg = Config()
    await drv.check("biss_config_from_preset", byref(cfg), b"resolute_c_26", int(CLK_HZ), MA_HZ)
    set_word(cfg.word[0], fmt.words[0])
    cfg.word1_enable = len(fmt.words) > 1
    if cfg.word1_enable:
        set_word(cfg.word[1], fmt.words[1])
    cfg.chain_words = max(len(fmt.words) - 2, 0)
    for i, fw in enumerate(fmt.words[2:]):
        set_word(cfg.chain[i], fw)
    for name, value in settings.items():
        setattr(cfg, name, value)
    return cfg


async def check_chain_registers(tb, fmt):
    """cfg_w2 .. cfg_w<build's last>, their CRC registers, as the frame format says: the
    words in the frame enabled with their settings, the others 0."""
    for w in range(2, len(CHAIN_BUS_DATA_BITS)):
        regs = {**await tb.read_fields(f"cfg_w{w}", 0), **await tb.read_fields(f"cfg_w{w}_crc", 0),
                **await tb.read_fields(f"cfg_w{w}_crc_start", 0)}
        if w >= len(fmt.words):
            assert not any(regs.values()), (w, regs)
            continue
        fw = fmt.words[w]
        code, crc = crc_config(fw.crc)
        want = {"data_bits": fw.data_bits, "nenw": int(fw.nenw), "lc": int(fw.lc),
                "crc": code, "gray": int(fw.gray), "is_signed": int(fw.signed), "enable": 1,
                "crc_poly": crc["poly"], "crc_width": crc["width"],
                "crc_inverted": crc["inverted"], "crc_start": crc["start"]}
        assert regs == want, (w, regs, want)


def check_frame(tb, fmt, res, status=None):
    """A result read through the driver against the frame the encoder sent at its timestamp:
    every word's data (as its port shows it), nE / nW (words that have them) and crc_ok, and
    the status (``status``; None: what the CRC verdicts give, else OK). Returns the parsed
    frame."""
    bits = tb.channels[0].sent.get(res["time"])
    assert bits is not None, f"no frame sent at timestamp {res['time']}"
    parsed = frames.parse_frame(fmt, bits)
    crc_ok = tuple(w["crc_ok"] for w in parsed["words"])
    want_status = status or crc_status(crc_ok) or "OK"
    assert STATUS_NAME[res["status"]] == want_status, (STATUS_NAME[res["status"]], want_status)
    assert res["chain_words"] == len(fmt.words) - 2
    for w, (fw, word) in enumerate(zip(fmt.words, parsed["words"])):
        want = port_position(fw, word["position"], CHAIN_BUS_DATA_BITS[w])
        got = res[f"word{w}"]
        assert got == want, f"word {w}: {got:#x}, sent {want:#x}"
        if fw.nenw:
            assert (res[f"w{w}_ne"], res[f"w{w}_nw"]) == (word["ne"], word["nw"]), w
        assert res[f"w{w}_crc_ok"] == int(word["crc_ok"]), (w, res[f"w{w}_crc_ok"])
    return parsed


async def wait_idle(drv, ch, polls=POLLS):
    state = State()
    for _ in range(polls):
        await drv.check("biss_read_state", byref(ch), byref(state))
        if not state.busy:
            return
    raise AssertionError("channel 0 never idle")


async def sample(drv, ch):
    """One request through the driver: start, wait for done, the result."""
    await wait_idle(drv, ch)
    await drv.check("biss_start", byref(ch))
    await drv.check("biss_wait_done", byref(ch), POLLS)
    return await drv.result(ch)


def send_next(tb, fmt, values=None, faults=None):
    """The encoder's next frame with these word values (None: its own) and faults; the frame
    as sent is what the checks parse."""
    chan = tb.channels[0]
    enc, good = chan.encoder, chan.encoder.respond

    def respond(t):
        enc.respond = good
        resp = good(t)
        vals = values or chan.source.values_at(t)
        bits = frames.build_frame(fmt, vals, faults)
        chan.sent[tb.timestamp_of(enc.records[-1].t_first_rise_s)] = bits
        return replace(resp, bits=bits)
    enc.respond = respond


def corner_values(fmt, k):
    """Every word at a corner of its field (all ones, zero, the most negative, a walking
    pattern), nE / nW of each slave different."""
    out = []
    for w, fw in enumerate(fmt.words):
        n = fw.data_bits
        pos = ((1 << n) - 1, 0, 1 << (n - 1), 0x5555555555 & ((1 << n) - 1))[k % 4]
        ne, nw = ((1, 0), (0, 1), (1, 1), (0, 0))[(k + w) % 4] if fw.nenw else (1, 1)
        out.append(frames.WordValue(pos, ne, nw))
    return out


@cocotb.test()
async def driver_chain_of_four(dut):
    """A chain of four slaves configured through biss_configure (the caps read by
    biss_channel_init: 4 words, words 2 and 3 of up to 24 and 16 bits; cfg_w2 / cfg_w3 and
    their CRC registers hold the formats): frames at the corners of every word with nE / nW
    set differently per slave, then random ones, every word's data, nE, nW and crc_ok as sent
    (word 2 sign-extended, also through biss_signed_data; word 3 Gray-decoded). Then a CRC
    error in word 2, in word 3, in words 0 and 3: the status by the documented rule, that
    word's crc_ok 0 and its counter (biss_read_counters' crc_chain) by one, UNCONFIRMED then
    OK after it; biss_clear_counters clears words 2 and 3's counters too."""
    fmt = CHAIN_4
    tb, drv, ch = await setup(dut, seed=2611, fmt=fmt)
    assert (ch.words, tuple(ch.chain_data_bits), ch.chain_words) == \
        (len(CHAIN_BUS_DATA_BITS), (*CHAIN_BUS_DATA_BITS[2:], 0, 0, 0, 0), 2)
    assert tuple(ch.max_data_bits) == CHAIN_BUS_DATA_BITS[:2] and ch.has_timestamp
    cfg = await chain_config(drv, fmt)
    await drv.check("biss_configure", byref(ch), byref(cfg))
    await check_chain_registers(tb, fmt)
    assert (await tb.read_fields("state", 0))["config_error"] == 0
    await tb.encoders_ready()

    negative = 0
    for k in range(8):
        if k < 4:
            send_next(tb, fmt, values=corner_values(fmt, k))
        res = await sample(drv, ch)
        parsed = check_frame(tb, fmt, res)
        want = frames.to_signed(parsed["words"][2]["position"], fmt.words[2].data_bits)
        assert drv.lib.biss_signed_data(byref(ch), 2, res["word2"]) == want
        negative += want < 0
    assert negative > 0, "a negative word 2 was read"
    counts = await drv.counters(ch)
    assert not any(counts.values()), counts

    offsets = fmt.word_offsets()
    for bad in ((2,), (3,), (0, 3)):
        before = await drv.counters(ch)
        crc_ok = tuple(w not in bad for w in range(len(fmt.words)))
        # The last bit of each bad word's CRC flipped.
        send_next(tb, fmt, faults=frames.FrameFaults(flip_bits=tuple(
            offsets[w] + fmt.words[w].total_bits - 1 for w in bad)))
        res = await sample(drv, ch)
        parsed = check_frame(tb, fmt, res)
        assert tuple(w["crc_ok"] for w in parsed["words"]) == crc_ok
        assert STATUS_NAME[res["status"]] == crc_status(crc_ok), (bad, res["status"])
        after = await drv.counters(ch)
        counted = crc_counters(crc_ok)
        for name in after:
            assert after[name] == before[name] + (name in counted), (bad, name, after)
        await tb.encoders_ready()
        check_frame(tb, fmt, await sample(drv, ch), status="UNCONFIRMED")
        check_frame(tb, fmt, await sample(drv, ch))
    assert (await drv.counters(ch))["crc_word3"] == 2
    await drv.check("biss_clear_counters", byref(ch))
    await ClockCycles(dut.clk, 20)          # every count 0 within 14 clocks (docs/bus.md)
    counts = await drv.counters(ch)
    assert not any(counts.values()), counts


@cocotb.test()
async def driver_chain_of_three_on_a_four_word_build(dut):
    """Three slaves (issue 26's chain of three) on the four-word build: biss_channel_init reads
    words 4 and the caps of words 2..7 (64, 16, 0, 0, 0, 0); configured for one chain word,
    cfg_w2 holds word 2 and cfg_w3 reads 0 (disabled); biss_read_result reads words 0..2 only
    (chain_words 1, the chain[] entries beyond 0), each as its slave sent it."""
    fmt = CHAIN_3
    tb, drv, ch = await setup(dut, seed=2612, fmt=fmt)
    assert ch.words == 4 and tuple(ch.chain_data_bits) == (64, 16, 0, 0, 0, 0)
    # The map's view of the build, from the test side: caps.words and caps_chain.
    assert (await tb.read_fields("caps", 0))["words"] == len(CHAIN_BUS_DATA_BITS)
    caps = await tb.read_fields("caps_chain", 0)
    assert (caps["data_bits_a"], caps["data_bits_b"], caps["data_bits_c"],
            caps["data_bits_d"]) == (64, 16, 0, 0)
    cfg = await chain_config(drv, fmt)
    assert cfg.chain_words == 1
    await drv.check("biss_configure", byref(ch), byref(cfg))
    assert ch.chain_words == 1, "biss_configure sets the words biss_read_result reads"
    await check_chain_registers(tb, fmt)
    await tb.encoders_ready()
    for _ in range(4):
        res = await sample(drv, ch)
        check_frame(tb, fmt, res)
        assert "word3" not in res
    raw = Result()
    await drv.check("biss_read_result", byref(ch), byref(raw))
    assert raw.chain_words == 1 and all(raw.chain[i].data == 0 and not raw.chain[i].crc_ok
                                        for i in range(1, CHAIN_WORDS))


@cocotb.test()
async def driver_chain_words_of_64_bits(dut):
    """Words 0, 1 and 2 of 64 bits through the driver (map version 2): biss_channel_init
    reads 64-bit caps for words 0 and 1, biss_configure writes data_bits 64 (each field's top
    bit), biss_read_result joins result.w0_lo / w0_hi, w1_lo / w1_hi and chain.w2_lo / w2_hi
    (all 32 bits of each _hi); every word as sent, Gray-decoded in one format and two's
    complement in the other (biss_signed_data of a 64-bit word is the word itself);
    positions with bit 63 set in every word."""
    tb, drv, ch = await setup(dut, seed=2615, fmt=CHAIN_64[0])
    assert tuple(ch.max_data_bits) == (64, 64) and ch.chain_data_bits[0] == 64
    top_set = [0, 0, 0]
    for fmt in CHAIN_64:
        tb.channels[0].set_format(fmt)
        tb.channels[0].source.chain_positions_at = lambda t, fmt=fmt: [
            tb.rng.getrandbits(w.data_bits) for w in fmt.words]
        cfg = await chain_config(drv, fmt)
        await drv.check("biss_configure", byref(ch), byref(cfg))
        await check_chain_registers(tb, fmt)
        words = await tb.read_fields("cfg_words", 0)
        assert (words["w0_data_bits"], words["w1_data_bits"]) == (64, 64)
        await tb.encoders_ready()
        for _ in range(5):
            res = await sample(drv, ch)
            check_frame(tb, fmt, res)
            for w in range(3):
                data = res[f"word{w}"]
                top_set[w] += data >> 63
                if fmt.words[w].signed:
                    got = drv.lib.biss_signed_data(byref(ch), w, data)
                    assert got == data - (data >> 63 << 64), (w, got, data)
    assert all(top_set), f"a word never had bit 63 set ({top_set}): the top bit not reached"


@cocotb.test()
async def driver_chain_refuses_bad_settings(dut):
    """Chain settings the build cannot run, each refused by biss_config_check / biss_configure
    with its code before anything is written (the chain registers keep the good
    configuration, config_error stays 0): word 5 on the four-word build, word 4 too, word 2
    of 65 bits (the build's word 2 is 64), word 3 of 17 bits, chain words without word 1,
    an LC in two words, a custom CRC of width 0 in word 3; then the good one is accepted."""
    fmt = CHAIN_4
    tb, drv, ch = await setup(dut, seed=2613, fmt=fmt)
    good = await chain_config(drv, fmt)
    await drv.check("biss_configure", byref(ch), byref(good))
    paths = [f"cfg_w{w}{r}" for w in (2, 3) for r in ("", "_crc", "_crc_start")] + ["cfg_words"]
    before = {p: await tb.read(p, 0) for p in paths}

    def bad(chain_words=None, word1_enable=None, **chain_fields):
        c = Config.from_buffer_copy(good)
        if chain_words is not None:
            c.chain_words = chain_words
        if word1_enable is not None:
            c.word1_enable = word1_enable
        for key, value in chain_fields.items():         # w2_data_bits=25 ...
            w, name = key.split("_", 1)
            setattr(c.chain[int(w[1:]) - 2], name, value)
        return c

    cases = [
        ("BISS_ERR_CHAIN", bad(chain_words=4)),                      # words 2..5: no word 5
        ("BISS_ERR_CHAIN", bad(chain_words=3)),                      # no word 4
        ("BISS_ERR_DATA_BITS", bad(w2_data_bits=CHAIN_BUS_DATA_BITS[2] + 1)),
        ("BISS_ERR_DATA_BITS", bad(w3_data_bits=CHAIN_BUS_DATA_BITS[3] + 1)),
        ("BISS_ERR_DATA_BITS", bad(w2_data_bits=0)),
        ("BISS_ERR_CHAIN", bad(word1_enable=False)),                 # a gap: no word 1
        ("BISS_ERR_LC", bad(w2_lc=True, w3_lc=True)),
        ("BISS_ERR_CRC", bad(w3_crc=3, w3_crc_width=0)),
    ]
    for want, cfg in cases:
        got = drv.error_name(await drv.call("biss_config_check", byref(ch), byref(cfg)))
        assert got == want, f"{want} expected, biss_config_check said {got}"
        got = drv.error_name(await drv.call("biss_configure", byref(ch), byref(cfg)))
        assert got == want, f"{want} expected, biss_configure said {got}"
    assert {p: await tb.read(p, 0) for p in paths} == before, "a refused configuration was written"
    assert (await tb.read_fields("state", 0))["config_error"] == 0
    assert ch.chain_words == 2
    await drv.check("biss_configure", byref(ch), byref(good))
    await tb.encoders_ready()
    check_frame(tb, fmt, await sample(drv, ch))


class PacedBus:
    """The bus model with every read ``delay_us`` later (a slow bridge), counting the reads of
    result.status and chain.updates."""

    def __init__(self, tb, delay_us):
        self.tb, self.bus, self.delay_us = tb, tb.bus, delay_us
        self.status, self.updates = tb.addr("result.status", 0), tb.addr("chain.updates", 0)
        self.reads = {self.status: 0, self.updates: 0}

    async def read(self, addr):
        if addr in self.reads:
            self.reads[addr] += 1
        if self.delay_us:
            await Timer(self.delay_us, "us")
        return await self.bus.read(addr)

    async def write(self, addr, value):
        await self.bus.write(addr, value)


#: Reads of the torn-read scenario (each a biss_read_result while frames end every ~13 us).
TORN_READS = 150


@cocotb.test()
async def driver_chain_reads_are_of_one_frame(dut):
    """Periodic requests back to back (a frame ends every ~13 us) while the driver reads
    result after result on a slow bus (each read 0.3 us and more: about 3 us from the first
    chain.updates read to the second). Every result biss_read_result returns is one frame: all
    four words as the encoder sent them in the frame of the result's timestamp; it had to read
    again at times (reads of result.status above one per call). The same reads without the
    rule (result.status, a 2 us pause, word 2) find torn sets: word 2 of a later
    frame than the snapshot. A bus so slow (3 us a read) that a frame ends during every try
    gives BISS_ERR_TORN after BISS_READ_RETRIES tries."""
    fmt = CHAIN_4
    tb, drv, ch = await setup(dut, seed=2614, fmt=fmt, spec=fast_encoder(fmt))
    # A 2 us break (above the encoder's 0.15 us timeout), requests at once after it.
    cfg = await chain_config(drv, fmt, break_time=200)
    await drv.check("biss_configure", byref(ch), byref(cfg))
    await tb.encoders_ready()
    await drv.check("biss_set_periodic", byref(ch), True, 0)
    await drv.check("biss_wait_done", byref(ch), POLLS)         # the first frame
    paced = PacedBus(tb, 0.3)
    drv.model = paced
    times = set()
    for _ in range(TORN_READS):
        res = await drv.result(ch)
        check_frame(tb, fmt, res)
        times.add(res["time"])
        await Timer(1, "us")
    sent = sorted(tb.channels[0].sent)             # the frames' timestamps
    period_us = (sent[-1] - sent[0]) / (len(sent) - 1) / CLK_HZ * 1e6
    retries = paced.reads[paced.status] - TORN_READS
    assert paced.reads[paced.updates] == TORN_READS + paced.reads[paced.status]
    assert len(times) > TORN_READS // 4, f"only {len(times)} frames read"
    assert retries > 0, "no read had to be repeated: the rule went untested"

    # Without the rule: the snapshot, a pause, then the live chain words.
    torn = 0
    for _ in range(TORN_READS // 3):
        res = await tb.read_fields("result.status", 0)
        time = await tb.read("result.timestamp", 0)
        await Timer(2, "us")
        lo = await tb.read("chain.w2_lo", 0)
        bits = tb.channels[0].sent[time]
        word2 = frames.parse_frame(fmt, bits)["words"][2]["position"]
        torn += lo != port_position(fmt.words[2], word2, CHAIN_BUS_DATA_BITS[2])
    assert torn > 0, "no torn set without the rule: the scenario does not stress it"

    paced.delay_us = 3.0
    res = Result()
    got = drv.error_name(await drv.call("biss_read_result", byref(ch), byref(res)))
    assert got == "BISS_ERR_TORN", got
    await drv.check("biss_set_periodic", byref(ch), False, 0)
    dut._log.info("%d reads, %d frames of %d sent (one every %.1f us), %d retries; without the "
                  "rule %d of %d torn", TORN_READS, len(times), len(sent), period_us, retries,
                  torn, TORN_READS // 3)
