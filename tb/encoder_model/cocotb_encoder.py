"""cocotb model of a BiSS encoder (RESOLUTE / EVOLUTE / FORTiS style) plus the cable to it.

The model follows the master's MA pin and drives the master's SLO pin, as a real encoder at the
end of a cable would (docs/protocol.md sections 2, 3, 4 and 9):

* MA edges reach the encoder ``Cable.m2e_s()`` later (plus per-edge jitter);
* the encoder reacts in *encoder time* (Ack on the 2nd rising edge, Start on the first rising
  edge at or after the processing time, one bit per rising edge, stop bit, timeout);
* every SLO change reaches the master ``ENCODER_INTERNAL_DELAY_S + Cable.e2m_s()`` later (plus
  per-edge jitter).

It shares no logic with the RTL and does not build frames itself: the bits of every cycle come
from the ``respond`` callback (for instance ``encoder_model.frames``).

Implementation: both delay lines and the encoder's own timers are events on a single
time-ordered queue (integer simulator steps, FIFO among equal times), worked through by short
wake-up tasks, one per distinct wake-up time. MA edges are timestamped by a monitor coroutine when they happen at the master pin and
queued for their arrival time at the encoder, so any number of edges can be "in flight" on the
cable (a round trip of many MA periods). Jitter is drawn per edge and direction; the arrival
times are clamped so that edges never overtake each other (and never arrive before they left).
Every delay is rounded to the simulator precision (1 ps with timescale 1ns/1ps).

One cycle, in encoder time:

1. Ready (SLO high): the first MA falling edge starts a cycle and appends a ``CycleRecord``.
2. 1st rising edge: the sampling moment is this edge + ``SAMPLING_MOMENT_S``;
   ``respond(t_latch_s)`` is called (once per cycle) and returns the ``Response``.
3. 2nd rising edge: SLO low (Ack).
4. The first rising edge k >= 3 with t_k - t_1 >= ``processing_time_s`` (measured at the
   encoder) puts Start (``bits[0]``) on SLO; every further rising edge the next bit; the rising
   edge after the last bit drives SLO low (stop bit / timeout); further edges keep it low.
5. The cycle ends when MA has not changed for ``timeout_s`` (normally MA high after the clock
   stopped; MA held low is BiSS C's CDM = 1 and is recorded as ``cdm = 1``). SLO returns high
   (ready) at max(last MA edge + timeout_s, first fall + min_cycle_s) (31.25 us start-to-start).
   MA falling edges before that are not a new cycle: they are noted in ``ignored_falls``.
6. If the cycle ends before all bits and the stop bit went out, it was an abort (encoder reset):
   ``aborted = True``; SLO keeps its last level until it returns high as in 5. A master that
   stops right after the last data bit, without the stop-bit rising edge, counts as aborted.

Faults (``Response.fault``):

* ``"no_response"``: the encoder ignores MA, SLO stays high; it is ready again as soon as MA
  has been quiet for timeout_s (no 31.25 us rule, nothing was acquired).
* ``"stuck_low"``: SLO forced low from the 1st rising edge of this cycle (where ``respond``
  is called; half an MA period after the cycle's first fall) until ``clear_fault()``. Until
  then the encoder is dead: MA falls are ignored (noted), no new cycles, no ``respond`` calls.
* ``"stuck_high"``: SLO stays high from the 2nd rising edge (no Ack, no frame); the encoder
  still runs the cycle and its timeout (31.25 us rule) internally.
* ``"timeout_stuck"``: the frame is sent normally, then SLO never returns high; the encoder is
  dead until ``clear_fault()`` as for stuck_low.
* ``"ack_forever"``: Ack never ends (no Start); when the master gives up and holds MA high the
  cycle ends as an abort (``aborted = True``) and SLO returns high as in 5.

``force_slo(level)`` overrides the line at the master pin (broken / unplugged cable) on top of
all that; ``force_slo(None)`` gives the pin back to the cable.

Control channel (BiSS C CDM/CDS, docs/protocol.md, section 10), only with ``control=ControlSlave(...)``
(``encoder_model.control``): the CDS slot of every frame (``bits[1]`` of the Response) is
replaced by ``control.cds`` when ``respond`` is called, and at the end of every cycle (step 5)
the encoder steps the control slave with that cycle's ``cdm`` (the inverted MA level when the
timeout ran out), which sets the CDS of the next frame. Cycles that ended without the encoder's
logic seeing them (``no_response``, ``stuck_low``, ``timeout_stuck``) do not step it; aborted
cycles do. MA held low at the end of the timeout does not start a cycle: SLO returns high as in
5 and the next cycle starts on the first MA fall after that (MA must rise first). Without a
control slave nothing changes: CDS is whatever ``respond`` put in ``bits[1]``.

``invert_slo(True)`` inverts the line at the master pin (noise coupled into the cable near the
master: whatever the encoder sends, and any edge it makes meanwhile, arrives inverted) until
``invert_slo(False)``; ``await glitch_slo(width_s)`` is one such glitch, from now for
``width_s``. A force wins over an inversion.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import math
import random
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Callable

import cocotb
from cocotb.simtime import convert, get_sim_time
from cocotb.triggers import Timer

import protocol_facts as facts

if TYPE_CHECKING:
    from .control import ControlSlave

FAULTS = (None, "no_response", "stuck_low", "stuck_high", "timeout_stuck", "ack_forever")
# Faults whose cycles the encoder's logic does not live through: no CDM sampled after them.
_NO_CONTROL_STEP = ("no_response", "stuck_low", "timeout_stuck")
CDS_INDEX = 1                           # Response.bits: [Start, CDS, data...]


@dataclass
class Cable:
    """The line between master and encoder (both directions, plus transceivers)."""
    length_m: float = 0.0
    extra_round_trip_s: float = 0.0     # e.g. transceivers; split half/half
    jitter_s: float = 0.0               # peak, uniform +/- per edge on each direction

    def _one_way_s(self) -> float:
        return (self.length_m * facts.CABLE_ROUND_TRIP_S_PER_M + self.extra_round_trip_s) / 2

    def m2e_s(self) -> float:
        """Master -> encoder delay (MA)."""
        return self._one_way_s()

    def e2m_s(self) -> float:
        """Encoder -> master delay (SLO), without the encoder's internal delay."""
        return self._one_way_s()

    def round_trip_s(self) -> float:
        """The true round trip a master measures (2nd MA rise to Ack fall), without jitter."""
        return self.m2e_s() + self.e2m_s() + facts.ENCODER_INTERNAL_DELAY_S


@dataclass
class Response:
    """What the encoder sends in one cycle."""
    bits: list[int]                     # [Start=1, CDS, data...] as sent after Ack, MSB first
    processing_time_s: float = 5e-6     # Start goes out on the first MA rise (3rd or later)
                                        # at or after t_first_rise + processing_time
    fault: str | None = None            # see FAULTS and the module doc


@dataclass
class CycleRecord:
    """One request cycle as the encoder saw it (appended at the cycle's first MA fall and
    completed while the cycle runs; ``ended`` tells when it is final)."""
    t_first_fall_s: float               # master-pin time of the first MA falling edge
    t_first_rise_s: float = math.nan    # master-pin time of the first MA rising edge
    t_latch_s: float = math.nan         # encoder time of the sampling moment
    ma_rises: int = 0                   # MA rising edges the encoder saw in this cycle
    bits_sent: list[int] = field(default_factory=list)   # bits put on SLO (no Ack, no stop bit)
    round_trip_s: float = math.nan      # master-pin 2nd MA rise -> Ack fall at the master pin
                                        # (as realised, incl. jitter); nominal if no Ack was sent
    aborted: bool = False               # MA stopped before all bits and the stop bit were sent
    # -- extras (not in the original brief) --
    fault: str | None = None            # Response.fault of this cycle
    t_start_rise_s: float = math.nan    # master-pin time of the MA rise that launched Start
    t_end_s: float = math.nan           # encoder time the cycle ended (MA quiet for timeout_s)
    t_ready_s: float = math.nan         # encoder time SLO was released high again (nan: stuck)
    t_last_bit_s: float = math.nan      # master-pin time the frame's last bit begins to arrive
                                        # (nominal: without jitter; nan: not sent)
    cdm: int = 0                        # 1 if the cycle ended with MA held low (BiSS C CDM)
    ended: bool = False
    cds: int | None = None              # CDS the control slave put in this frame (None: no
                                        # control slave, or respond() was not called)


class _Cycle:
    """Encoder-internal state of the running cycle (all times in simulator steps)."""

    def __init__(self, te_first_fall: int, record: CycleRecord):
        self.te_first_fall = te_first_fall
        self.te_first_rise = 0
        self.record = record
        self.rises = 0
        self.resp: Response | None = None
        self.fault: str | None = None
        self.fault_active = True        # cleared by BissEncoder.clear_fault()
        self.phase = "wait_ack"         # wait_ack | ack | data | stop | silent
        self.index = 0                  # next bit of resp.bits to send
        self.done = False               # all bits and the stop bit sent
        self.proc_steps = 0
        self.tm_second_rise: int | None = None


class SimSteps:
    """Time helpers of the cocotb encoder models (``BissEncoder``, cocotb_ssi.SsiLineEncoder):
    times in integer simulator steps, rounded to the nearest step; ``_jitter`` draws one value
    from ``self.rng`` per call, uniform in +-``self.cable.jitter_s`` (no draw when that is 0),
    so a seeded ``rng`` gives the same edges whichever model uses it."""

    cable: Cable
    rng: random.Random

    @staticmethod
    def _steps(seconds: float) -> int:
        return convert(seconds, "sec", to="step", round_mode="round")

    @staticmethod
    def _sec(steps: int) -> float:
        return convert(steps, "step", to="sec")

    @staticmethod
    def _now() -> int:
        return get_sim_time("step")

    def _jitter(self) -> float:
        j = self.cable.jitter_s
        return self.rng.uniform(-j, j) if j > 0 else 0.0


class BissEncoder(SimSteps):
    """BiSS encoder + cable model. See the module doc string."""

    def __init__(self, ma, slo, *, cable: Cable, respond: Callable[[float], Response],
                 timeout_s: float = 12.5e-6, min_cycle_s: float = facts.MIN_CYCLE_PERIOD_S,
                 rng: random.Random | None = None, log: logging.Logger | None = None,
                 control: ControlSlave | None = None):
        self.ma = ma
        self.slo = slo
        self.cable = cable
        self.respond = respond
        self.timeout_s = timeout_s
        self.min_cycle_s = min_cycle_s
        self.rng = rng if rng is not None else random.Random(0)
        self.control = control          # BiSS C control side (module doc); None: CDS as sent
        self.log = log if log is not None else logging.getLogger("cocotb.encoder_model")
        # Optional event trace for debugging / self-checks: set to a list to collect
        # ("ma", t_master_steps, t_encoder_steps, level) and
        # ("slo", t_encoder_steps, t_master_steps, level) tuples.
        self.trace: list[tuple] | None = None
        self.records: list[CycleRecord] = []
        # master-pin times of MA falling edges that did not start a cycle (encoder in its
        # timeout / stuck): a master clocking too early shows up here
        self.ignored_falls: list[float] = []
        self._queue: list[tuple[int, int, Callable, tuple]] = []
        self._seq = itertools.count()
        self._armed: set[int] = set()    # times of pending wake-up tasks
        self._timeout_deadline = 0      # encoder time the MA-quiet timeout runs out
        self._timeout_pending = False
        self._tasks: list = []
        self._running = False
        # master side
        self._ma_master_level: int | None = None
        self._slo_line = 1              # level that arrived at the master over the cable
        self._force: int | None = None  # force_slo()
        self._invert = 0                # invert_slo(): 1 while the pin shows the inverted line
        self._slo_pin: int | None = None
        self._last_ma_arrival = -1      # encoder time of the last MA edge (order clamp)
        self._last_slo_arrival = -1     # master time of the last SLO change (order clamp)
        # encoder side
        self._ma_level = 1
        self._edge_count = 0
        self._state = "ready"           # ready | cycle | recover | stuck
        self._cycle: _Cycle | None = None
        self._enc_out = 1               # level the encoder logic drives
        self._override: int | None = None   # encoder-side fault level (stuck_* faults)
        self._out_sent = 1              # last level launched onto the cable

    # -- public API -------------------------------------------------------------------------
    def start(self) -> None:
        if self._running:
            return
        self._running = True
        try:
            lvl = int(self.ma.value)
        except ValueError:
            lvl = 1
        self._ma_master_level = lvl
        self._ma_level = lvl
        self._drive_pin()
        self._tasks = [cocotb.start_soon(self._ma_monitor())]

    def stop(self) -> None:
        self._running = False
        for task in self._tasks:
            if not task.done():
                task.cancel()
        self._tasks = []
        self._queue.clear()
        self._armed.clear()

    def force_slo(self, level: int | None) -> None:
        """Override the SLO level at the master pin (None releases to the cable's level)."""
        self._force = None if level is None else int(level)
        self._drive_pin()

    def invert_slo(self, on: bool) -> None:
        """Invert the SLO level at the master pin (a glitch) while ``on``; edges the cable
        brings meanwhile arrive inverted too."""
        self._invert = int(bool(on))
        self._drive_pin()

    async def glitch_slo(self, width_s: float) -> None:
        """One glitch: the SLO pin inverted from now for ``width_s`` (at least one step)."""
        self.invert_slo(True)
        await Timer(max(1, self._steps(width_s)), "step")
        self.invert_slo(False)

    def set_cable(self, cable: Cable) -> None:
        """Change the cable (applies to edges that happen from now on)."""
        self.cable = cable

    def clear_fault(self) -> None:
        """Repair a latched fault (stuck_low, timeout_stuck): the encoder becomes ready again
        (at once if it is not inside a cycle, else when that cycle ends)."""
        self._override = None
        if self._cycle is not None:
            self._cycle.fault_active = False
        if self._state == "stuck":
            self._go_ready()
        self._update_output()

    @property
    def phase(self) -> str | None:
        """The running cycle's phase (wait_ack, ack, data, stop, silent), None between cycles."""
        return None if self._cycle is None else self._cycle.phase

    @property
    def ready(self) -> bool:
        """True when the encoder would start a cycle on the next MA falling edge."""
        return self._state == "ready"

    # -- event queue ------------------------------------------------------------------------
    def _push(self, t: int, fn: Callable, *args) -> None:
        heapq.heappush(self._queue, (t, next(self._seq), fn, args))
        self._ensure_waker()

    def _run_due(self) -> None:
        now = self._now()
        while self._queue and self._queue[0][0] <= now:
            _, _, fn, args = heapq.heappop(self._queue)
            fn(*args)

    def _ensure_waker(self) -> None:
        # One Timer task per wake-up time, armed only when no earlier one is pending: cheaper
        # than a long-lived scheduler waiting on First(Timer, Event), which costs two tasks
        # and a cancellation per event.
        if not self._queue or not self._running:
            return
        t = self._queue[0][0]
        if any(w <= t for w in self._armed):
            return
        self._armed.add(t)
        cocotb.start_soon(self._waker(t))

    async def _waker(self, t: int) -> None:
        now = self._now()
        if t > now:
            await Timer(t - now, "step")
        self._armed.discard(t)
        if self._running:
            self._run_due()
            self._ensure_waker()

    # -- master -> encoder (MA) -------------------------------------------------------------
    async def _ma_monitor(self) -> None:
        while True:
            await self.ma.value_change
            try:
                lvl = int(self.ma.value)
            except ValueError:
                continue                # X/Z: not an edge
            if lvl == self._ma_master_level:
                continue
            self._ma_master_level = lvl
            tm = self._now()
            te = tm + self._steps(self.cable.m2e_s() + self._jitter())
            te = max(te, tm, self._last_ma_arrival)
            self._last_ma_arrival = te
            if self.trace is not None:
                self.trace.append(("ma", tm, te, lvl))
            self._push(te, self._on_ma_edge, lvl, tm)
            if te == tm:
                self._run_due()

    # -- encoder -> master (SLO) ------------------------------------------------------------
    def _pin_delay_s(self) -> float:
        """From the encoder's output to the master pin, without jitter."""
        return facts.ENCODER_INTERNAL_DELAY_S + self.cable.e2m_s()

    def _update_output(self) -> None:
        lvl = self._override if self._override is not None else self._enc_out
        if lvl == self._out_sent:
            return
        self._out_sent = lvl
        now = self._now()
        tm = now + self._steps(self._pin_delay_s() + self._jitter())
        tm = max(tm, now, self._last_slo_arrival)
        self._last_slo_arrival = tm
        if self.trace is not None:
            self.trace.append(("slo", now, tm, lvl))
        cyc = self._cycle
        if (cyc is not None and lvl == facts.ACK_LEVEL and cyc.phase == "ack"
                and cyc.tm_second_rise is not None and math.isnan(cyc.record.round_trip_s)):
            cyc.record.round_trip_s = self._sec(tm - cyc.tm_second_rise)
        # (a zero delay is picked up by the running _run_due loop or, from outside it, by
        # a wake-up task started in this same time step: no re-entrant processing)
        self._push(tm, self._on_slo_arrival, lvl)

    def _on_slo_arrival(self, lvl: int) -> None:
        self._slo_line = lvl
        self._drive_pin()

    def _drive_pin(self) -> None:
        lvl = self._force if self._force is not None else self._slo_line ^ self._invert
        if lvl != self._slo_pin:
            self._slo_pin = lvl
            self.slo.value = lvl

    # -- encoder logic (runs in encoder time) -----------------------------------------------
    def _on_ma_edge(self, lvl: int, tm: int) -> None:
        self._ma_level = lvl
        self._edge_count += 1
        te = self._now()
        if lvl == 0:
            if self._state == "ready":
                rec = CycleRecord(t_first_fall_s=self._sec(tm))
                self.records.append(rec)
                self._cycle = _Cycle(te, rec)
                self._state = "cycle"
                self._arm_timeout(te)
            elif self._state == "cycle":
                self._arm_timeout(te)
            else:
                self.ignored_falls.append(self._sec(tm))
                self.log.info("encoder model: MA fall at %.3f us ignored (encoder %s)",
                              self._sec(tm) * 1e6, self._state)
            return
        if self._state != "cycle":
            return
        self._arm_timeout(te)
        self._on_rise(te, tm)

    def _on_rise(self, te: int, tm: int) -> None:
        cyc = self._cycle
        rec = cyc.record
        cyc.rises += 1
        rec.ma_rises = cyc.rises
        if cyc.rises == 1:
            cyc.te_first_rise = te
            rec.t_first_rise_s = self._sec(tm)
            rec.t_latch_s = self._sec(te) + facts.SAMPLING_MOMENT_S
            resp = self.respond(rec.t_latch_s)
            if resp.fault not in FAULTS:
                raise ValueError(f"unknown fault {resp.fault!r}")
            if self.control is not None and len(resp.bits) > CDS_INDEX:
                bits = list(resp.bits)
                bits[CDS_INDEX] = rec.cds = self.control.cds
                resp = replace(resp, bits=bits)
            cyc.resp = resp
            cyc.fault = rec.fault = resp.fault
            cyc.proc_steps = self._steps(resp.processing_time_s)
            if resp.fault == "stuck_low":
                self._override = 0
                self._update_output()
                cyc.phase = "silent"
            elif resp.fault == "no_response":
                cyc.phase = "silent"
            return
        if cyc.phase == "silent":
            return
        if cyc.rises == 2:
            cyc.tm_second_rise = tm
            if cyc.fault == "stuck_high":
                self._override = 1
                self._update_output()
                cyc.phase = "silent"
                return
            cyc.phase = "ack"
            self._enc_out = facts.ACK_LEVEL
            self._update_output()
            return
        if cyc.phase == "ack":
            if cyc.fault == "ack_forever" or te - cyc.te_first_rise < cyc.proc_steps:
                return
            rec.t_start_rise_s = self._sec(tm)
            cyc.phase = "data"
        if cyc.phase == "data":
            bits = cyc.resp.bits
            if cyc.index < len(bits):
                bit = int(bits[cyc.index])
                cyc.index += 1
                rec.bits_sent.append(bit)
                if cyc.index == len(bits):
                    rec.t_last_bit_s = self._sec(self._now()) + self._pin_delay_s()
                self._enc_out = bit
            else:
                self._enc_out = 0       # stop bit / start of the timeout
                cyc.phase = "stop"
                cyc.done = True
            self._update_output()
        # phase "stop": further rises keep SLO low

    def _arm_timeout(self, te: int) -> None:
        """MA changed at encoder time ``te``: the cycle ends when MA stays quiet for timeout_s.
        One pending timer event, moved on as edges come (not one event per edge)."""
        self._timeout_deadline = te + self._steps(self.timeout_s)
        if not self._timeout_pending:
            self._timeout_pending = True
            self._push(self._timeout_deadline, self._on_timeout_timer)

    def _on_timeout_timer(self) -> None:
        if self._now() < self._timeout_deadline:
            self._push(self._timeout_deadline, self._on_timeout_timer)
            return
        self._timeout_pending = False
        self._on_timeout_check(self._edge_count)

    def _on_timeout_check(self, edge_count: int) -> None:
        # MA has not changed for timeout_s: the cycle ends. Normally MA is high (the master
        # stopped the clock); MA held low is BiSS C's CDM = 1, recorded as such.
        if self._state != "cycle" or edge_count != self._edge_count:
            return
        cyc = self._cycle
        rec = cyc.record
        te = self._now()
        rec.t_end_s = self._sec(te)
        rec.cdm = 1 - self._ma_level
        rec.ended = True
        if self.control is not None and cyc.fault not in _NO_CONTROL_STEP:
            self.control.step(rec.cdm)      # sampled now: answered in the next frame's CDS
        rec.aborted = cyc.fault not in ("no_response", "stuck_low", "stuck_high") and not cyc.done
        if math.isnan(rec.round_trip_s):
            rec.round_trip_s = self._sec(self._steps(self.cable.m2e_s())
                                         + self._steps(facts.ENCODER_INTERNAL_DELAY_S
                                                       + self.cable.e2m_s()))
        if cyc.fault_active and cyc.fault in ("stuck_low", "timeout_stuck"):
            self._override = 0
            self._update_output()
            self._state = "stuck"
            self._cycle = None
            return
        if cyc.fault == "no_response":
            t_ready = te                # the encoder ignored the cycle: no acquisition
        else:
            t_ready = max(te, cyc.te_first_fall + self._steps(self.min_cycle_s))
        self._state = "recover"
        self._push(t_ready, self._go_ready)

    def _go_ready(self) -> None:
        if self._state == "ready":
            return
        if self._cycle is not None:
            self._cycle.record.t_ready_s = self._sec(self._now())
        self._cycle = None
        self._state = "ready"
        self._override = None
        self._enc_out = 1
        self._update_output()
