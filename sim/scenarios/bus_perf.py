"""make bench, bus tops: the CPU-visible latency from a trigger to the result read over AXI4-Lite.

Run by sim/tools/perf.py on the committed ``biss_master_axil`` (Verilator); not part of the
regression. One cocotb test, ``bus_trigger_latency``: channel 0 reads an encoder model (the
protocol's fastest slave: Start on the third MA rise), ``irq`` enabled for ``done``. For each
point (preset, MA rate, cable, trigger source) one frame is started by the input ``trigger``
(a pulse synchronous to ``clk``) or by a write of the ``trigger`` register, with the master
idle and SLO high at its pin for longer than the quiet time (the previous cycle over), and
the moment the result is readable on the bus is measured, split into parts that add up
exactly:

* **start**: the trigger's clock edge (the edge at which the top takes the input, or the first
  edge that samples the trigger write's AWVALID high) -> the master's first MA fall (the
  model's pin time);
* **frame**: first MA fall -> the clock edge at which the core decides the last CRC bit,
  predicted on the test side from the model's edge times and the protocol (latch rise, the
  round trip, Ack slots, Start, CDS, the data and CRC bits, the sampling point of a slot and
  its third vote; the same derivation as sim/scenarios/perf.py's verdict_latency);
* **verdict**: that edge -> the edge that sets the core's output ``done`` (observed inside the
  bus top, ``ch0.done``: Verilator builds with public signals);
* **irq**: ``done`` -> the edge that sets the ``irq`` pin (the register bank's sticky status,
  the registered pin);
* **read**: ``irq`` -> the AXI read data of the result (the edge of the R handshake), for
  ``result.status``
  (the first read, which takes the snapshot) and for the position's two words after it;
  split into the bus master's reaction (irq -> the AR handshake; cocotbext-axi's
  AxiLiteMaster, a CPU would take longer) and the slave's own read latency (AR handshake ->
  R handshake).

Every frame is checked against what the encoder sent (``BusTestbench.check_result``). The raw
figures go to ``$BISS_PERF_OUT/bus_trigger_latency-<sim>.json``; nothing here judges them.
"""

import dataclasses
import json
import os

import cocotb
from cocotb.simtime import get_sim_time
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import QUIET_TIME_S
from sim.shared.bus_testbench import CLK_HZ, BusTestbench

PS_PER_CLK = round(1e12 / CLK_HZ)

BUS_LATENCY_PRESETS = ["resolute_c_36", "bp3_24"]
BUS_LATENCY_RATES_HZ = [1e6, 10e6]
BUS_LATENCY_CABLES_M = [0, 100]
BUS_LATENCY_TRIGGERS = ["pin", "register"]


def ps(seconds):
    return round(seconds * 1e12)


async def handshakes(clk, valid, ready, times, data=None):
    """The clock edges (ps) at which ``valid`` and ``ready`` are both high (with ``data``:
    (edge, data) pairs)."""
    while True:
        await RisingEdge(clk)
        if valid.value == 1 and ready.value == 1:
            t = get_sim_time("step")
            times.append((t, int(data.value)) if data is not None else t)


async def rises(signal, times):
    """The times (ps) at which ``signal`` rises: for a register, the clock edge that sets it."""
    while True:
        await RisingEdge(signal)
        times.append(get_sim_time("step"))


async def first_high(clk, signal, times):
    """The clock edges (ps) that first sample ``signal`` high (after an edge that sampled it
    low): for a bus input, the edge at which the top takes it."""
    before = 0
    while True:
        await RisingEdge(clk)
        now = int(signal.value)
        if now and not before:
            times.append(get_sim_time("step"))
        before = now


def last_bit_decided_ps(rec, hp, slots, phase):
    """The clock edge (ps) at which the core decides the last CRC bit, from the model's edge
    times: the Ack fall reaches SLO at the master's second MA rise + the round trip; the first
    clock edge after it, + 1 (second synchronizer flop) + hp (middle of slot 0) + 2 hp per slot
    + the third vote, v = hp // 2 clocks after the middle (v = 0 at hp = 2; docs/ports.md,
    "Noise immunity"). ``slots``: Ack slots + Start + CDS + data and CRC bits."""
    t_ack_pin = ps(rec.t_first_rise_s) + 2 * hp * PS_PER_CLK + ps(rec.round_trip_s)
    first_edge = ((t_ack_pin - phase) // PS_PER_CLK + 1) * PS_PER_CLK + phase
    vote = hp // 2 if hp >= 3 else 0
    return first_edge + (1 + hp + 2 * hp * (slots - 1) + vote) * PS_PER_CLK


@cocotb.test()
async def bus_trigger_latency(dut):
    tb = BusTestbench(dut, seed=44)
    fmt0 = frames.PRESETS[BUS_LATENCY_PRESETS[0]]
    await tb.start([fmt0])
    chan = tb.channels[0]
    # The protocol's fastest slave: Start on the third MA rise (no processing time beyond it).
    respond = chan.encoder.respond
    chan.encoder.respond = lambda t: dataclasses.replace(respond(t), processing_time_s=0.0)
    axi = {name: getattr(dut, f"s_axil_{name}") for name in
           ("awvalid", "awready", "arvalid", "arready", "rvalid", "rready", "rdata")}
    aw, ar, r, irqs, dones = [], [], [], [], []
    cocotb.start_soon(first_high(dut.clk, axi["awvalid"], aw))
    cocotb.start_soon(handshakes(dut.clk, axi["arvalid"], axi["arready"], ar))
    cocotb.start_soon(handshakes(dut.clk, axi["rvalid"], axi["rready"], r, axi["rdata"]))
    cocotb.start_soon(rises(dut.irq, irqs))
    try:
        # The core's output `done` as the channel sees it (inside the core, Amaranth names it
        # `done$N`; the core's own `done` wire is the decoder's, a clock earlier). The bank
        # gets it later, as `frame_done`, once the cycle's counts are in the counter memory.
        core_done = dut.ch0.done
    except AttributeError:
        core_done = None                            # not visible: verdict and irq reported together
    if core_done is not None:
        cocotb.start_soon(rises(core_done, dones))
    phase = tb.t_clk0 % PS_PER_CLK                  # clock edges: phase + n x T_clk

    await tb.write_fields("irq_enable", 0, done=1)
    await tb.write_fields("ctrl", 0, trigger_enable=1)
    done_mask = tb.map.channel["irq_status"].fields["done"].mask
    rows, failures = [], []
    for name in BUS_LATENCY_PRESETS:
        fmt = frames.PRESETS[name]
        chan.fmt = fmt
        chan.position = lambda t, bits=fmt.words[0].data_bits: tb.rng.getrandbits(bits)
        chan.sign_of_life = frames.SignOfLife()
        chan.source = frames.EncoderFrameSource(fmt, lambda t: chan.position(t),
                                                sign_of_life=chan.sign_of_life)
        for ma_hz in BUS_LATENCY_RATES_HZ:
            hp = round(CLK_HZ / (2 * ma_hz))
            await tb.configure(0, fmt, ma_hz)
            for cable_m in BUS_LATENCY_CABLES_M:
                chan.encoder.set_cable(Cable(length_m=cable_m))
                for source in BUS_LATENCY_TRIGGERS:
                    await tb.wait_idle(0)
                    await tb.encoders_ready()
                    await tb.write("irq_status", done_mask, 0)
                    # The encoder's release of SLO reaches the master one cable delay later;
                    # until then a trigger waits for it (WAIT_READY), which is not latency.
                    # Nor is the quiet time SLO must then be high before MA starts (1 us by
                    # default, docs/ports.md, cfg_quiet_time): a quiet line waits it out.
                    while dut.ch0_slo.value != 1:
                        await RisingEdge(dut.clk)
                    await ClockCycles(dut.clk, round(QUIET_TIME_S * CLK_HZ) + 4)
                    assert dut.irq.value == 0, "irq still high after clearing irq_status"
                    first = len(chan.encoder.records)
                    marks = len(aw), len(ar), len(r), len(irqs), len(dones)
                    if source == "pin":
                        await FallingEdge(dut.clk)
                        dut.trigger.value = 1
                        await RisingEdge(dut.clk)
                        t_trig = get_sim_time("step")       # the edge that takes the trigger
                        await FallingEdge(dut.clk)
                        dut.trigger.value = 0
                    else:
                        await tb.write_fields("trigger", start=1)
                        t_trig = aw[marks[0]]               # AWVALID first sampled high
                    while len(irqs) == marks[3]:
                        await RisingEdge(dut.clk)
                    # The CPU's reads on irq: status (takes the snapshot), the position.
                    reads = len(r)
                    res = await tb.read_fields("result.status", 0)
                    lo = await tb.read("result.w0_lo", 0)
                    hi = await tb.read("result.w0_hi", 0)
                    t_status, t_pos = r[reads][0], r[reads + 2][0]
                    t_ar = next(t for t in ar[marks[1]:] if t >= irqs[marks[3]])
                    for path in ("result.seq", "result.timestamp"):
                        res.update(await tb.read_fields(path, 0))
                    res.update(word0=lo | hi << 32, word1=0)
                    try:
                        tb.check_result(0, res)
                    except AssertionError as e:
                        failures.append(f"{name} {ma_hz:g} Hz {cable_m} m {source}: {e}")
                    rec = chan.encoder.records[first]
                    k = 1 + round((rec.t_start_rise_s - rec.t_first_rise_s) * ma_hz)
                    slots = (k - 2) + 2 + fmt.total_bits    # Ack slots, Start, CDS, D
                    t_decided = last_bit_decided_ps(rec, hp, slots, phase)
                    t_irq = irqs[marks[3]]
                    t_done = dones[marks[4]] if core_done is not None else None
                    clk = lambda a, b: (b - a) / PS_PER_CLK
                    rows.append({
                        "preset": name, "ma_hz": ma_hz, "cable_m": cable_m, "trigger": source,
                        "data_crc_bits": fmt.total_bits, "start_rise": k,
                        "round_trip_s": rec.round_trip_s, "status": res["status"],
                        "start_clk": clk(t_trig, ps(rec.t_first_fall_s)),
                        "frame_clk": clk(ps(rec.t_first_fall_s), t_decided),
                        "verdict_clk": clk(t_decided, t_done) if t_done else None,
                        "irq_clk": clk(t_done, t_irq) if t_done else None,
                        "verdict_irq_clk": clk(t_decided, t_irq),
                        "reaction_clk": clk(t_irq, t_ar),
                        "slave_read_clk": clk(t_ar, t_status),
                        "read_status_clk": clk(t_irq, t_status),
                        "read_position_clk": clk(t_irq, t_pos),
                        "total_status_clk": clk(t_trig, t_status),
                        "total_position_clk": clk(t_trig, t_pos),
                    })
                    dut._log.info("%s", rows[-1])
    out = os.environ.get("BISS_PERF_OUT")
    if out:
        os.makedirs(out, exist_ok=True)
        sim = "icarus" if "icarus" in cocotb.SIM_NAME.lower() else "verilator"
        with open(os.path.join(out, f"bus_trigger_latency-{sim}.json"), "w") as f:
            json.dump({"test": "bus_trigger_latency", "sim": cocotb.SIM_NAME,
                       "sim_version": cocotb.SIM_VERSION, "clk_hz": CLK_HZ, "rows": rows,
                       "checked": len(rows), "failures": failures,
                       "core_done_visible": core_done is not None}, f, indent=1)
