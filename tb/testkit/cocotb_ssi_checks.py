"""Self-checks of the cocotb SSI encoder + cable model (tb/encoder_model/cocotb_ssi.py).

Python plays an ideal master on ``ma`` of the empty harness tb/testkit/hdl/ma_loopback.v and
records every SLO change the model drives. The expected SLO waveform is computed here from the
master's own edge times and the pure model's levels (encoder_model.ssi.line_levels): level k
at the master pin at rise k + m2e + encoder delay + e2m, high again tm after the last fall (plus
the same delays); compared change by change, to the picosecond.

Run by tb/tests/model/test_ssi_driver.py (Icarus, timescale 1ns/1ps).
"""

from __future__ import annotations

import random

import cocotb
from cocotb.simtime import get_sim_time
from cocotb.triggers import Timer

import protocol_facts as facts
from encoder_model.cocotb_encoder import Cable
from encoder_model.cocotb_ssi import SsiFaults, SsiLineEncoder
from encoder_model.frames import CRC6
from encoder_model.ssi import SsiFormat, line_levels

PS_PER_S = 10**12
CABLES = {"0m": Cable(), "100m": Cable(length_m=100),
          "rt3us": Cable(extra_round_trip_s=3e-6 - facts.ENCODER_INTERNAL_DELAY_S)}


def ps(seconds: float) -> int:
    return round(seconds * PS_PER_S)


def now_ps() -> int:
    return get_sim_time("ps")


def delays_ps(cable: Cable) -> tuple[int, int]:
    """(MA master -> encoder, encoder -> SLO at the master incl. the encoder delay), in ps."""
    one_way = cable.length_m * facts.CABLE_ROUND_TRIP_S_PER_M / 2 + cable.extra_round_trip_s / 2
    return ps(one_way), ps(facts.ENCODER_INTERNAL_DELAY_S + one_way)


async def clock(dut, f_hz: float, n: int) -> tuple[list[int], list[int]]:
    """n MA pulses (fall, then rise half a period later), MA left high: (falls, rises) in ps."""
    half = round(PS_PER_S / (2 * f_hz))
    falls, rises = [], []
    for _ in range(n):
        dut.ma.value = 0
        falls.append(now_ps())
        await Timer(half, "ps")
        dut.ma.value = 1
        rises.append(now_ps())
        await Timer(half, "ps")
    return falls, rises


class SloMonitor:
    """Every SLO level change at the master pin, as (time_ps, level)."""

    def __init__(self, dut):
        self.dut = dut
        self.changes: list[tuple[int, int]] = []
        self.level = None
        cocotb.start_soon(self._run())

    async def _run(self):
        while True:
            await self.dut.slo.value_change
            lvl = int(self.dut.slo.value)
            if lvl != self.level:
                if self.level is not None:
                    self.changes.append((now_ps(), lvl))
                self.level = lvl

    def between(self, t0, t1):
        return [c for c in self.changes if t0 <= c[0] < t1]


def expected_changes(falls, rises, levels, cable, tm_s, level=1):
    """SLO changes at the master pin for one train from idle: level k at rise k + round trip,
    high at the last fall + m2e + tm + encoder delay + e2m."""
    m2e, dout = delays_ps(cable)
    out = []
    for t, lvl in [(r + m2e + dout, v) for r, v in zip(rises, levels)] + \
            [(falls[-1] + m2e + ps(tm_s) + dout, 1)]:
        if lvl != level:
            out.append((t, lvl))
            level = lvl
    return out


async def setup(dut, fmt, cable, **kw):
    dut.ma.value = 1
    dut.slo.value = 0                   # the model must drive it high at start()
    await Timer(100, "ns")
    positions = []

    def position_at(t):
        positions.append(random.Random(len(positions)).getrandbits(fmt.data_bits))
        return positions[-1]

    enc = SsiLineEncoder(dut.ma, dut.slo, fmt, position_at, cable=cable, **kw)
    mon = SloMonitor(dut)
    enc.start()
    await Timer(1, "us")
    assert int(dut.slo.value) == 1
    return enc, mon, positions


@cocotb.test()
@cocotb.parametrize(f_hz=[1e6, 10e6], cable_name=["0m", "100m", "rt3us"], double=[False, True])
async def train_timing(dut, f_hz, cable_name, double):
    """Two trains, the second after tm: every SLO change to the picosecond; sampled half a
    period after rise + round trip, the word (and with ring the second copy); the records."""
    cable = CABLES[cable_name]
    fmt = SsiFormat(13, gray=True, repeat="ring" if double else "zeros")
    enc, mon, positions = await setup(dut, fmt, cable)
    m2e, dout = delays_ps(cable)
    n = 2 * fmt.clocks if double else fmt.clocks
    for i in range(2):
        t0 = now_ps()
        falls, rises = await clock(dut, f_hz, n)
        await Timer(ps(fmt.tm_s) + ps(cable.round_trip_s()) + 1_000_000, "ps")
        rec = enc.records[-1]
        assert len(enc.records) == i + 1 and rec.position == positions[i]
        levels = line_levels(fmt, rec.position, n_clocks=n)
        assert rec.levels == levels and (rec.ma_falls, rec.ma_rises) == (n, n)
        assert rec.ended and ps(rec.t_line_high_s) == falls[-1] + m2e + ps(fmt.tm_s)
        assert ps(rec.t_first_fall_s) == falls[0] and ps(rec.t_latch_s) == falls[0] + m2e
        got = mon.between(t0, now_ps())
        assert got == expected_changes(falls, rises, levels, cable, fmt.tm_s), got
        half = round(PS_PER_S / (2 * f_hz))

        def level_at(t):
            lvl = 1
            for tc, v in got:
                if tc <= t:
                    lvl = v
            return lvl

        sampled = [level_at(r + m2e + dout + half) for r in rises]
        assert sampled == levels
    enc.stop()


@cocotb.test()
async def faults_and_force(dut):
    """Queued faults reach the line (copy 2 flipped, separator 1, a CRC bit in both copies);
    force_slo overrides the pin at once and hands it back to the cable."""
    fmt = SsiFormat(9, nenw=True, crc=CRC6, repeat="ring")
    cable = CABLES["100m"]
    enc, mon, _ = await setup(dut, fmt, cable)
    n = 2 * fmt.clocks
    w = fmt.total_bits
    for faults in (SsiFaults(flip_copy2=(2,)), SsiFaults(separator=1), SsiFaults(flip=(w - 1,))):
        enc.queue(faults)
        t0 = now_ps()
        falls, rises = await clock(dut, 5e6, n)
        await Timer(25, "us")
        rec = enc.records[-1]
        assert rec.faults == faults
        word = [b ^ (i in faults.flip) for i, b in enumerate(rec.word)]
        second = [b ^ (i in faults.flip_copy2) for i, b in enumerate(word)]
        sep = 0 if faults.separator is None else 1
        want = word + [sep] + second + [0]
        assert rec.levels == want
        assert mon.between(t0, now_ps()) == expected_changes(falls, rises, want, cable, fmt.tm_s)
    # force: the pin follows the force at once, the encoder runs on behind it
    t0 = now_ps()
    enc.force_slo(1)
    falls, rises = await clock(dut, 5e6, fmt.clocks)
    await Timer(1, "us")                # the last edges reach the encoder (100 m)
    assert mon.between(t0, now_ps()) == [] and enc.records[-1].ma_rises == fmt.clocks
    enc.force_slo(None)                 # the encoder's line is low (tm): the pin follows
    assert int(dut.slo.value) == 1
    await Timer(1, "ps")
    assert int(dut.slo.value) == 0
    await Timer(25, "us")
    t0 = now_ps()
    enc.force_slo(0)
    await Timer(100, "us")              # a master clocks nothing: nothing changes behind it
    enc.force_slo(None)
    await Timer(1, "ns")
    assert mon.between(t0, now_ps()) == [(t0, 0), (t0 + 100_000_000, 1)]
    enc.stop()


@cocotb.test()
async def retrigger_within_tm(dut):
    """A train that starts within tm latches nothing (the ring shifts on, the record counts its
    edges); one that starts after the line went high latches anew."""
    fmt = SsiFormat(8, repeat="ring")
    enc, mon, positions = await setup(dut, fmt, CABLES["0m"])
    await clock(dut, 1e6, fmt.clocks)
    await Timer(10, "us")
    await clock(dut, 1e6, 3)
    assert len(enc.records) == 1 and enc.records[0].ma_rises == fmt.clocks + 3
    assert enc.records[0].levels[fmt.clocks:] == enc.records[0].word[:3]
    await Timer(30, "us")
    assert enc.records[0].ended and enc.ready
    await clock(dut, 1e6, fmt.clocks)
    assert len(enc.records) == 2 and enc.records[1].position == positions[1]
    assert enc.logic.stray_rises == 0
    enc.stop()


@cocotb.test()
async def jitter_keeps_order(dut):
    """Jitter of 45 % of a half period on every edge: edges never overtake each other, and
    sampled at the centre the word is still right."""
    cable = Cable(length_m=20, jitter_s=45e-9)
    fmt = SsiFormat(24)
    enc, mon, positions = await setup(dut, fmt, cable, rng=random.Random(3))
    m2e, dout = delays_ps(cable)
    for _ in range(3):
        t0 = now_ps()
        falls, rises = await clock(dut, 5e6, fmt.clocks)
        await Timer(25, "us")
        rec = enc.records[-1]
        got = mon.between(t0, now_ps())
        assert [t for t, _ in got] == sorted(t for t, _ in got)

        def level_at(t):
            lvl = 1
            for tc, v in got:
                if tc <= t:
                    lvl = v
            return lvl

        assert [level_at(r + m2e + dout + 100_000) for r in rises] == \
            line_levels(fmt, rec.position)
    enc.stop()
