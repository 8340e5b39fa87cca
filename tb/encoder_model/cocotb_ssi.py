"""cocotb model of an SSI encoder plus the cable to it (docs/frames_research.md, section 2).

The encoder follows the master's MA pin and drives the master's SLO pin, as ``BissEncoder``
(cocotb_encoder.py) does for BiSS, with the same cable (``Cable``) and delays:

* MA edges reach the encoder ``Cable.m2e_s()`` later (plus per-edge jitter);
* the encoder reacts in *encoder time* (:class:`SsiLineLogic`, pure Python);
* every SLO change reaches the master ``ENCODER_INTERNAL_DELAY_S + Cable.e2m_s()`` later (plus
  per-edge jitter). The round trip a master must allow for, MA rising edge at its pin to the
  resulting SLO change at its pin, is ``Cable.round_trip_s()``.

The levels come from the pure model, encoder_model.ssi (``ssi_bits`` for the word,
``level_after`` for what follows it: zeros or, ``repeat="ring"``, the word again after one 0):

1. A falling edge that finds the monoflop run out (line high, or no train yet) latches:
   ``position_at(t)``, ``errors_at(t)``, ``nenw_at(t)`` at that encoder time, and appends an
   :class:`SsiRecord`. A falling edge within tm latches nothing (the shift goes on: model
   choice 4 of ssi.py); ``repeat="same_value"`` needs train boundaries, which are no event on
   the pins: refused.
2. Every falling edge retriggers tm (``retrigger="any"``: every edge).
3. Rising edge k (1, 2, ...) since the latch puts ``level_after(fmt, word, k - 1)`` on the line.
4. tm after the last retriggering edge the line goes high (ready).

Faults: :meth:`SsiLineEncoder.force_slo` overrides the line at the master pin (unplugged
encoder: fail-safe receiver high, or shorted low); :meth:`SsiLineEncoder.queue` plans
:class:`SsiFaults` for the next latches (a flipped bit in every copy or in the second copy of a
ring, the bit after the first copy forced).
"""

from __future__ import annotations

import heapq
import itertools
import math
import random
from dataclasses import dataclass, field
from typing import Callable

import cocotb
from cocotb.simtime import convert
from cocotb.triggers import Timer

import protocol_facts as facts

from .cocotb_encoder import Cable, SimSteps
from .ssi import (IDLE_LEVEL, REPEAT_SAME_VALUE, RETRIGGER_ANY, SsiFormat, level_after,
                  ssi_bits)


@dataclass(frozen=True)
class SsiFaults:
    """Deliberate faults of one latched transmission (indices count from 0, the MSB).

    flip       : word bits flipped in every copy (the word as sent is wrong: a bad CRC).
    flip_copy2 : word bits flipped in the second copy of a ring only (double transmission:
                 the copies differ).
    separator  : the level of the bit right after the first copy (ring: the separator between
                 the copies; zeros: the 0 after the LSB), None: as the model sends it.
    force      : ``(index, level)`` pairs: the level after rising edge ``index + 1`` of the
                 transmission, whatever the rest says (e.g. the bit after a ring's second copy).
    """
    flip: tuple[int, ...] = ()
    flip_copy2: tuple[int, ...] = ()
    separator: int | None = None
    force: tuple[tuple[int, int], ...] = ()


@dataclass
class SsiRecord:
    """One latched transmission as the encoder lived through it (appended at the latching
    falling edge; ``ended`` once the line went high again)."""
    t_first_fall_s: float               # master-pin time of the latching MA falling edge
    t_latch_s: float                    # encoder time of the latch
    fmt: SsiFormat
    position: int                       # latched (wrapped to data_bits), binary
    errors: tuple[bool, ...]            # error flags (True = active)
    nenw: tuple[int, int] | None        # extended SSI: (nE, nW) as sent
    word: list[int]                     # the word as the model builds it (no fault)
    faults: SsiFaults = SsiFaults()
    levels: list[int] = field(default_factory=list)   # put on the line, one per MA rise
    ma_falls: int = 1                   # MA falling edges the encoder saw (the latch included)
    ma_rises: int = 0                   # MA rising edges the encoder saw
    t_line_high_s: float = math.nan     # encoder time the line went high (monoflop ran out)
    ended: bool = False
    t_falls_s: list[float] = field(default_factory=list)   # encoder times of the MA edges
    t_rises_s: list[float] = field(default_factory=list)


class SsiLineLogic:
    """The encoder's behaviour in encoder time, free of cocotb: :meth:`fall`, :meth:`rise` and
    :meth:`expire` with integer times (simulator steps of ``step_s`` seconds), in time order.
    Each returns the new line level when it changes what the encoder drives, else None;
    :meth:`fall` and :meth:`rise` also return when the monoflop runs out (``high_at``), when
    the caller must call :meth:`expire`."""

    def __init__(self, fmt: SsiFormat, position_at: Callable[[float], int], *,
                 errors_at: Callable | None = None, nenw_at: Callable | None = None,
                 step_s: float = 1e-12):
        self.position_at = position_at
        self.errors_at = errors_at
        self.nenw_at = nenw_at
        self.step_s = step_s
        self.fmt = None
        self.set_format(fmt)
        self.records: list[SsiRecord] = []
        self.plan: list[SsiFaults] = []  # faults of the next latches, first first
        self.level = IDLE_LEVEL          # what the encoder drives
        self.high_at: int | None = None  # when the monoflop runs out (None: no train yet)
        self.stray_rises = 0             # MA rises while the line was high, after a latch
        self._shifted = 0
        self._last_fall = self._last_rise = None

    def set_format(self, fmt: SsiFormat) -> None:
        """The format of the next latch (a transmission in progress keeps its own)."""
        if fmt.repeat == REPEAT_SAME_VALUE:
            raise ValueError("repeat='same_value' restarts on a new clock train, which is no "
                             "event on the pins: not modelled here")
        self.fmt = fmt

    def _steps(self, seconds: float) -> int:
        return round(seconds / self.step_s)

    def _expired(self, t: int) -> bool:
        return self.high_at is None or t >= self.high_at

    def _retrigger(self, t: int, fmt: SsiFormat) -> None:
        # ssi.line_high_at: tm after the last falling edge, or after the last edge ("any")
        last = self._last_fall if self._last_rise is None or fmt.retrigger != RETRIGGER_ANY \
            else max(self._last_fall, self._last_rise)
        self.high_at = last + self._steps(fmt.tm_s)

    def fall(self, t: int, t_master_s: float = math.nan) -> tuple[int | None, int]:
        """A falling edge at encoder time ``t`` (``t_master_s``: when it left the master pin):
        ``(new level or None, the time the monoflop now runs out)``."""
        out = None
        if self._expired(t):                    # a fall at exactly that time latches anew
            out = self.expire(t)                # the previous transmission ends first
            fmt = self.fmt
            t_s = t * self.step_s
            position = self.position_at(t_s) % (1 << fmt.data_bits)
            errors = tuple(self.errors_at(t_s)) if self.errors_at else (False,) * fmt.error_bits
            nenw = (tuple(self.nenw_at(t_s)) if self.nenw_at else (1, 1)) if fmt.nenw else None
            self.records.append(SsiRecord(t_master_s, t_s, fmt, position, errors, nenw,
                                          ssi_bits(fmt, position, errors, nenw),
                                          self.plan.pop(0) if self.plan else SsiFaults()))
            self._shifted = 0
            self._last_rise = None
        else:
            self.records[-1].ma_falls += 1
        self.records[-1].t_falls_s.append(t * self.step_s)
        self._last_fall = t
        self._retrigger(t, self.records[-1].fmt)
        return out, self.high_at

    def rise(self, t: int) -> tuple[int | None, int | None]:
        """A rising edge at encoder time ``t``: ``(new level or None, high_at)``."""
        if self._expired(t):        # MA held low past tm: the line went high, nothing to send
            # (a rise before any fall is MA coming out of the master's reset: no clock)
            self.stray_rises += bool(self.records)
            return None, self.high_at
        rec = self.records[-1]
        lvl = self._level(rec, self._shifted)
        self._shifted += 1
        rec.ma_rises += 1
        rec.levels.append(lvl)
        rec.t_rises_s.append(t * self.step_s)
        self._last_rise = t
        if rec.fmt.retrigger == RETRIGGER_ANY:
            self._retrigger(t, rec.fmt)
        return self._drive(lvl), self.high_at

    def expire(self, t: int) -> int | None:
        """Time ``t`` has come: if the monoflop ran out, the line goes high."""
        if self.high_at is None or t < self.high_at or not self.records:
            return None
        rec = self.records[-1]
        if not rec.ended:
            rec.ended = True
            rec.t_line_high_s = self.high_at * self.step_s
        return self._drive(IDLE_LEVEL)

    def _drive(self, lvl: int) -> int | None:
        if lvl == self.level:
            return None
        self.level = lvl
        return lvl

    @staticmethod
    def _level(rec: SsiRecord, index: int) -> int:
        """Rising edge ``index + 1``'s level: the model's (``level_after``), faults applied."""
        fmt, f = rec.fmt, rec.faults
        forced = dict(f.force)
        if index in forced:
            return int(forced[index])
        word = [b ^ (i in f.flip) for i, b in enumerate(rec.word)]
        n = len(word)
        if index == n and f.separator is not None:
            return int(f.separator)
        lvl = level_after(fmt, word, index)
        if index // (n + 1) == 1 and index % (n + 1) in f.flip_copy2:
            lvl ^= 1
        return lvl


class SsiLineEncoder(SimSteps):
    """SSI encoder + cable on the MA / SLO pins. See the module doc string.

    ``position_at(t)``, ``errors_at(t)``, ``nenw_at(t)``: the values latched at encoder time
    ``t`` (seconds). ``records`` (one :class:`SsiRecord` per latch), ``ma_edges`` (MA edges that
    reached the encoder, any state) and ``pin_edges`` (MA edges at the master pin).
    """

    def __init__(self, ma, slo, fmt: SsiFormat, position_at: Callable[[float], int], *,
                 cable: Cable = Cable(), errors_at: Callable | None = None,
                 nenw_at: Callable | None = None, rng: random.Random | None = None):
        self.ma = ma
        self.slo = slo
        self.cable = cable
        self.rng = rng if rng is not None else random.Random(0)
        self.logic = SsiLineLogic(fmt, position_at, errors_at=errors_at, nenw_at=nenw_at,
                                  step_s=convert(1, "step", to="sec"))
        self.ma_edges = 0
        self.pin_edges = 0
        self._queue: list = []
        self._seq = itertools.count()
        self._armed: set[int] = set()
        self._running = False
        self._task = None
        self._ma_pin: int | None = None
        self._slo_line = IDLE_LEVEL      # level that arrived at the master over the cable
        self._force: int | None = None
        self._slo_pin: int | None = None
        self._last_ma_arrival = -1
        self._last_slo_arrival = -1
        self._expiry_pending = False

    # -- public API -------------------------------------------------------------------------
    @property
    def records(self) -> list[SsiRecord]:
        return self.logic.records

    @property
    def fmt(self) -> SsiFormat:
        return self.logic.fmt

    def set_format(self, fmt: SsiFormat) -> None:
        """The format of the next latch."""
        self.logic.set_format(fmt)

    def set_cable(self, cable: Cable) -> None:
        """Change the cable (edges from now on)."""
        self.cable = cable

    def queue(self, faults: SsiFaults) -> None:
        """Faults of the next latched transmission (one per latch, in order)."""
        self.logic.plan.append(faults)

    def force_slo(self, level: int | None) -> None:
        """Override SLO at the master pin (None: the cable's level again)."""
        self._force = None if level is None else int(level)
        self._drive_pin()

    @property
    def ready(self) -> bool:
        """The encoder's line is high (the next falling edge latches)."""
        return self.logic.level == IDLE_LEVEL and self.logic._expired(self._now())

    def start(self) -> None:
        if self._running:
            return
        self._running = True
        try:
            self._ma_pin = int(self.ma.value)
        except ValueError:
            self._ma_pin = 1
        self._drive_pin()
        self._task = cocotb.start_soon(self._ma_monitor())

    def stop(self) -> None:
        self._running = False
        if self._task is not None and not self._task.done():
            self._task.cancel()
        self._queue.clear()
        self._armed.clear()

    # -- queue (as BissEncoder: integer steps from SimSteps, FIFO among equal times) --------
    def _push(self, t: int, fn: Callable, *args) -> None:
        heapq.heappush(self._queue, (t, next(self._seq), fn, args))
        if not self._running or any(w <= self._queue[0][0] for w in self._armed):
            return
        t0 = self._queue[0][0]
        self._armed.add(t0)
        cocotb.start_soon(self._waker(t0))

    def _run_due(self) -> None:
        now = self._now()
        while self._queue and self._queue[0][0] <= now:
            _, _, fn, args = heapq.heappop(self._queue)
            fn(*args)

    async def _waker(self, t: int) -> None:
        now = self._now()
        if t > now:
            await Timer(t - now, "step")
        self._armed.discard(t)
        if self._running:
            self._run_due()
            if self._queue and not any(w <= self._queue[0][0] for w in self._armed):
                t0 = self._queue[0][0]
                self._armed.add(t0)
                cocotb.start_soon(self._waker(t0))

    # -- master -> encoder ------------------------------------------------------------------
    async def _ma_monitor(self) -> None:
        while True:
            await self.ma.value_change
            try:
                lvl = int(self.ma.value)
            except ValueError:
                continue                # X/Z: not an edge
            if lvl == self._ma_pin:
                continue
            self._ma_pin = lvl
            self.pin_edges += 1
            tm = self._now()
            te = max(tm + self._steps(self.cable.m2e_s() + self._jitter()), tm,
                     self._last_ma_arrival)
            self._last_ma_arrival = te
            self._push(te, self._on_ma_edge, lvl, tm * self.logic.step_s)
            if te == tm:
                self._run_due()

    def _on_ma_edge(self, lvl: int, t_master_s: float) -> None:
        self.ma_edges += 1
        now = self._now()
        if lvl == 0:
            out, high_at = self.logic.fall(now, t_master_s)
        else:
            out, high_at = self.logic.rise(now)
        if out is not None:
            self._send(out)
        if high_at is not None and not self._expiry_pending:
            # one pending expiry event, moved on as edges retrigger the monoflop
            self._expiry_pending = True
            self._push(high_at, self._on_expire)

    def _on_expire(self) -> None:
        now = self._now()
        if self.logic.high_at is not None and now < self.logic.high_at:
            self._push(self.logic.high_at, self._on_expire)
            return
        self._expiry_pending = False
        out = self.logic.expire(now)
        if out is not None:
            self._send(out)

    # -- encoder -> master ------------------------------------------------------------------
    def _send(self, lvl: int) -> None:
        now = self._now()
        t = max(now + self._steps(facts.ENCODER_INTERNAL_DELAY_S + self.cable.e2m_s()
                                  + self._jitter()), now, self._last_slo_arrival)
        self._last_slo_arrival = t
        self._push(t, self._on_slo_arrival, lvl)

    def _on_slo_arrival(self, lvl: int) -> None:
        self._slo_line = lvl
        self._drive_pin()

    def _drive_pin(self) -> None:
        lvl = self._force if self._force is not None else self._slo_line
        if lvl != self._slo_pin:
            self._slo_pin = lvl
            self.slo.value = lvl
