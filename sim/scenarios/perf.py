"""make bench: performance measurements of ``biss_master`` against the encoder model (issue 4).

Run by sim/tools/perf.py, one cocotb test per run. Each test measures, checks every frame it
uses (``Testbench.check_frame``) and writes its raw figures as JSON to
``$BISS_PERF_OUT/<test>-<sim>.json``; sim/tools/perf.py turns them into tables and judges them
against the goals. Nothing here asserts a goal: a missed goal must show up in the tables, not as
a crashed test.

* ``request_cycle_overhead``: periodic "as fast as possible" mode (``cfg_request_period`` = 0),
  start-to-start time from the master's MA falling edges, the protocol minimum, and the
  master's dead time (SLO high at its pin -> its next MA fall).
* ``verdict_latency``: clocks from the sampling of the last CRC bit to ``done`` / ``valid``.
* ``line_delay_error``: reported ``line_delay`` against the model's realised round trip.
* ``sim_speed``: N frames of one fixed scenario; wall time of the frame loop only.
* ``register_access_cost``: data frames and time per register access (control channel) against
  the protocol's floor, with request cycles as fast as the encoder allows.
"""

import json
import math
import os
import platform
import time

import cocotb
from cocotb.simtime import get_sim_time
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

import protocol_facts as facts
from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from encoder_model.control import (ADDRESS_BITS, CRC4_WIDTH, DATA_BITS, ID_BITS, IDLE_FRAMES,
                                   Bp3Eds, ControlSlave, RegisterFile)
from encoder_model.control_master import RegisterAccess, control_frame_cdm
from master_contract import CA_STATUS
from sim.shared.control_channel import ControlChannel
from sim.shared.testbench import CLK_HZ, Testbench, half_period_for, preset

PS_PER_CLK = round(1e12 / CLK_HZ)

#: The "typical cable" of the overhead and latency tables: 25 m, 292.5 ns of round trip.
TYPICAL_CABLE_M = 25

OVERHEAD_PRESETS = ["resolute_c_36", "resolute_fs_rsh", "bp3_24"]
OVERHEAD_RATES_HZ = [1e6, 2.5e6, 5e6, 10e6]
#: Encoder timing profiles of the overhead table: (name, processing time, timeout).
#: ``None`` processing time: the protocol minimum (Start on the 3rd MA rise, 2 MA periods after
#: the latch edge). A timeout given as a string "1.5T" is adaptive: 1.5 MA periods.
OVERHEAD_PROFILES = [("typical", 5e-6, 12.5e-6), ("fastest", None, "1.5T")]
OVERHEAD_INTERVALS = int(os.environ.get("BISS_PERF_INTERVALS", "5"))
DEAD_SWEEP_RUNS = 20
DEAD_SWEEP_MA_HZ = 10e6

LATENCY_PRESETS = ["resolute_fs_rsh", "resolute_c_36", "bp3_24", "bp3_1"]
LATENCY_RATES_HZ = [1e6, 10e6]
LATENCY_CABLES_M = [0, 100]

DELAY_RATES_HZ = [10e6, 1e6]
DELAY_CABLES_M = [0, 3, 10, 25, 50, 100, 200]
DELAY_JITTER = [0.0, 0.05, 0.125]       # peak jitter per edge and direction, fraction of T_MA
DELAY_FRAMES = int(os.environ.get("BISS_PERF_DELAY_FRAMES", "6"))
DELAY_PRESET = "resolute_c_36"

SPEED_PRESET = "resolute_fs_rsh"
SPEED_MA_HZ = 10e6
SPEED_CABLE_M = TYPICAL_CABLE_M
SPEED_FRAMES = int(os.environ.get("BISS_PERF_SPEED_FRAMES", "200"))


def ps(seconds):
    """Model times (seconds, from integer ps steps) back to integer ps."""
    return round(seconds * 1e12)


def dump(test, data):
    out = os.environ.get("BISS_PERF_OUT")
    data = {"test": test, "sim": cocotb.SIM_NAME, "sim_version": cocotb.SIM_VERSION,
            "clk_hz": CLK_HZ, "internal_clock": bool(os.environ.get("BISS_INTERNAL_CLOCK")),
            **data}
    if out:
        os.makedirs(out, exist_ok=True)
        sim = "icarus" if "icarus" in cocotb.SIM_NAME.lower() else "verilator"
        variant = os.environ.get("BISS_PERF_VARIANT", "")     # "iclk": clock made in Verilog
        name = f"{test}-{sim}{'-' + variant if variant else ''}.json"
        with open(os.path.join(out, name), "w") as f:
            json.dump(data, f, indent=1)


class PerfTestbench(Testbench):
    """The regression testbench with a fixed encoder processing time (the regression draws it at
    random per frame) and a tally of frame checks that failed, instead of stopping at the first."""

    processing_time_s = 5e-6

    def __init__(self, dut, **kw):
        super().__init__(dut, **kw)
        self.failures = []
        self.checked = 0

    def _respond(self, t_latch):
        if not self.plan:
            self.queue(processing_time_s=self.processing_time_s)
        return super()._respond(t_latch)

    def check(self, res, **kw):
        self.checked += 1
        try:
            self.check_frame(res, **kw)
        except AssertionError as e:
            self.failures.append(str(e))
            self.dut._log.error("frame check failed: %s", e)

    def check_ma_rises(self, *args, **kw):
        try:
            super().check_ma_rises(*args, **kw)
        except AssertionError as e:
            self.failures.append(str(e))
            self.dut._log.error("MA rise check failed: %s", e)


def start_index(record, t_ma):
    """Index k of the MA rising edge that launched Start (1 = the latch edge)."""
    return 1 + round((record.t_start_rise_s - record.t_first_rise_s) / t_ma)


async def log_edges(signal, edge, times):
    while True:
        await edge(signal)
        times.append(get_sim_time("step"))


# -- 1. Request-cycle overhead --------------------------------------------------------------------
@cocotb.test()
async def request_cycle_overhead(dut):
    tb = PerfTestbench(dut, seed=41)
    cable = Cable(length_m=TYPICAL_CABLE_M)
    await tb.start(cable=cable)
    # A generic BiSS C slave: no 31.25 us request-rate rule (a RESOLUTE/EVOLUTE would hold SLO
    # low until 31.25 us after the cycle's start, and that rule would set the pace instead).
    tb.encoder.min_cycle_s = 0.0
    slo_rises = []                      # SLO rising edges at the master's pin (after the cable)
    cocotb.start_soon(log_edges(dut.slo, RisingEdge, slo_rises))
    rows = []
    for profile, proc_s, timeout in OVERHEAD_PROFILES:
        for name in OVERHEAD_PRESETS:
            fmt = preset(name)
            for ma_hz in OVERHEAD_RATES_HZ:
                t_ma = 1 / ma_hz
                timeout_s = 1.5 * t_ma if timeout == "1.5T" else timeout
                tb.processing_time_s = 0.0 if proc_s is None else proc_s
                await tb.wait_idle()
                await tb.encoder_ready()
                tb.encoder.timeout_s = timeout_s
                tb.configure(fmt, ma_hz)               # cfg_request_period = 0
                first = len(tb.encoder.records)
                dut.periodic.value = 1
                for _ in range(OVERHEAD_INTERVALS + 1):
                    tb.check(await tb.wait_done())
                dut.periodic.value = 0
                await tb.wait_idle()
                await tb.encoder_ready()               # the last cycle has ended
                recs = tb.encoder.records[first:first + OVERHEAD_INTERVALS + 1]
                falls = [ps(r.t_first_fall_s) for r in recs]
                intervals = [b - a for a, b in zip(falls, falls[1:])]
                dead = []
                for f in falls[1:]:
                    rise = max(t for t in slo_rises if t < f)
                    dead.append(f - rise)
                # Protocol minimum, T_MA x (5 + D) + line delay + processing time + timeout:
                # D = every bit of the data words (position, nE/nW, LC, CRC). The 5 are the latch
                # rise, one Ack slot, Start, CDS and the stop bit, so "processing time" is the Ack
                # beyond its first slot: Start comes on MA rise k >= 3, the first at or after the
                # encoder's processing time past the latch edge, i.e. (k - 3) extra MA periods.
                ks = {start_index(r, t_ma) for r in recs}
                k_model = max(3, 1 + math.ceil(tb.processing_time_s / t_ma - 1e-9))
                proc_extra_s = (k_model - 3) * t_ma
                d_bits = fmt.total_bits
                line_delay_s = cable.round_trip_s()
                minimum_s = t_ma * (5 + d_bits) + line_delay_s + proc_extra_s + timeout_s
                needed_rises = [start_index(r, t_ma) + 2 + d_bits for r in recs]
                rows.append({
                    "profile": profile, "preset": name, "ma_hz": ma_hz, "t_ma_s": t_ma,
                    "data_crc_bits": d_bits, "cable_m": TYPICAL_CABLE_M,
                    "line_delay_s": line_delay_s, "processing_time_s": tb.processing_time_s,
                    "start_rise": sorted(ks), "start_rise_model": k_model,
                    "proc_extra_s": proc_extra_s, "timeout_s": timeout_s,
                    "minimum_s": minimum_s,
                    "intervals_s": [i * 1e-12 for i in intervals],
                    "dead_s": [d * 1e-12 for d in dead],
                    "ma_rises": [r.ma_rises for r in recs], "needed_rises": needed_rises,
                    "aborted": sum(r.aborted for r in recs),
                })
                dut._log.info("%s %s %.1f MHz: start-to-start %.3f us, minimum %.3f us, "
                              "dead %s ns", profile, name, ma_hz / 1e6,
                              sum(intervals) / len(intervals) * 1e-6, minimum_s * 1e6,
                              [d / 1e3 for d in dead])
    # The dead time depends on where the SLO edge falls between two clock edges: sweep that
    # phase with a random 0..20 ns transceiver delay per run (fastest slave, 10 MHz).
    sweep = []
    fmt = preset(OVERHEAD_PRESETS[0])
    tb.processing_time_s = 0.0
    for _ in range(DEAD_SWEEP_RUNS):
        await tb.wait_idle()
        await tb.encoder_ready()
        tb.encoder.set_cable(Cable(length_m=TYPICAL_CABLE_M,
                                      extra_round_trip_s=tb.rng.uniform(0, 20e-9)))
        tb.encoder.timeout_s = 1.5 / DEAD_SWEEP_MA_HZ
        tb.configure(fmt, DEAD_SWEEP_MA_HZ)
        first = len(tb.encoder.records)
        dut.periodic.value = 1
        for _ in range(3):
            tb.check(await tb.wait_done())
        dut.periodic.value = 0
        await tb.wait_idle()
        await tb.encoder_ready()
        falls = [ps(r.t_first_fall_s) for r in tb.encoder.records[first:first + 3]]
        sweep += [(f - max(t for t in slo_rises if t < f)) * 1e-12 for f in falls[1:]]
    await tb.wait_idle()
    dump("request_cycle_overhead", {"rows": rows, "checked": tb.checked,
                                    "dead_sweep_s": sweep, "dead_sweep_preset": fmt.name,
                                    "dead_sweep_ma_hz": DEAD_SWEEP_MA_HZ,
                                    "failures": tb.failures,
                                    "ignored_falls": len(tb.encoder.ignored_falls),
                                    "overrun": tb.read().counters["overrun"]})


# -- 2. Latency from the last CRC bit to the verdict --------------------------------------------
@cocotb.test()
async def verdict_latency(dut):
    """The sampler's ``sample`` strobe marks the clock in which a slot is decided: its third vote,
    v = hp // 2 clocks after the middle of the slot (v = 0 at hp = 2; docs/ports.md, "Noise
    immunity"): the clock edge that starts it is "the core decides the bit" (the decoder and CRC
    registers take it at the next edge). The last strobe before ``done`` must be the
    last CRC bit: that is checked by counting strobes (Ack slots + Start + CDS + every data and
    CRC bit) and, independently of the RTL, by predicting its clock edge from the model's edge
    times: first clock edge after the Ack fall reaches the SLO pin, + 1 (second synchronizer
    flop) + half period + slot x MA period + v."""
    tb = PerfTestbench(dut, seed=42)
    await tb.start()
    tb.encoder.min_cycle_s = 0.0
    strobes, dones, valids = [], [], []
    for sig, times in ((dut.sampler.sample, strobes), (dut.done, dones), (dut.valid, valids)):
        cocotb.start_soon(log_edges(sig, RisingEdge, times))
    rows = []
    for cable_m in LATENCY_CABLES_M:
        cable = Cable(length_m=cable_m)
        tb.encoder.set_cable(cable)
        for name in LATENCY_PRESETS:
            fmt = preset(name)
            for ma_hz in LATENCY_RATES_HZ:
                tb.configure(fmt, ma_hz)
                hp = half_period_for(ma_hz)
                for corrupt in (False, True):
                    faults = frames.FrameFaults(flip_bits=(2 + fmt.total_bits - 1,)) \
                        if corrupt else None
                    tb.queue(faults=faults, processing_time_s=tb.processing_time_s)
                    mark = len(strobes), len(dones), len(valids)
                    res = await tb.request()
                    status = "OK" if not corrupt else \
                        ("CRC_ERROR_WORD1" if len(fmt.words) == 2 else "CRC_ERROR_WORD0")
                    tb.check(res, status=status)
                    rec = tb.encoder.records[-1]
                    t_done = dones[mark[1]]
                    t_valid = valids[mark[2]] if len(valids) > mark[2] else None
                    # (the previous cycle's stop-bit strobe comes after its done: skip it)
                    cyc_strobes = [t for t in strobes[mark[0]:]
                                   if ps(rec.t_first_fall_s) < t <= t_done]
                    k = start_index(rec, 1 / ma_hz)
                    expected_strobes = (k - 2) + 2 + fmt.total_bits   # Ack slots, Start, CDS, D
                    # Model prediction of the last CRC bit's strobe edge.
                    t_ack_pin = ps(rec.t_first_rise_s) + 2 * hp * PS_PER_CLK + ps(rec.round_trip_s)
                    phase = tb.t_clk0 % PS_PER_CLK        # clock edges: phase + n x T_clk
                    first_edge = ((t_ack_pin - phase) // PS_PER_CLK + 1) * PS_PER_CLK + phase
                    slot = expected_strobes - 1
                    vote = hp // 2 if hp >= 3 else 0
                    predicted = first_edge + (1 + hp + 2 * hp * slot + vote) * PS_PER_CLK
                    rows.append({
                        "preset": name, "ma_hz": ma_hz, "cable_m": cable_m,
                        "corrupt_last_crc_bit": corrupt, "status": res.status,
                        "valid": res.valid,
                        "strobes": len(cyc_strobes), "expected_strobes": expected_strobes,
                        "t_last_strobe_ps": cyc_strobes[-1], "t_predicted_ps": predicted,
                        "t_done_ps": t_done, "t_valid_ps": t_valid,
                        "done_clocks": (t_done - cyc_strobes[-1]) / PS_PER_CLK,
                        "vote_clocks": vote,
                        "valid_clocks": None if t_valid is None or corrupt
                        else (t_valid - cyc_strobes[-1]) / PS_PER_CLK,
                    })
                    if corrupt and len(fmt.words) == 2:
                        # The LC of a frame with a bad SPW CRC is not trusted: the next frame
                        # shows the lost frame as a sign-of-life skip (not measured).
                        tb.check(await tb.request(), status="SIGN_OF_LIFE")
                    if corrupt:
                        # After a fault the first good frame is UNCONFIRMED, not valid (the
                        # default confirmation, docs/ports.md; the testbench expects it): one
                        # more, not measured, so that the next point's good frame is valid.
                        tb.check(await tb.request())
    dump("verdict_latency", {"rows": rows, "checked": tb.checked, "failures": tb.failures})


# -- 3. Line-delay measurement error ---------------------------------------------------------------
@cocotb.test()
async def line_delay_error(dut):
    """Reported ``line_delay`` minus the model's realised round trip (master's 2nd MA rise to the
    Ack fall at its SLO pin, jitter included). Each frame adds a random 0..20 ns of transceiver
    delay, so the round trip takes every phase against the system clock."""
    tb = PerfTestbench(dut, seed=43)
    await tb.start()
    tb.encoder.min_cycle_s = 0.0
    fmt = preset(DELAY_PRESET)
    rows = []
    for ma_hz in DELAY_RATES_HZ:
        tb.configure(fmt, ma_hz)
        for cable_m in DELAY_CABLES_M:
            for jitter in DELAY_JITTER:
                # A new cable: re-arm the round-trip check, as a user does (docs/ports.md,
                # "Noise: the line checks"); else the new length is a DELAY_JUMP.
                await tb.wait_idle()
                tb.rearm_delay_check()
                errors, trips, reported = [], [], []
                for _ in range(DELAY_FRAMES):
                    await tb.wait_idle()
                    await tb.encoder_ready()
                    tb.encoder.set_cable(Cable(length_m=cable_m,
                                                  extra_round_trip_s=tb.rng.uniform(0, 20e-9),
                                                  jitter_s=jitter / ma_hz))
                    res = await tb.request()
                    tb.check(res, check_rises=jitter == 0)
                    rec = tb.encoder.records[-1]
                    errors.append(res.fields["line_delay"] - rec.round_trip_s * CLK_HZ)
                    trips.append(rec.round_trip_s)
                    reported.append(res.fields["line_delay"])
                rows.append({"ma_hz": ma_hz, "cable_m": cable_m, "jitter": jitter,
                             "nominal_round_trip_s": Cable(length_m=cable_m).round_trip_s(),
                             "errors_clk": errors, "round_trips_s": trips,
                             "line_delays_clk": reported})
    dump("line_delay_error", {"rows": rows, "checked": tb.checked, "failures": tb.failures,
                              "preset": DELAY_PRESET})


# -- 4. Simulation speed ---------------------------------------------------------------------------
@cocotb.test()
async def sim_speed(dut):
    """SPEED_FRAMES frames of a RESOLUTE FS RSH (BiSS Safety 36/28) at 10 MHz over 25 m, periodic
    as fast as the encoder allows (its 31.25 us rule included), every frame checked. Only the
    frame loop is timed: no build, no simulator start-up, no reset and power-up break."""
    tb = PerfTestbench(dut, seed=44)
    await tb.start(cable=Cable(length_m=SPEED_CABLE_M))
    tb.configure(preset(SPEED_PRESET), SPEED_MA_HZ)
    await tb.wait_idle()
    t_sim0 = get_sim_time("step")
    wall0 = time.perf_counter()
    cpu0 = time.process_time()
    dut.periodic.value = 1
    for _ in range(SPEED_FRAMES):
        tb.check(await tb.wait_done())
    dut.periodic.value = 0
    wall = time.perf_counter() - wall0
    cpu = time.process_time() - cpu0
    sim_s = (get_sim_time("step") - t_sim0) * 1e-12
    dump("sim_speed", {"frames": SPEED_FRAMES, "wall_s": wall, "cpu_s": cpu, "sim_time_s": sim_s,
                       "preset": SPEED_PRESET, "ma_hz": SPEED_MA_HZ, "cable_m": SPEED_CABLE_M,
                       "checked": tb.checked, "failures": tb.failures,
                       "python": platform.python_version()})


# -- 5. Register access: frames and time per access ------------------------------------------------
#: A BP3 encoder with a 24-bit position (32 bits after CDS: position, nE, nW, CRC-6) at the
#: protocol's fastest: 10 MHz, Start on the 3rd MA rise (the minimum processing time), the adaptive
#: timeout of 1.5 MA periods (docs/protocol.md, section 9), no 31.25 us rule; 100 m of cable.
CONTROL_DL_POS = 24
CONTROL_MA_HZ = 10e6
CONTROL_CABLE_M = 100
CONTROL_TIMEOUT_MA_PERIODS = 1.5
CONTROL_BANK = 1            # the EDS bank (register 0x41), selected: 0x00..0x3F show it
CONTROL_USER_REGISTER = 0x50


def control_frame_bits(count):
    """CDM bits of the control frame of an access to ``count`` consecutive registers, from spec
    section 10: S, CTS, ID[2:0], ADR[6:0], CRC4[3:0], R, W (18 bits), then per register S, 8
    data slots, 4 CRC-4 slots and P (14 bits; "14 more frames per register")."""
    header = 1 + 1 + ID_BITS + ADDRESS_BITS + CRC4_WIDTH + 1 + 1
    return header + count * (1 + DATA_BITS + CRC4_WIDTH + 1)


def shortest_cycle_s(fmt, ma_hz, cable_m, timeout_s):
    """Spec section 9, the minimum cycle time of one slave: TMA x (5 + data bits + CRC bits) +
    line delay + processing time + timeout, with the processing time at its minimum (Start on
    the 3rd MA rise: the 5 already hold it, as in section 1) and the line delay of ``cable_m``
    (10 ns/m round trip + the encoder's 42.5 ns, section 3)."""
    line_delay_s = cable_m * facts.CABLE_ROUND_TRIP_S_PER_M + facts.ENCODER_INTERNAL_DELAY_S
    return (5 + fmt.total_bits) / ma_hz + line_delay_s + timeout_s


async def power_up_again(tb):
    """Reset the core as ``Testbench.start`` does (its count of CDM = 0 frames before S starts
    again at 0, docs/control.md) and wait out the power-up break."""
    dut = tb.dut
    await tb.wait_idle()
    await tb.encoder_ready()
    await FallingEdge(dut.clk)
    dut.rst.value = 1
    await ClockCycles(dut.clk, 3)
    dut.rst.value = 0
    await RisingEdge(dut.clk)
    tb.t_clk0 = get_sim_time("step")
    await tb.wait_idle()


def idle_on_line(records, t_power_up_s, t_start_s):
    """CDM = 0 frames in a row on the line since power-up, before ``t_start_s``: what the master
    can know the encoder has seen (a cycle already running at ``t_start_s`` included)."""
    n = 0
    for r in reversed([r for r in records if t_power_up_s <= r.t_first_fall_s < t_start_s]):
        if r.cdm:
            break
        n += 1
    return n


@cocotb.test()
async def register_access_cost(dut):
    """Register accesses through the ``ca_*`` ports against the encoder model's control slave,
    request cycles as fast as the encoder allows (``cfg_request_period`` = 0: the engine's own
    cycles with ``periodic`` = 0, and once with ``periodic`` = 1), every cycle checked field by
    field and every OK access's CDM against the reference layout (``ControlChannel``).

    Each access is timed from ``ca_start`` to ``ca_done`` in cycles reported (frames) and in
    simulated time, against the protocol's floor: the CDM = 0 frames still missing of the 14
    before S (14 after power-up; after a read none: its 12 slot zeros, P and final frame are
    14 already) plus the control frame's CDM bits (:func:`control_frame_bits`). Also recorded:
    the start-to-start time of every cycle of the access by its CDM (a CDM = 1 cycle holds MA
    low through the timeout, docs/timing.md)."""
    eds = Bp3Eds(CONTROL_DL_POS)
    regs = RegisterFile.bp3(eds, eds_bank=CONTROL_BANK, bank_select=CONTROL_BANK)
    fmt = frames.bp3(CONTROL_DL_POS)
    timeout_s = CONTROL_TIMEOUT_MA_PERIODS / CONTROL_MA_HZ
    tb = Testbench(dut, seed=45)
    tb.processing_s = (0.0, 0.0)
    cable = Cable(length_m=CONTROL_CABLE_M)
    await tb.start(cable=cable, timeout_s=timeout_s, control=ControlSlave(regs), min_cycle_s=0)
    tb.configure(fmt, CONTROL_MA_HZ)                    # cfg_request_period = 0
    rows, checked = [], 0
    t_power_up = 0.0
    ctl = ControlChannel(tb)

    async def measure(label, count, after, *, write=False, periodic=False):
        if periodic:
            await FallingEdge(dut.clk)
            dut.periodic.value = 1
            await ctl.monitor.wait_frames(ctl.monitor.count + IDLE_FRAMES)
        address = CONTROL_USER_REGISTER if write else 0x00
        data = bytes([0x5A ^ len(rows)]) if write else None
        expected = None if write else bytes(regs.read(a) for a in range(address, address + count))
        t0 = get_sim_time("step") * 1e-12
        acc = await ctl.access(0, address, count, write=write, data=data)
        if periodic:
            await FallingEdge(dut.clk)
            dut.periodic.value = 0
        assert acc.status == CA_STATUS["OK"], str(acc)
        if write:
            assert regs.read(address) == data[0], "the write did not reach the register"
        else:
            assert acc.data == expected, acc.data.hex()
        records = tb.encoder.records
        own = [r for r in records if acc.t_start_s <= r.t_first_fall_s <= acc.t_done_s]
        falls = [r.t_first_fall_s for r in own]
        cycles = {0: [], 1: []}
        for r, a, b in zip(own, falls, falls[1:]):
            cycles[r.cdm].append(b - a)
        cdm = [r.cdm for r in own]
        request = (RegisterAccess.write(address, data) if write
                   else RegisterAccess.read(address, count))
        layout = control_frame_cdm(request)
        assert len(layout) == control_frame_bits(count), "spec count and reference layout differ"
        idle_known = min(IDLE_FRAMES, idle_on_line(records, t_power_up, t0))
        rows.append({
            "access": label, "count": count, "write": write, "periodic": periodic,
            "after": after, "idle_on_line": idle_known,
            "floor_frames": IDLE_FRAMES - idle_known + control_frame_bits(count),
            "frames": acc.frames, "time_s": acc.t_done_s - acc.t_start_s,
            "frames_in_flight": acc.frames - len(own), "idle_before_s": cdm.index(1),
            "control_frames": len(layout),
            "after_last_p": len(own) - cdm.index(1) - len(layout),
            "cdm1_frames": sum(cdm), "cycle_cdm0_s": cycles[0], "cycle_cdm1_s": cycles[1],
        })
        dut._log.info("%s (%d idle frames on the line%s): %d frames, %.2f us", label,
                      idle_known, ", periodic" if periodic else "", acc.frames,
                      rows[-1]["time_s"] * 1e6)

    await measure("read 1 register", 1, "power-up")
    await measure("read 1 register", 1, "a read")
    await measure("write 1 register", 1, "a read", write=True)
    await measure("read 1 register", 1, "a write")
    await measure("read 1 register", 1, "a read", periodic=True)    # positions read meanwhile
    checked += ctl.monitor.count
    ctl.monitor.stop()
    for label, count, write in (("write 1 register", 1, True),
                                ("read 64 registers (EDS bank)", 64, False)):
        await power_up_again(tb)
        t_power_up = get_sim_time("step") * 1e-12
        ctl = ControlChannel(tb)
        await measure(label, count, "power-up", write=write)
        checked += ctl.monitor.count
        ctl.monitor.stop()
    await tb.wait_idle()
    assert not tb.encoder.ignored_falls, tb.encoder.ignored_falls[:5]
    dump("register_access_cost", {
        "rows": rows, "checked": checked, "preset": fmt.name, "data_crc_bits": fmt.total_bits,
        "ma_hz": CONTROL_MA_HZ, "cable_m": CONTROL_CABLE_M, "timeout_s": timeout_s,
        "line_delay_s": cable.round_trip_s(), "idle_frames": IDLE_FRAMES,
        "shortest_cycle_s": shortest_cycle_s(fmt, CONTROL_MA_HZ, CONTROL_CABLE_M, timeout_s)})
