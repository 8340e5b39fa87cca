"""cocotb testbench for ``biss_master``: clock, reset, configuration, one request, and the checks.

The expected values come from the encoder model (tb/encoder_model), never from the RTL: what
the encoder sent (frames.py) and what happened on the wire (cocotb_encoder.CycleRecord).
"""

import math
import os
import random
import re
from dataclasses import dataclass, field

import cocotb
from cocotb.clock import Clock
from cocotb.simtime import get_sim_time
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge, Timer, with_timeout

from encoder_model import frames
from encoder_model.cocotb_encoder import BissEncoder, Cable, Response
from master_contract import (CA_COUNTERS, COUNTERS, CRC_CODE, crc_config, NOISE_COUNTERS, NOISE_FIELDS,
                             STATUS, SYS_CLK_HZ, NOISE_CONFIG_DEFAULTS, ConfirmationAccount,
                             SSI_PORTS, MAX_WORDS, port_position)

CLK_HZ = int(os.environ.get("BISS_CLK_HZ", str(SYS_CLK_HZ)))
CLK_NS = 1e9 / CLK_HZ
FRAME_LOG = os.environ.get("BISS_FRAME_LOG")
INTERNAL_CLOCK = bool(os.environ.get("BISS_INTERNAL_CLOCK"))

CFG_PORTS = ["cfg_ma_half_period", "cfg_request_period", "cfg_break_time", "cfg_ack_limit",
             "cfg_timeout_limit", "cfg_delay_limit", "cfg_end_check", "cfg_quiet_time",
             "cfg_noise_limit", "cfg_delay_tolerance", "cfg_confirm_frames", "cfg_spw_check",
             "cfg_spw_tolerance"] + [f"cfg_w{w}_enable" for w in range(1, MAX_WORDS)] + [
             f"cfg_w{w}_{f}" for w in range(MAX_WORDS)
             for f in ("data_bits", "nenw", "lc", "crc", "gray")]
#: A word's two's complement setting, in builds with signed words.
SIGNED_PORTS = [f"cfg_w{w}_signed" for w in range(MAX_WORDS)]
#: A word's custom CRC (cfg_wN_crc = 3), in builds with custom CRCs.
CUSTOM_CRC_PORTS = [f"cfg_w{w}_crc_{f}" for w in range(MAX_WORDS)
                    for f in ("width", "poly", "start", "inverted")]
#: The word a port belongs to: ``cfg_w2_crc`` and ``word2_position`` are word 2's.
_WORD_OF_PORT = re.compile(r"(?:^|_)w(?:ord)?(\d+)_")

#: ``done`` strobes whose confirmation state the watch keeps (the newest; expected_status
#: looks up a result read right after its ``done``).
CONFIRM_MEMORY = 256

MA_RATES_HZ = (250e3, 1e6, 2.5e6, 5e6, 10e6)
CABLES_M = (0, 20, 50, 100)


def preset(name):
    """A FrameFormat by name: a preset of frames.PRESETS, or ``bp3_N`` for any BP3 length."""
    return frames.PRESETS[name] if name in frames.PRESETS else frames.bp3(int(name.split("_")[1]))


def _int(dut, name):
    """A port's value; an X or Z fails naming the port."""
    value = getattr(dut, name).value
    if not value.is_resolvable:
        raise AssertionError(f"port {name} reads {value} (not 0/1)")
    return int(value)


def half_period_for(ma_hz):
    hp = CLK_HZ / (2 * ma_hz)
    assert hp == int(hp), f"MA {ma_hz} Hz is not a whole number of half periods at {CLK_HZ} Hz"
    return int(hp)


@dataclass
class Result:
    """All result ports, read right after ``done`` (the counters a clock later)."""
    status: int
    valid: int
    fields: dict
    counters: dict
    t_done_s: float


@dataclass
class Sent:
    """What the encoder was asked to send in one cycle."""
    values: list
    bits: list
    faults: object = None
    response: Response = None


class Testbench:
    def __init__(self, dut, *, seed=1):
        self.dut = dut
        self.rng = random.Random(seed)
        self.fmt = None
        self.sent = []                # one Sent per respond() call
        self.plan = []                # queued (values_or_None, FrameFaults, Response kwargs)
        self.source = None
        self.t_clk0 = None            # time of the first clock edge after reset release
        self.encoder = None
        self.pending = []             # MA-rise checks waiting for the encoder to end the cycle
        self.sign_of_life = frames.SignOfLife()     # one encoder: its LC runs on across configs
        self.delay_tolerance = 0      # cfg_delay_tolerance as configured (rearm_delay_check)
        # A one-word build (BiSS C only) has no word-1, SPW or CRC-16-word ports; a lean
        # build (bissmaster.generate --preset biss-c-lean) no counters and no timestamp. A
        # chain build has words 0 .. N-1 (wordN_position, cfg_wN_*, cfg_wN_enable).
        self.words = next(w for w in range(MAX_WORDS, 0, -1)
                          if hasattr(dut, f"word{w - 1}_position"))
        self.has_counters = hasattr(dut, "clear_counters")
        self.has_timestamp = hasattr(dut, "timestamp")
        self.has_register_access = hasattr(dut, "ca_start")      # the default build's engine
        self.has_custom_crc = hasattr(dut, "cfg_w0_crc_width")   # not in biss-c-lean
        self.has_signed = hasattr(dut, "cfg_w0_signed")          # not in biss-c-lean
        # Issue 28's noise defences: their ports only where the core has them, so every
        # scenario runs on a core with them and on one without.
        self.noise_defaults = {n: v for n, v in NOISE_CONFIG_DEFAULTS.items()
                               if hasattr(dut, n)}
        self.noise_fields = [n for n in NOISE_FIELDS if hasattr(dut, n)]
        self.noise_counters = [n for n in NOISE_COUNTERS if hasattr(dut, f"count_{n}")]
        #: The encoder's processing time (Ack to Start) is drawn from this range per frame,
        #: unless a queued Response gives it.
        self.processing_s = (2e-6, 16e-6)
        # Confirmation after a fault (docs/ports.md): the test side's own account of it, kept
        # by a watch on every ``done`` (_watch_confirmation), on cores with cfg_confirm_frames.
        self.has_confirmation = hasattr(dut, "cfg_confirm_frames")
        self.confirmation = ConfirmationAccount()
        self.confirm_was_pending = {}   # done time (s) -> the frame there was to be confirmed

    def _ports(self, names):
        """The names of ``names`` this build has: no word past its last, and in a one-word
        build no SPW check and no word-1 CRC counter."""
        def has(n):
            m = _WORD_OF_PORT.search(n)
            if m and int(m.group(1)) >= self.words:
                return False
            return self.words >= 2 or not any(k in n for k in ("spw", "crc_word1"))
        return [n for n in names if has(n)]

    # -- Setup ----------------------------------------------------------------------------
    async def start(self, cable=Cable(), timeout_s=12.5e-6, *, control=None, min_cycle_s=None):
        """Clock, inputs, reset and the encoder model; ``control``: an
        ``encoder_model.control.ControlSlave`` for the CDS/CDM side (None: CDS as sent, CDM
        ignored); ``min_cycle_s``: the encoder's shortest start-to-start (default: the
        RESOLUTE / EVOLUTE 31.25 us)."""
        dut = self.dut
        if not INTERNAL_CLOCK:              # else the wrapper makes it (sim/shared/fastclk.py)
            Clock(dut.clk, CLK_NS, unit="ns").start()
        # Drive every input from time 0 (an undriven input is X in a four-state simulator).
        for name in ("start", "periodic", "abort_cycle") + (
                ("clear_counters",) if self.has_counters else ()):
            getattr(dut, name).value = 0
        for name in self._ports(CFG_PORTS + (CUSTOM_CRC_PORTS if self.has_custom_crc else [])
                                + (SIGNED_PORTS if self.has_signed else [])
                                # SSI mode (master_contract.SSI_PORTS), in builds with it: 0 = BiSS
                                + [n for n in SSI_PORTS if hasattr(dut, n)]):
            getattr(dut, name).value = 0
        self._drive_noise_config(self.noise_defaults)
        # The register-access engine's inputs (builds with it): no access unless a test asks.
        for name in ("ca_slave_id", "ca_address", "ca_count", "ca_write", "ca_start", "ca_abort",
                     "ca_wbuf_addr", "ca_wbuf_data", "ca_wbuf_en", "ca_rbuf_addr", "ca_rbuf_en"):
            if hasattr(dut, name):
                getattr(dut, name).value = 0
        dut.slo.value = 1
        dut.rst.value = 1
        self.encoder = self._make_encoder(cable, timeout_s, control, min_cycle_s)
        self.encoder.start()
        await ClockCycles(dut.clk, 3)
        dut.rst.value = 0
        await RisingEdge(dut.clk)
        self.t_clk0 = get_sim_time("step")
        if self.has_confirmation:
            cocotb.start_soon(self._watch_confirmation())
        # Power-up break: the core is busy for 40 us before it accepts requests.
        await self.wait_idle()

    def _make_encoder(self, cable, timeout_s, control, min_cycle_s):
        """The encoder model on the MA / SLO pins (an SSI test bench puts its own there)."""
        extra = {} if min_cycle_s is None else {"min_cycle_s": min_cycle_s}
        return BissEncoder(self.dut.ma, self.dut.slo, cable=cable, respond=self._respond,
                           timeout_s=timeout_s, rng=self.rng, control=control, **extra)

    async def _watch_confirmation(self):
        """Every reported cycle, by its status: after one with a status outside
        CONFIRM_NEUTRAL the next ``cfg_confirm_frames`` frames (0: 1, 15: none) that pass every
        check are UNCONFIRMED (docs/ports.md, "Confirmation after a fault"). Records, per
        ``done``, whether its frame was to be confirmed: :meth:`expected_status` reads it."""
        dut = self.dut
        while True:
            await RisingEdge(dut.done)
            await ReadOnly()
            setting = int(dut.cfg_confirm_frames.value)
            self.confirm_was_pending[get_sim_time("step") * 1e-12] = \
                self.confirmation.pending(setting)
            # Results are judged soon after their ``done``: keep the recent ones only, so a
            # long campaign does not grow the map with every cycle.
            while len(self.confirm_was_pending) > CONFIRM_MEMORY:
                del self.confirm_was_pending[next(iter(self.confirm_was_pending))]
            self.confirmation.reported(int(dut.status.value), setting)

    def expected_status(self, res, status):
        """The status a result must have that the protocol's checks judge ``status``: a frame
        that passes them all is UNCONFIRMED within ``cfg_confirm_frames`` frames of a fault."""
        if status == "OK" and self.confirm_was_pending.get(res.t_done_s, False):
            return "UNCONFIRMED"
        return status

    async def wait_idle(self, limit_s=1e-3):
        """Until ``busy`` is low: a start is only honoured then (else it is an overrun)."""
        await RisingEdge(self.dut.clk)
        # Icarus 11 runs Yosys's combinational blocks only on their first input change, so
        # busy reads X until the power-up break ends: count that as busy.
        waited = 0.0
        while not self.dut.busy.value.is_resolvable:
            await Timer(1, "us")
            waited += 1e-6
            assert waited < limit_s, "busy never resolved"
        if int(self.dut.busy.value):
            await with_timeout(FallingEdge(self.dut.busy), limit_s * 1e9, "ns")
            await RisingEdge(self.dut.clk)

    async def encoder_ready(self, limit_s=1e-3):
        """Until the encoder model would start a cycle (its timeout is over)."""
        for _ in range(int(limit_s / 1e-6)):
            if self.encoder.ready:
                return
            await Timer(1, "us")
        raise AssertionError("encoder model never became ready")

    def configure(self, fmt, ma_hz=None, *, half_period=None, spw_tolerance=1, **cfg):
        """Set the cfg_* ports for a frame format (frames.FrameFormat) and MA rate: every word
        of the build, those past the format's disabled (``cfg_wN_enable`` 0, a harmless valid
        one-bit CRC-6 word); the SPW check on for BiSS Safety (two words, not a chain)."""
        dut = self.dut
        self.fmt = fmt
        hp = half_period if half_period is not None else half_period_for(ma_hz)
        ports = {
            "cfg_ma_half_period": hp, "cfg_request_period": 0, "cfg_break_time": 0,
            "cfg_ack_limit": 0, "cfg_timeout_limit": 0, "cfg_delay_limit": 0, "cfg_end_check": 0,
            **{f"cfg_w{w}_enable": int(w < len(fmt.words)) for w in range(1, self.words)},
            "cfg_spw_check": int(fmt.is_safety), "cfg_spw_tolerance": spw_tolerance,
        }
        # A BiSS frame format: the SSI mode off (builds with it; SsiTestbench sets it in cfg).
        ports.update({n: 0 for n in SSI_PORTS if hasattr(dut, n)})
        for w in range(self.words):
            word = fmt.words[w] if w < len(fmt.words) else frames.WordFormat(1)
            code, custom = crc_config(word.crc)
            ports.update({f"cfg_w{w}_data_bits": word.data_bits, f"cfg_w{w}_nenw": int(word.nenw),
                          f"cfg_w{w}_lc": int(word.lc), f"cfg_w{w}_crc": code,
                          f"cfg_w{w}_gray": int(word.gray)})
            if self.has_signed:
                ports[f"cfg_w{w}_signed"] = int(word.signed)
            else:
                assert not word.signed, "this build has no signed words"
            if self.has_custom_crc:
                ports.update({f"cfg_w{w}_crc_{k}": v for k, v in custom.items()})
            else:
                assert code != CRC_CODE["custom"], "this build has no custom CRCs"
        noise = {**self.noise_defaults, **{n: cfg.pop(n) for n in list(cfg)
                                           if n in NOISE_CONFIG_DEFAULTS}}
        ports.update(cfg)
        assert len(fmt.words) <= self.words, \
            f"{fmt.name} needs a build of {len(fmt.words)} words, this one has {self.words}"
        for name in self._ports(ports):
            getattr(dut, name).value = ports[name]
        self._drive_noise_config(noise)
        self.half_period = hp
        self.source = frames.EncoderFrameSource(fmt, self._position_at,
                                                 sign_of_life=self.sign_of_life,
                                                 chain_positions_at=self._chain_positions_at)
        # A new setup is a new encoder or cable for the core: re-arm its round-trip check, as
        # a user does (docs/ports.md, "Noise: the line checks").
        self.delay_tolerance = noise.get("cfg_delay_tolerance", 0)
        if hasattr(dut, "cfg_delay_tolerance"):
            self.rearm_delay_check()

    def rearm_delay_check(self):
        """Forget the settled round trip: ``cfg_delay_tolerance`` = 15 for two clocks, then the
        configured setting back (docs/ports.md). Returns at once; the restore runs on its own
        (a value written now reads back only after this time step, hence the stored one)."""
        dut = self.dut
        keep = self.delay_tolerance
        dut.cfg_delay_tolerance.value = 15

        async def restore():
            await ClockCycles(dut.clk, 2)
            dut.cfg_delay_tolerance.value = keep

        cocotb.start_soon(restore())

    def _drive_noise_config(self, values):
        """Issue 28's configuration ports, those the core has (the others are ignored: a core
        without the defences runs the same scenario without them); a value wider than its port
        (the 1 us quiet time at a fast clock) is clamped to the port's largest."""
        for name, value in values.items():
            if hasattr(self.dut, name):
                port = getattr(self.dut, name)
                port.value = min(value, (1 << len(port)) - 1)

    def _position_at(self, t):
        return self.rng.getrandbits(self.fmt.words[0].data_bits)

    def _chain_positions_at(self, t):
        """A chain's slaves each at their own random position (only chains draw these)."""
        return [self.rng.getrandbits(w.data_bits) for w in self.fmt.words]

    # -- The encoder's answer ---------------------------------------------------------------
    def queue(self, *, values=None, faults=None, lc=None, **response):
        """Plan the next cycle: explicit WordValues, frame faults, Response fields (fault=...)."""
        self.plan.append((values, faults, lc, response))

    def _respond(self, t_latch):
        values, faults, lc, response = self.plan.pop(0) if self.plan else (None, None, None, {})
        if values is None:
            values = self.source.values_at(t_latch, lc=lc)
        bits = frames.build_frame(self.fmt, values, faults)
        response.setdefault("processing_time_s", self.rng.uniform(*self.processing_s))
        resp = Response(bits=bits, **response)
        self.sent.append(Sent(values, bits, faults, resp))
        return resp

    # -- One request ------------------------------------------------------------------------
    async def request(self, limit_s=3e-3):
        """Wait until idle, pulse start, wait for done, return the Result."""
        dut = self.dut
        await self.wait_idle()
        dut.start.value = 1
        # Wait for done from now on: a bad configuration answers on the very next edge.
        done = cocotb.start_soon(self.wait_done(limit_s))
        await RisingEdge(dut.clk)
        dut.start.value = 0
        return await done

    async def wait_done(self, limit_s=3e-3):
        self.check_pending()
        await with_timeout(RisingEdge(self.dut.done), limit_s * 1e9, "ns")
        # Every result register changed on the same clock edge as done; read them once all
        # updates of that time step are in (simulators order them differently), then step
        # past the read-only phase so the caller may drive inputs again.
        await ReadOnly()

        async def next_clock():
            await RisingEdge(self.dut.clk)
            await ReadOnly()

        res = await self.read_done(next_clock)
        await Timer(1, "ps")
        if FRAME_LOG:                   # optional tally of ended cycles (for reports)
            with open(FRAME_LOG, "a") as f:
                f.write(f"{res.status}\n")
        return res

    async def read_done(self, next_clock):
        """The result ports, read in the clock of ``done``, with the counters read one clock
        later (they count a cycle a clock after its ``done``, docs/ports.md, Counters).
        ``next_clock``: a coroutine function that waits to the same point of the next clock."""
        res = self.read()
        if self.has_counters:
            await next_clock()
            res.counters = self.read().counters
        return res

    def read(self):
        dut = self.dut
        names = ["line_delay", "cds", "lc", "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch"]
        names += ["timestamp"] if self.has_timestamp else []
        for w in range(self.words):
            names += [f"word{w}_position", f"word{w}_ne", f"word{w}_nw", f"word{w}_crc_ok"]
        fields = {n: _int(dut, n) for n in self._ports(names) if not n.endswith("crc_ok")}
        # Icarus 11 runs Yosys's combinational blocks only on an input change (see wait_idle):
        # for a word whose CRC kind is "none" the checker's ``ok = 1`` may not have run yet,
        # and its crc_ok reads X. Read as None; check_frame accepts it only for such a word.
        fields.update({n: int(v) if (v := getattr(dut, n).value).is_resolvable else None
                       for n in self._ports(names) if n.endswith("crc_ok")})
        fields.update({n: _int(dut, n) for n in self.noise_fields})
        names = self._ports(COUNTERS) + self.noise_counters if self.has_counters else []
        # A chain build counts each word's CRC errors (count_crc_word2 ..).
        names += [f"crc_word{w}" for w in range(2, self.words) if self.has_counters]
        if self.has_counters and self.has_register_access:
            names += list(CA_COUNTERS.values())
        counters = {n: _int(dut, f"count_{n}") for n in names}
        return Result(_int(dut, "status"), _int(dut, "valid"), fields, counters,
                      get_sim_time("step") * 1e-12)

    # -- Checks -------------------------------------------------------------------------------
    def clocks(self, seconds):
        return seconds * CLK_HZ

    @staticmethod
    def line_bits(sent, view):
        """The bits a master that reads the frame format ``view`` takes from the line: what the
        encoder sent, then zeros (its stop bit and timeout keep SLO low while MA clocks on)."""
        n = frames.FRAME_HEADER_BITS + view.total_bits
        assert len(sent.bits) <= n, f"{view.name} is shorter than the encoder's frame"
        return list(sent.bits) + [0] * (n - len(sent.bits))

    def check_frame(self, res, *, status="OK", sent=None, record=None, check_rises=True,
                    view=None):
        """Every field of a decoded frame against what the encoder sent and what the wire did.

        ``view``: the frame format the master is configured for, if not the encoder's own
        (``self.fmt``); it must not be shorter (:meth:`line_bits`)."""
        sent = sent or self.sent[-1]
        record = record or self.encoder.records[-1]
        view = view or self.fmt
        status = self.expected_status(res, status)
        assert res.status == STATUS[status], f"status {res.status}, expected {status}"
        assert res.valid == int(status == "OK"), f"valid {res.valid} with status {status}"
        f = res.fields
        parsed = frames.parse_frame(view, self.line_bits(sent, view))
        for w, word in enumerate(parsed["words"]):
            got = f[f"word{w}_position"]
            want = port_position(view.words[w], word["position"],
                                 len(getattr(self.dut, f"word{w}_position")))
            assert got == want, f"word{w} position {got:#x} != sent {want:#x}"
            if view.words[w].nenw:
                assert (f[f"word{w}_ne"], f[f"word{w}_nw"]) == (word["ne"], word["nw"])
            if f[f"word{w}_crc_ok"] is None:
                assert view.words[w].crc == frames.CRC_NONE, f"word{w} crc_ok reads X"
            else:
                assert f[f"word{w}_crc_ok"] == int(word["crc_ok"]), f"word{w} crc_ok"
            if view.words[w].lc:
                assert f["lc"] == word["lc"], f"lc {f['lc']} != sent {word['lc']}"
        if self.words > 2:
            # A chain build: a disabled word's crc_ok reads 1 (not in the frame, not failed).
            for w in range(len(view.words), self.words):
                assert f[f"word{w}_crc_ok"] == 1, f"word{w} (disabled) crc_ok {f[f'word{w}_crc_ok']}"
        # With a control slave the encoder put its CDS in the frame (the record has it).
        cds = parsed["cds"] if record.cds is None else record.cds
        assert f["cds"] == cds, f"cds {f['cds']} != sent {cds}"
        # Line delay: the core reports ceil(true round trip) in clocks.
        rt = self.clocks(record.round_trip_s)
        assert rt - 1e-6 <= f["line_delay"] < rt + 1 + 1e-6, \
            f"line delay {f['line_delay']} clocks, true round trip {rt:.3f}"
        # Timestamp: clock edges from the first one after reset to the first MA rise.
        if self.has_timestamp:
            edges = round((record.t_first_rise_s * 1e12 - self.t_clk0) / (CLK_NS * 1e3))
            width = len(self.dut.timestamp)
            assert f["timestamp"] == (edges + 1) % 2**width, \
                f"timestamp {f['timestamp']} != {edges + 1} (mod 2**{width})"
        if check_rises:
            self.pending.append((record, self.half_period, view, res.t_done_s))
        return parsed

    def check_pending(self):
        """MA-rise checks of cycles the encoder has closed (MA high longer than its timeout)."""
        for item in [i for i in self.pending if i[0].ended]:
            self.pending.remove(item)
            self.check_ma_rises(*item)

    def check_ma_rises(self, record, half_period, fmt, t_done_s=None):
        """MA gives the frame exactly the rising edges it needs, unless the round trip is longer
        than the frame (the master learns where Start was only a round trip later)."""
        period_s = 2 * half_period / CLK_HZ
        start_edge = 1 + round((record.t_start_rise_s - record.t_first_rise_s) / period_s)
        needed = start_edge + 1 + fmt.total_bits + 1      # Start, CDS, data, stop
        # The master learns of Start a round trip, half a period and 5 clocks after its MA edge
        # (synchronizer, sampler, decoder, registered target and compare).
        late = self.clocks(record.round_trip_s) + half_period + 5
        spare = 2 * half_period * (1 + fmt.total_bits + 1) - half_period
        if late < spare:
            assert record.ma_rises == needed, f"MA rises {record.ma_rises}, needed {needed}: done at {t_done_s}, {record}"
        else:
            extra = math.ceil(late / (2 * half_period)) + 1
            assert needed <= record.ma_rises <= needed + extra, \
                f"MA rises {record.ma_rises}, needed {needed} (+{extra} allowed)"
        assert not record.aborted
