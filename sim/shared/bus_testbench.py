"""cocotb testbench for the bus tops (``biss_master_axil``, ``biss_master_wb``,
``biss_master_uart``).

The bus is driven by bus models (cocotbext-axi's AxiLiteMaster, cocotbext-wishbone's
WishboneMaster; on the UART top the host software's ``Link`` over a UART model,
sim/shared/uart.py), every address and field comes from the SystemRDL source through
:mod:`sim.shared.regspec`, and each channel's MA/SLO pair has its own encoder model
(tb/encoder_model): a BiSS one, or an SSI one (:class:`SsiEncoder`). Expected results come
from what each encoder sent, looked up by the result's timestamp (the clock count of the
frame's first MA rise), never from the RTL.
"""

import logging
import os
import random
from dataclasses import dataclass, field

import cocotb
from cocotb.clock import Clock
from cocotb.simtime import get_sim_time
from cocotb.triggers import ClockCycles, Lock, RisingEdge, Timer, with_timeout

from encoder_model import frames
from encoder_model.cocotb_encoder import BissEncoder, Cable, Response
from encoder_model.cocotb_ssi import SsiLineEncoder
from encoder_model.ssi import parse_ssi
from master_contract import (CHAIN_BUS_DATA_BITS, MAX_DATA_BITS, STATUS, SYS_CLK_HZ, crc_config,
                             port_position, ssi_ma_pulses, ssi_ne_nw)
from sim.shared import regspec

CLK_HZ = SYS_CLK_HZ
CLK_NS = 1e9 / CLK_HZ
BUS = os.environ.get("BISS_BUS", "axil")
#: The cores' longest data field per word: the committed tops' default cores, or the chain
#: top's (sim/shared/runner.py, ``axil_chain``: BISS_BUS_BUILD=chain).
BUILD_DATA_BITS = (CHAIN_BUS_DATA_BITS if os.environ.get("BISS_BUS_BUILD") == "chain"
                   else MAX_DATA_BITS)
#: The chain words' settings and results are read through the chain registers (words 2..7).
CHAIN_FIRST = 2
#: Reads of a chain result before giving up on a consistent set (chain.updates).
CHAIN_READ_TRIES = 8
#: Words of 64 data bits, as long as a word can be: Gray with CRC-16 and nE/nW, and two's
#: complement with iC-MB4's CRC-8 (0x12F) and no nE/nW.
WORD_64_GRAY = frames.WordFormat(64, crc=frames.CRC16, gray=True)
WORD_64_SIGNED = frames.WordFormat(64, nenw=False, signed=True,
                                   crc=frames.CustomCrc(8, 0x2F, 0x00, True))
#: The chain top's words 0, 1 and 2 all of 64 bits (result.w0_*, result.w1_*, chain.w2_*),
#: each word Gray in one format and two's complement in the other (the bus and the C driver
#: scenarios read both).
CHAIN_64 = (frames.FrameFormat("chain_64_a", (WORD_64_GRAY, WORD_64_SIGNED, WORD_64_GRAY),
                               chain=True),
            frames.FrameFormat("chain_64_b", (WORD_64_SIGNED, WORD_64_GRAY, WORD_64_SIGNED),
                               chain=True))


class AxiLiteBus:
    """32-bit reads and writes through cocotbext-axi's AxiLiteMaster (concurrent calls are
    queued by the model and run back to back)."""

    def __init__(self, dut):
        from cocotbext.axi import AxiLiteBus as Bus, AxiLiteMaster
        self.master = AxiLiteMaster(Bus.from_prefix(dut, "s_axil"), dut.clk, dut.rst)
        for side in (self.master.write_if, self.master.read_if):
            side.log.setLevel(logging.WARNING)          # no line per transaction

    async def read(self, addr):
        r = await self.master.read(addr, 4)
        assert r.resp == 0, f"read {addr:#x}: response {r.resp}"
        return int.from_bytes(r.data, "little")

    async def write(self, addr, value, lanes=0xF):
        """Write the byte lanes set in ``lanes`` (contiguous) of ``value``."""
        first = (lanes & -lanes).bit_length() - 1
        count = bin(lanes).count("1")
        assert lanes >> first == (1 << count) - 1, "lanes must be contiguous"
        data = value.to_bytes(4, "little")[first:first + count]
        r = await self.master.write(addr + first, data)
        assert r.resp == 0, f"write {addr:#x}: response {r.resp}"


class WishboneBus:
    """32-bit reads and writes through cocotbext-wishbone's WishboneMaster, as a **classic**
    master (``stb`` held until ``ack``; the top's ``stall`` is not given to the model), so that
    the classic protocol is what every scenario runs; the pipelined one (requests held through
    ``stall``, one after another) is driven by hand in ``wishbone_pipelined_back_to_back``. (The
    model's pipelined mode passes too.) One cycle at a time, several operations back to back
    per cycle."""

    SIGNALS = {"cyc": "cyc", "stb": "stb", "we": "we", "adr": "adr", "datwr": "dat_w",
               "datrd": "dat_r", "ack": "ack"}

    def __init__(self, dut):
        from cocotbext.wishbone import driver
        from cocotbext.wishbone.driver import WishboneMaster

        # The model sets its outputs' first values with immediate (VPI no-delay) writes; on
        # Icarus such a write to a top-level input wire never reaches the logic behind it
        # (the wire reads its value, what it drives stays Z). Ordinary writes instead.
        driver.set_immediate = lambda sig, value: setattr(sig, "value", value)

        class ClassicMaster(WishboneMaster):
            _optional_signals = ["sel"]

        self.master = ClassicMaster(dut, "wb", dut.clk, width=32, timeout=1000,
                                    signals_dict=self.SIGNALS)
        self.lock = Lock()

    async def ops(self, ops):
        from cocotbext.wishbone.driver import WBOp
        async with self.lock:
            res = await self.master.send_cycle(
                [WBOp(adr=addr >> 2, dat=value, sel=lanes) for addr, value, lanes in ops])
        assert all(r.ack == 1 for r in res), "every operation is acked (never err/rty)"
        return [int(r.datrd) for r in res]

    async def read(self, addr):
        return (await self.ops([(addr, None, 0xF)]))[0]

    async def write(self, addr, value, lanes=0xF):
        await self.ops([(addr, value, lanes)])


@dataclass(frozen=True)
class Encoder:
    """One channel's encoder model: its frames, cable, position function of time (default:
    random), control side (an ``encoder_model.control.ControlSlave``, None: CDS 0, CDM
    ignored), timing (timeout, processing time; ``min_cycle_s`` None: the 31.25 us rule)."""
    fmt: object
    cable: Cable = field(default_factory=Cable)
    position: object = None
    control: object = None
    timeout_s: float = 12.5e-6
    processing_s: tuple = (2e-6, 8e-6)
    min_cycle_s: float | None = None


class Channel:
    """One channel's encoder model and what it sent, by timestamp (``bits`` with the CDS the
    control slave put in, if any)."""

    def __init__(self, tb, n, spec):
        fmt = spec.fmt
        self.tb, self.n, self.fmt, self.spec = tb, n, fmt, spec
        self.sign_of_life = frames.SignOfLife()
        self.position = spec.position or (
            lambda t: tb.rng.getrandbits(self.fmt.words[0].data_bits))
        self.set_format(fmt)
        self.sent = {}          # expected timestamp -> frame bits
        extra = {} if spec.min_cycle_s is None else {"min_cycle_s": spec.min_cycle_s}
        self.encoder = BissEncoder(getattr(tb.dut, f"ch{n}_ma"), getattr(tb.dut, f"ch{n}_slo"),
                                   cable=spec.cable, respond=self._respond, rng=tb.rng,
                                   timeout_s=spec.timeout_s, control=spec.control, **extra)

    def set_format(self, fmt):
        """Frames of ``fmt`` from the next request on (the same encoder, cable and sign of
        life). A chain: every slave its own random position (word 0's from ``position``)."""
        rng = self.tb.rng
        chain = (lambda t: [self.position(t)] + [rng.getrandbits(w.data_bits)
                                                 for w in fmt.words[1:]]) if fmt.is_chain else None
        self.fmt = fmt
        self.source = frames.EncoderFrameSource(fmt, lambda t: self.position(t),
                                                sign_of_life=self.sign_of_life,
                                                chain_positions_at=chain)

    def _respond(self, t_latch):
        values = self.source.values_at(t_latch)
        bits = frames.build_frame(self.fmt, values)
        record = self.encoder.records[-1]
        self.sent[self.tb.timestamp_of(record.t_first_rise_s)] = bits
        return Response(bits=bits, processing_time_s=self.tb.rng.uniform(*self.spec.processing_s))


@dataclass(frozen=True)
class SsiEncoder:
    """One channel's SSI encoder model (encoder_model.cocotb_ssi.SsiLineEncoder on its pins):
    its word (an encoder_model.ssi.SsiFormat; ``encoder.set_format`` changes it for the next
    latch), cable, position function of time (default: random)."""
    fmt: object
    cable: Cable = field(default_factory=Cable)
    position: object = None


class SsiChannel:
    """One channel's SSI encoder model; what it sent is its ``encoder.records``."""

    def __init__(self, tb, n, spec):
        self.tb, self.n, self.spec = tb, n, spec
        self.position = spec.position or (
            lambda t: tb.rng.getrandbits(self.encoder.fmt.data_bits))
        self.encoder = SsiLineEncoder(getattr(tb.dut, f"ch{n}_ma"),
                                      getattr(tb.dut, f"ch{n}_slo"), spec.fmt,
                                      lambda t: self.position(t), cable=spec.cable, rng=tb.rng)

    def round_trip_clocks(self):
        """The true round trip (cable both ways + the encoder's delay), in clocks: what
        cfg_ssi.ssi_delay is set to (as sim/shared/ssi_testbench.py does)."""
        return round(self.spec.cable.round_trip_s() * CLK_HZ)


class BusTestbench:
    def __init__(self, dut, *, seed=1):
        self.dut = dut
        self.rng = random.Random(seed)
        self.map = regspec.load()
        if BUS == "uart":
            from sim.shared.uart import UartBus         # the host software: Link over the line
            self.bus = UartBus(dut)
        else:
            self.bus = AxiLiteBus(dut) if BUS == "axil" else WishboneBus(dut)
        self.channels = {}
        self.t_clk0 = None

    # -- Setup ----------------------------------------------------------------------------
    async def start(self, formats=(), cables=(), positions=()):
        """Clock, reset, and one encoder per entry of ``formats`` (channel 0, 1, ...): a frame
        format, an :class:`Encoder` or an :class:`SsiEncoder`; ``cables``, ``positions``: per
        channel, for the entries given as formats (default: a 0 m cable, random positions)."""
        dut = self.dut
        Clock(dut.clk, CLK_NS, unit="ns").start()
        dut.trigger.value = 0
        dut.rst.value = 1
        for n, spec in enumerate(formats):
            if not isinstance(spec, (Encoder, SsiEncoder)):
                spec = Encoder(spec, cables[n] if n < len(cables) else Cable(),
                               positions[n] if n < len(positions) else None)
            self.channels[n] = (SsiChannel if isinstance(spec, SsiEncoder) else Channel)(
                self, n, spec)
            self.channels[n].encoder.start()
        await ClockCycles(dut.clk, 4)
        dut.rst.value = 0
        await RisingEdge(dut.clk)
        self.t_clk0 = get_sim_time("step")
        # The power-up break (40 us): Icarus 11 runs some of Yosys's combinational blocks only
        # on their first input change, so `busy` (state.busy) reads X until the break ends
        # (README, Notes). Nothing else changes meanwhile: the registers still hold their
        # reset values after it.
        await Timer(45, "us")

    def timestamp_of(self, t_first_rise_s):
        """The core's timestamp of an MA rise at ``t_first_rise_s`` (docs/ports.md)."""
        edges = round((t_first_rise_s * 1e12 - self.t_clk0) / (CLK_NS * 1e3))
        return (edges + 1) % 2**32

    # -- Registers --------------------------------------------------------------------------
    def addr(self, path, ch=None, index=0):
        return self.map.address(path, ch, index)

    def fields(self, path, word, ch=None):
        return {name: f.get(word) for name, f in self.map.reg(path, ch).fields.items()}

    async def read(self, path, ch=None):
        return await self.bus.read(self.addr(path, ch))

    async def read_fields(self, path, ch=None):
        return self.fields(path, await self.read(path, ch), ch)

    async def write(self, path, value, ch=None, lanes=0xF):
        await self.bus.write(self.addr(path, ch), value, lanes)

    async def write_fields(self, path, ch=None, **values):
        """Write a register from field values; fields not named are written 0."""
        spec = self.map.reg(path, ch)
        word = 0
        for name, value in values.items():
            word = spec.fields[name].put(word, value)
        await self.write(path, word, ch)

    async def configure(self, ch, fmt, ma_hz, **cfg):
        """The cfg_* registers for a frame format and MA rate (every setting, as the core's
        Testbench.configure does on its ports); a word with a frames.CustomCrc gets code 3 and
        its cfg_crcN / cfg_crcN_start written (the others' are left as they are: the core does
        not read them with a named CRC)."""
        hp = CLK_HZ / (2 * ma_hz)
        assert hp == int(hp)
        words, custom = {}, {}
        for w in range(2):
            word = fmt.words[w] if w < len(fmt.words) else frames.WordFormat(1)
            code, crc = crc_config(word.crc)
            words.update({f"w{w}_data_bits": word.data_bits, f"w{w}_nenw": int(word.nenw),
                          f"w{w}_lc": int(word.lc), f"w{w}_crc": code,
                          f"w{w}_gray": int(word.gray), f"w{w}_signed": int(word.signed)})
            if isinstance(word.crc, frames.CustomCrc):
                custom[f"cfg_crc{w}"] = {f"w{w}_crc_{k}": crc[k]
                                         for k in ("width", "poly", "inverted")}
                custom[f"cfg_crc{w}_start"] = {f"w{w}_crc_start": crc["start"]}
        words["w1_enable"] = int(len(fmt.words) >= 2)
        # Words 2.. of a chain, in their own registers; the build's other words disabled.
        for w in range(CHAIN_FIRST, len(BUILD_DATA_BITS)):
            if w >= len(fmt.words):
                custom[f"cfg_w{w}"] = {"enable": 0}
                continue
            code, crc = crc_config(fmt.words[w].crc)
            word = fmt.words[w]
            custom[f"cfg_w{w}"] = {"data_bits": word.data_bits, "nenw": int(word.nenw),
                                   "lc": int(word.lc), "crc": code, "gray": int(word.gray),
                                   "is_signed": int(word.signed), "enable": 1}
            if isinstance(word.crc, frames.CustomCrc):
                custom[f"cfg_w{w}_crc"] = {f"crc_{k}": crc[k]
                                           for k in ("width", "poly", "inverted")}
                custom[f"cfg_w{w}_crc_start"] = {"crc_start": crc["start"]}
        settings = {
            "cfg_ma": {"ma_half_period": int(hp), "delay_limit": 0},
            "cfg_period": {"request_period": 0}, "cfg_break": {"break_time": 0},
            "cfg_ack": {"ack_limit": 0}, "cfg_timeout": {"timeout_limit": 0},
            **custom,
            "cfg_words": words,
            "cfg_checks": {"end_check": 0, "spw_check": int(len(fmt.words) == 2),
                           "spw_tolerance": 1},
        }
        for path, values in settings.items():
            for name in list(cfg):
                if name in self.map.channel[path].fields:
                    values[name] = cfg.pop(name)
            await self.write_fields(path, ch, **values)
        assert not cfg, f"unknown settings {cfg}"

    # -- Results ----------------------------------------------------------------------------
    async def result(self, ch):
        """The last result: ``result.status`` first (it takes the snapshot), then the rest; in
        a build of more than two words, between two reads of ``chain.updates`` with the chain
        words (docs/bus.md, "Chains"), read again until both reads agree (``res["tries"]``:
        how many sets it took)."""
        chain = len(BUILD_DATA_BITS) > CHAIN_FIRST
        for tries in range(1, CHAIN_READ_TRIES + 1):
            before = await self.read("chain.updates", ch) if chain else None
            res = await self._result_once(ch, chain)
            if not chain or await self.read("chain.updates", ch) == before:
                res["tries"] = tries
                return res
        raise AssertionError(f"ch{ch}: chain.updates changed in {CHAIN_READ_TRIES} reads")

    async def _result_once(self, ch, chain):
        res = await self.read_fields("result.status", ch)
        for path in ("result.seq", "result.timestamp", "result.line"):
            res.update(await self.read_fields(path, ch))
        for w in range(2):
            lo = await self.read(f"result.w{w}_lo", ch)
            hi = await self.read(f"result.w{w}_hi", ch)
            res[f"word{w}"] = lo | hi << 32
        if chain:
            res.update(await self.read_fields("chain.flags", ch))
            for w in range(CHAIN_FIRST, len(BUILD_DATA_BITS)):
                lo = await self.read(f"chain.w{w}_lo", ch)
                hi = await self.read(f"chain.w{w}_hi", ch)
                res[f"word{w}"] = lo | hi << 32
        return res

    def check_result(self, ch, res, status="OK", seq=False):
        """The result against the frame its channel's encoder sent at its timestamp; with
        ``seq``, also that ``result.seq`` counts every frame sent up to that one (none lost)."""
        chan = self.channels[ch]
        assert res["status"] == STATUS[status], f"ch{ch}: status {res['status']} != {status}"
        bits = chan.sent.get(res["time"])
        assert bits is not None, \
            f"ch{ch}: no frame sent at timestamp {res['time']} (sent: {sorted(chan.sent)[-4:]})"
        parsed = frames.parse_frame(chan.fmt, bits)
        if seq:
            n = sorted(chan.sent).index(res["time"]) + 1
            assert res["seq"] == n % 2**16, f"ch{ch}: seq {res['seq']}, frame {n} since reset"
        for w, word in enumerate(parsed["words"]):
            got = res[f"word{w}"]
            want = port_position(chan.fmt.words[w], word["position"], BUILD_DATA_BITS[w])
            assert got == want, f"ch{ch} word{w}: {got:#x} != sent {want:#x}"
            if chan.fmt.words[w].nenw:
                assert (res[f"w{w}_ne"], res[f"w{w}_nw"]) == (word["ne"], word["nw"])
            assert res[f"w{w}_crc_ok"] == 1
            if chan.fmt.words[w].lc:
                assert res["lc"] == word["lc"]
        return parsed

    def check_ssi_result(self, ch, res, status="OK", *, word, ssi_delay, double=False):
        """An SSI result against the transmission channel ``ch``'s SSI encoder latched for it
        (the record whose first MA rise is the result's timestamp): the status, MA pulses
        N + 1 (2N + 2 ``double``) as the encoder saw them, ``line_delay`` = ``ssi_delay``, and
        word 0 (``word``: the frames.WordFormat configured) as the first copy was sent (the
        position, flags and CRC). Returns the record."""
        chan = self.channels[ch]
        assert res["status"] == STATUS[status], f"ch{ch}: status {res['status']} != {status}"
        m2e = chan.spec.cable.m2e_s()
        recs = [r for r in chan.encoder.records
                if r.t_rises_s and self.timestamp_of(r.t_rises_s[0] - m2e) == res["time"]]
        assert len(recs) == 1, f"ch{ch}: {len(recs)} SSI latches at timestamp {res['time']}"
        rec = recs[0]
        pulses = ssi_ma_pulses(rec.fmt.total_bits, double)
        assert (rec.ma_falls, rec.ma_rises) == (pulses, pulses), \
            f"ch{ch}: MA {rec.ma_falls} falls / {rec.ma_rises} rises, expected {pulses}"
        assert res["line_delay"] == ssi_delay, f"line_delay {res['line_delay']} != {ssi_delay}"
        sent = parse_ssi(rec.fmt, [b ^ (i in rec.faults.flip) for i, b in enumerate(rec.word)])
        want = port_position(word, sent.position, MAX_DATA_BITS[0])
        assert res["word0"] == want, f"ch{ch} word0: {res['word0']:#x} != sent {want:#x}"
        flags = ssi_ne_nw(error_active=sent.errors[0] if rec.fmt.error_bits else None,
                          nenw=(sent.ne, sent.nw) if rec.fmt.nenw else None)
        if flags is not None:
            assert (res["w0_ne"], res["w0_nw"]) == flags
        crc_ok = 1 if sent.crc_ok is None else int(sent.crc_ok)
        assert res["w0_crc_ok"] == crc_ok, f"w0_crc_ok {res['w0_crc_ok']}, sent {crc_ok}"
        return rec

    async def wait_irq_status(self, ch, cause="done", limit_s=1e-3, clear=True):
        """Poll ``irq_status`` until ``cause`` is set; clear it (write 1) if asked."""
        spec = self.map.channel["irq_status"].fields[cause]
        t_end = get_sim_time("step") + limit_s * 1e12
        while True:
            word = await self.read("irq_status", ch)
            if spec.get(word):
                break
            assert get_sim_time("step") < t_end, f"ch{ch}: irq_status.{cause} never set"
            await Timer(1, "us")
        if clear:
            await self.write("irq_status", spec.put(0, 1), ch)
        return self.fields("irq_status", word, ch)

    async def request(self, ch, limit_s=1e-3):
        """Wait until idle, ctrl.start, wait for done (irq_status, cleared), return the result."""
        await self.wait_idle(ch)
        await self.write("irq_status", self.map.channel["irq_status"].fields["done"].mask, ch)
        await self.write_fields("ctrl", ch, start=1, **await self._ctrl_keep(ch))
        await self.wait_irq_status(ch, "done", limit_s)
        return await self.result(ch)

    async def _ctrl_keep(self, ch):
        """The stored (non-pulse) fields of ``ctrl``, to write them back unchanged."""
        fields = await self.read_fields("ctrl", ch)
        spec = self.map.channel["ctrl"].fields
        return {k: v for k, v in fields.items() if not spec[k].singlepulse}

    async def encoders_ready(self, limit_s=1e-3):
        for _ in range(int(limit_s / 1e-6)):
            if all(c.encoder.ready for c in self.channels.values()):
                return
            await Timer(1, "us")
        raise AssertionError("encoder models never became ready")

    async def wait_idle(self, ch, limit_s=1e-3):
        t_end = get_sim_time("step") + limit_s * 1e12
        while (await self.read_fields("state", ch))["busy"]:
            assert get_sim_time("step") < t_end, f"ch{ch} never idle"
            await Timer(1, "us")

    # -- Register access (the control channel, registers ca.*) --------------------------------
    async def register_access(self, ch, address, *, count=None, data=None, slave_id=0,
                              limit_s=20e-3):
        """One register access through the bus as a driver makes it: for a write (``data``)
        the bytes into ``ca.wbuf`` (byte i in lane i % 4 of word i // 4, docs/bus.md; whole
        words, a partial last word with its byte strobes), ``ca.request``, ``ca.ctrl.start``,
        then the ``irq`` pin (:meth:`wait_access_done`). Returns ``(ca.state fields, bytes)``:
        for a read the ``count`` bytes of ``ca.rbuf``."""
        write = data is not None
        count = len(data) if write else count
        if write:
            for w in range(0, len(data), 4):
                chunk = bytes(data[w:w + 4])
                await self.bus.write(self.addr("ca.wbuf", ch, w // 4),
                                     int.from_bytes(chunk.ljust(4, b"\0"), "little"),
                                     (1 << len(chunk)) - 1)
        await self.write_fields("ca.request", ch, slave_id=slave_id, address=address,
                                count=count, write=int(write))
        await self.write_fields("ca.ctrl", ch, start=1)
        await self.wait_access_done(ch, limit_s)
        state = await self.read_fields("ca.state", ch)
        assert state["busy"] == 0, "access_done while ca.state.busy"
        out = bytearray()
        if not write:
            for w in range(-(-count // 4)):
                out += (await self.bus.read(self.addr("ca.rbuf", ch, w))).to_bytes(4, "little")
        return state, bytes(out[:count])

    async def wait_access_done(self, ch, limit_s):
        """The interrupt of an ended access: ``irq`` rises (irq_enable.access_done must be set,
        nothing else enabled), ``irq_pending`` names the channel, ``irq_status.access_done`` is
        set; writing 1 clears it and ``irq`` falls."""
        dut = self.dut
        assert (await self.read_fields("irq_enable", ch))["access_done"] == 1
        if not int(dut.irq.value):
            await with_timeout(RisingEdge(dut.irq), round(limit_s * 1e9), "ns")
        assert await self.read("irq_pending") == 1 << ch
        status = await self.read_fields("irq_status", ch)
        assert status["access_done"] == 1, status
        await self.write("irq_status", self.map.channel["irq_status"].fields["access_done"].mask,
                         ch)
        await ClockCycles(dut.clk, 2)                   # irq is registered
        assert int(dut.irq.value) == 0, "irq stays high after access_done was cleared"
