"""Engine of the reliability campaigns (sim/scenarios/campaigns.py): one request cycle at a time,
its outcome predicted by the reference model (sim/shared/reference.py) and compared field by field.

A campaign cycle differs from the regression's (sim/shared/testbench.py) in three ways:

* **fast timing**: the encoder's timeout is short (2 us, like an adaptive-timeout encoder), the
  31.25 us start-to-start rule is off and the master's break is 3 us plus the round trip, so a cycle costs little
  more than its frame: the campaigns run hundreds of thousands of frames;
* **expected results from the reference model**, including the sign-of-life state that frames
  carry from one cycle to the next, and the error counters;
* **line faults**: the outcome of a cycle with a fault on the line is not predictable to the
  bit, so it is checked for what must always hold: the cycle ends (watchdog), with a status the
  fault can cause, never marked valid with a position other than the one sent, and any word
  the core calls CRC-good carries exactly what the encoder sent, unless the received bits are
  a pattern the CRC cannot see (counted separately: the protocol's residual error rate).
"""

import json
import os
import time
from collections import Counter, defaultdict
from pathlib import Path

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, Timer, with_timeout

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import NOISE_STATUSES, STATUS, STATUS_NAME, crc_counters, port_position
from sim.shared.functional_coverage import Coverage
from sim.shared.reference import BREAK_STATUSES, FRAME_STATUS_CODES, MasterReference
from sim.shared.testbench import CLK_HZ, Testbench, preset

#: Scale of every campaign: 1 is the fast slice of `make test`, `make soak` sets more.
SCALE = float(os.environ.get("BISS_CAMPAIGN_SCALE", "1"))
RESULTS = os.environ.get("BISS_CAMPAIGN_RESULTS")       # directory for the JSON results

FAST_TIMEOUT_S = 2e-6           # encoder timeout (adaptive-timeout encoders: ~1.5 MA periods)
FAST_BREAK = 300                # master break in clocks (3 us): longer than the encoder timeout
#: One cycle can never take longer than this (the slowest MA rate, the longest frame, the
#: limits above): the watchdog on every request.
WATCHDOG_S = 2e-3
#: Faults that leave a stuck tail at the end of the frame: the end check (cfg_end_check) catches
#: them, so with it on they must never yield a CRC-good wrong word.
STUCK_LINE_FAULTS = ("slo_stuck_low", "slo_stuck_high")


def scaled(n, minimum=1):
    return max(minimum, round(n * SCALE))


def sliced(n, slice_n, minimum=1):
    """``n`` scaled, except up to scale 1 (the slice of make test and make campaigns), where
    it is ``slice_n`` scaled: a smaller slice, the soak's sizes unchanged."""
    return scaled(slice_n if SCALE <= 1 else n, minimum)


class CampaignFailure(AssertionError):
    pass


class Campaign:
    """One campaign on one simulated core: bench, reference model, coverage and tallies."""

    def __init__(self, dut, name, *, seed):
        self.dut = dut
        self.name = name
        self.tb = Testbench(dut, seed=seed)
        self.rng = self.tb.rng
        self.ref = MasterReference()
        self.cov = Coverage()
        self.tally = defaultdict(Counter)       # per fault kind: outcome -> count
        self.stats = Counter()
        self.recovery = defaultdict(Counter)    # per fault kind: cycles to the next valid frame
        self.preset_name = None
        self.ma_hz = None
        self.cfg = {}
        self.expected_counters = None
        self.counter_max = None
        self.t0 = None

    # -- setup ------------------------------------------------------------------------------
    async def start(self, cable=Cable()):
        await self.tb.start(cable=cable, timeout_s=FAST_TIMEOUT_S)
        enc = self.tb.encoder
        enc.min_cycle_s = 0.0
        self.expected_counters = dict(self.tb.read().counters)
        self.counter_max = (1 << len(self.dut.count_no_ack)) - 1
        self.t0 = time.monotonic()

    async def power_cycle(self):
        """Reset the core, as at power-up on a new cable: what it learned of the line (the
        settled round trip of issue 28's delay check, the last LC) is gone, the counters are 0,
        and it waits out its power-up break. The encoder keeps running."""
        await self.settle()
        dut = self.dut
        dut.rst.value = 1
        await ClockCycles(dut.clk, 3)
        dut.rst.value = 0
        await RisingEdge(dut.clk)
        await self.tb.wait_idle(limit_s=WATCHDOG_S)
        self.expected_counters = dict(self.tb.read().counters)
        self.expect(all(v == 0 for v in self.expected_counters.values()),
                    f"[{self.name}] counters after reset: {self.expected_counters}")
        self.ref.resync()
        self.stats["power_cycles"] += 1

    async def settle(self):
        """Until the line is quiet: the master idle, every MA edge it sent arrived at the
        encoder (a long cable holds many), the encoder ready, and its "ready" back at the
        master. Test bookkeeping (which cycle answered what) needs it; the core does not."""
        await self.tb.wait_idle(limit_s=WATCHDOG_S)
        await Timer(round(self.tb.encoder.cable.round_trip_s() * 1e9) + 100, "ns")
        await self.tb.encoder_ready()
        for _ in range(1000):
            if int(self.dut.slo.value):
                return
            await Timer(100, "ns")

    def line_limits(self, cable=None):
        """Break and Ack limit for a cable: the break must outlast the encoder's timeout plus
        the round trip, or bits still on the line after a fault would look like a ready
        encoder (docs/ports.md, cfg_break_time)."""
        rt = round((cable or self.tb.encoder.cable).round_trip_s() * CLK_HZ)
        slave_timeout = round(self.tb.encoder.timeout_s * CLK_HZ)
        return dict(cfg_break_time=max(FAST_BREAK, slave_timeout + rt + 100),
                    # the processing time is up to 6 MA periods (Campaign.processing)
                    cfg_ack_limit=max(1500, round(7 * CLK_HZ / (self.ma_hz or 1e6))) + rt,
                    cfg_timeout_limit=800 + slave_timeout + rt)

    async def set_cable(self, cable, *, power_up=False):
        """Change the cable between cycles (a cable cannot change length within a frame: the
        master would sample the stop bit on the old delay and start early). ``power_up``: the
        new cable is another installation, not this one's cable changing while powered: the
        round-trip check is re-armed before the next request, as a user does after changing
        the installation (docs/ports.md, "Noise: the line checks"), so that it settles afresh
        instead of reporting DELAY_JUMP (cable_step tests the change while powered)."""
        await self.settle()
        self.tb.encoder.set_cable(cable)
        if power_up:
            self.tb.rearm_delay_check()
        limits = self.line_limits(cable)
        self.cfg.update(limits)
        for name, value in limits.items():
            getattr(self.dut, name).value = value

    def setup(self, name, ma_hz, **cfg):
        """Configure the core and the encoder for a preset (or a FrameFormat) at an MA rate."""
        fmt = name if isinstance(name, frames.FrameFormat) else preset(name)
        self.preset_name = None if isinstance(name, frames.FrameFormat) else name
        self.ma_hz = ma_hz
        hp = cfg.pop("half_period", None)
        rate = ma_hz if hp is None else CLK_HZ / (2 * hp)
        self.ma_hz = rate
        # An adaptive-timeout encoder: about 1.5 MA periods, at least 2 us here.
        self.tb.encoder.timeout_s = max(FAST_TIMEOUT_S, 1.5 / rate)
        self.cfg = {**self.line_limits(), **cfg}
        self.ref.confirm_setting = self.cfg.get("cfg_confirm_frames", 0)
        self.tb.configure(fmt, ma_hz, half_period=hp, **self.cfg)
        if hp is not None:
            self.ma_hz = CLK_HZ / (2 * hp)
        return fmt

    @property
    def end_check(self):
        return bool(self.cfg.get("cfg_end_check", 0))

    @property
    def fmt(self):
        return self.tb.fmt

    def spw_opts(self):
        two = len(self.fmt.words) == 2
        return dict(spw_check=bool(self.cfg.get("cfg_spw_check", two)),
                    spw_tolerance=self.cfg.get("spw_tolerance", 1))

    def processing(self):
        """Processing time of the next frame: at least 2 MA periods (protocol), here short."""
        return self.rng.uniform(2, 6) / self.ma_hz

    def queue(self, **kw):
        """Plan the next cycle's answer; a plan left over from a cycle that never reached the
        encoder (a stuck line, a bad configuration) is dropped first."""
        self.tb.plan.clear()
        self.tb.queue(**kw)

    # -- one cycle ----------------------------------------------------------------------------
    async def frame(self, fault="none", *, faults=None, values=None, lc=None, record_cov=True,
                    **response):
        """One request with a clean line: everything must be exactly as the reference says."""
        response.setdefault("processing_time_s", self.processing())
        self.queue(values=values, faults=faults, lc=lc, **response)
        n_sent, n_rec = len(self.tb.sent), len(self.tb.encoder.records)
        res = await self.tb.request(limit_s=WATCHDOG_S)
        self.expect(len(self.tb.sent) == n_sent + 1,
                    f"{self.where(fault)}: the encoder answered {len(self.tb.sent) - n_sent} "
                    f"times, {len(self.tb.encoder.records) - n_rec} new cycles, status "
                    f"{STATUS_NAME[res.status]}, last records {self.tb.encoder.records[-3:]}")
        sent = self.tb.sent[-1]
        record = self.tb.encoder.records[-1]
        verdict = self.ref.judge(self.fmt, sent.bits, **self.spw_opts())
        self.check_verdict(res, verdict, record, fault)
        self.count_outcome(res)
        if record_cov:
            self.note(fault, res, record.round_trip_s)
        return res, verdict

    def check_verdict(self, res, v, record, fault):
        where = self.where(fault)
        f = res.fields
        self.expect(res.status == v.status,
                    f"{where}: status {STATUS_NAME[res.status]}, expected {v.name}")
        self.expect(res.valid == int(v.status == STATUS["OK"]), f"{where}: valid {res.valid}")
        for w, word in enumerate(v.parsed["words"]):
            self.expect(f[f"word{w}_crc_ok"] == int(word["crc_ok"]), f"{where}: word{w} crc_ok")
            want = port_position(self.fmt.words[w], word["position"],
                                 len(getattr(self.dut, f"word{w}_position")))
            self.expect(f[f"word{w}_position"] == want,
                        f"{where}: word{w} position {f[f'word{w}_position']:#x} "
                        f"!= {want:#x}")
            if self.fmt.words[w].nenw:
                self.expect((f[f"word{w}_ne"], f[f"word{w}_nw"]) == (word["ne"], word["nw"]),
                            f"{where}: word{w} nE/nW")
            if self.fmt.words[w].lc:
                self.expect(f["lc"] == word["lc"], f"{where}: lc {f['lc']} != {word['lc']}")
        for flag in ("lc_repeat", "lc_skip", "lc_zero"):
            self.expect(f[flag] == getattr(v, flag),
                        f"{where}: {flag} {f[flag]}, expected {getattr(v, flag)}")
        if "spw_mismatch" in f and len(self.fmt.words) == 2:
            self.expect(f["spw_mismatch"] == v.spw_mismatch, f"{where}: spw_mismatch")
        self.check_delay(res, record, where)

    def where(self, fault):
        cable = self.tb.encoder.cable
        return (f"[{self.name}/{fault} cycle {self.stats['cycles']}] "
                f"{self.preset_name or self.fmt} at {self.ma_hz / 1e6:g} MHz, round trip "
                f"{cable.round_trip_s() * 1e9:.1f} ns, cfg {self.cfg}")

    def check_delay(self, res, record, where):
        rt = record.round_trip_s * CLK_HZ
        d = res.fields["line_delay"]
        self.expect(rt - 1e-6 <= d < rt + 1 + 1e-6,
                    f"{where}: line delay {d} clocks, true round trip {rt:.3f}")
        self.stats["delay_checked"] += 1
        self.stats["delay_err_max_x1000"] = max(self.stats["delay_err_max_x1000"],
                                                round((d - rt) * 1000))

    def expect(self, cond, message):
        if not cond:
            raise CampaignFailure(message)

    # -- counters -----------------------------------------------------------------------------
    def count_outcome(self, res, *, frame=True):
        """Advance the expected counters by what this result must have counted; compare."""
        f, c = res.fields, self.expected_counters
        name = STATUS_NAME[res.status]

        def inc(counter):
            if counter in c:
                c[counter] = min(c[counter] + 1, self.counter_max)

        if res.status in FRAME_STATUS_CODES and frame:
            words = len(self.fmt.words)
            for counter in crc_counters([f[f"word{w}_crc_ok"] for w in range(words)]):
                inc(counter)
            for flag in ("lc_repeat", "lc_skip", "lc_zero"):
                if f[flag]:
                    inc(flag)
            if words == 2 and f.get("spw_mismatch"):
                inc("spw_mismatch")
        for status, counter in (("NO_ACK", "no_ack"), ("NO_START", "no_start"),
                                ("DELAY_RANGE", "delay_range"), ("SLO_STUCK_LOW", "slo_stuck_low"),
                                ("ABORTED", "aborted"), ("NO_STOP", "no_stop"),
                                ("NOISY_LINE", "noisy_line"), ("DELAY_JUMP", "delay_jump")):
            if name == status:
                inc(counter)
        got = dict(res.counters)
        if "noise_event" in c:
            # Noise events seen: a saturating count that never goes back (its step per cycle
            # is the RTL's to document; the cycle's own figure is the noise_events field).
            self.expect(got["noise_event"] >= c["noise_event"],
                        f"[{self.name}] count_noise_event went back: {got['noise_event']} < "
                        f"{c['noise_event']}")
            c["noise_event"] = got["noise_event"]
        self.expect(got == c, f"[{self.name}] counters {got} != expected {c}")
        self.ref.after_status(res.status)

    def note(self, fault, res, round_trip_s, outcome=None):
        self.cov.sample(preset=self.preset_name, ma_hz=self.ma_hz, round_trip_s=round_trip_s,
                        fault=fault, status=res.status)
        self.tally[fault][outcome or STATUS_NAME[res.status]] += 1
        self.stats["cycles"] += 1

    # -- faulted cycles -------------------------------------------------------------------------
    def judge_faulted(self, res, fault, allowed, explain=None):
        """A cycle with a line fault: status allowed, no false valid, CRC-good words exact.

        ``explain(bits_sent)`` yields candidate received bit lists for the fault (e.g. every
        tail of a stuck line): a CRC-good word that differs from what was sent is accepted only
        if one candidate passes every CRC and reproduces the reported fields; it is then counted
        as undetected by the CRC (the protocol's residual error), never silently.
        """
        where = self.where(fault)
        name = STATUS_NAME[res.status]
        self.expect(name in allowed, f"{where}: status {name}, allowed {allowed}")
        outcome = name
        if res.status in FRAME_STATUS_CODES:
            sent = self.tb.sent[-1]
            v = self.ref.judge(self.fmt, sent.bits, commit=False, **self.spw_opts())
            f = res.fields
            wrong = [w for w, word in enumerate(v.parsed["words"])
                     if f[f"word{w}_crc_ok"] and not self._word_matches(f, w, word)]
            if wrong:
                # With the end check a stuck tail never gets this far (NO_STOP or
                # SLO_STUCK_LOW instead): for a stuck line any wrong CRC-good word is then a
                # defect. A glitch or jitter changes bits inside the frame and leaves its end
                # intact, which the end check cannot see: those stay CRC blind spots.
                self.expect(not (self.end_check and fault in STUCK_LINE_FAULTS),
                            f"{where}: end check on, yet CRC-good word(s) {wrong} differ from "
                            f"what was sent: status {name}, fields {f}, sent {sent.bits}")
                cand = self._explained(f, sent.bits, explain)
                self.expect(cand is not None,
                            f"{where}: CRC-good word(s) {wrong} differ from what was sent, and "
                            f"no {fault} pattern explains it: status {name}, fields {f}, "
                            f"sent {sent.bits}")
                outcome = f"{name} (CRC blind spot)"
                self.stats[f"crc_blind_spot_{fault}, end check "
                           f"{'on' if self.end_check else 'off'}"] += 1
                v = self.ref.judge(self.fmt, cand, **self.spw_opts())
            else:
                # The core judged the words it received; the LC state follows the LC word only
                # if the core found that word's CRC good (then it is exactly what was sent).
                rtl_ok = tuple(bool(f[f"word{w}_crc_ok"]) for w in range(len(self.fmt.words)))
                v = self.ref.judge(self.fmt, sent.bits, received_ok=rtl_ok, **self.spw_opts())
                if name in NOISE_STATUSES and v.name in ("OK", "UNCONFIRMED") and fault != "jitter":
                    # The protocol's checks pass; on a glitched or stuck line the core's line
                    # checks may still reject the frame (docs/ports.md, "Noise: the line
                    # checks"): safe, and counted. Jitter within the protocol's limit is a
                    # clean line: never (no_false_alarm proves it at scale).
                    self.stats[f"line_check_{name}_{fault}"] += 1
                else:
                    self.expect(res.status == v.status,
                                f"{where}: status {name}, expected {v.name} for crc_ok {rtl_ok}, "
                                f"fields {f}")
            for flag in ("lc_repeat", "lc_skip", "lc_zero"):
                self.expect(f[flag] == getattr(v, flag), f"{where}: {flag}")
            self.expect(res.valid == int(res.status == STATUS["OK"]), f"{where}: valid")
        else:
            self.expect(res.valid == 0, f"{where}: valid with status {name}")
        self.count_outcome(res)
        return outcome

    def _word_matches(self, f, w, word):
        ok = f[f"word{w}_position"] == word["position"]
        if self.fmt.words[w].nenw:
            ok &= (f[f"word{w}_ne"], f[f"word{w}_nw"]) == (word["ne"], word["nw"])
        if self.fmt.words[w].lc:
            ok &= f["lc"] == word["lc"]
        return ok

    def _explained(self, f, sent_bits, explain):
        for bits in (explain(sent_bits) if explain else ()):
            parsed = frames.parse_frame(self.fmt, bits)
            words = parsed["words"]
            if all(not f[f"word{w}_crc_ok"] or (word["crc_ok"] and self._word_matches(f, w, word))
                   for w, word in enumerate(words)):
                return bits
        return None

    async def recover(self, fault, limit=4):
        """Good frames after a fault until one is valid; tallies how many cycles that took."""
        for n in range(1, limit + 1):
            res, v = await self.frame("none", record_cov=False)
            if res.valid:
                self.recovery[fault][n] += 1
                return n
        raise CampaignFailure(f"[{self.name}/{fault}] no valid frame {limit} cycles after")

    # -- results ------------------------------------------------------------------------------
    def save(self, extra=None):
        wall = time.monotonic() - self.t0
        out = {
            "campaign": self.name,
            "cycles": self.stats["cycles"],
            "wall_s": wall,
            "cycles_per_s": self.stats["cycles"] / wall if wall else 0,
            "tally": {k: dict(v) for k, v in self.tally.items()},
            "recovery": {k: {str(n): c for n, c in v.items()} for k, v in self.recovery.items()},
            "stats": dict(self.stats),
            **(extra or {}),
        }
        self.dut._log.info("%s: %d cycles in %.1f s (%.0f/s)", self.name, out["cycles"], wall,
                           out["cycles_per_s"])
        for k, v in sorted(out["tally"].items()):
            self.dut._log.info("  %-14s %s", k, v)
        if RESULTS:
            d = Path(RESULTS)
            d.mkdir(parents=True, exist_ok=True)
            sim = cocotb.SIM_NAME.lower().split()[0] if cocotb.SIM_NAME else "sim"
            (d / f"{self.name}-{sim}.json").write_text(json.dumps(out, indent=1))
            self.cov.save(d / f"{self.name}-{sim}.cov.json")
        return out
