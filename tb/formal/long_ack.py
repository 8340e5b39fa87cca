"""Return to idle beyond the formal depth: Start after a very long Ack (simulation).

The formal liveness check covers short cycles only. This looks at the one place where a fixed
16-bit counter could break "every cycle returns to idle": ``BissMaster`` stops MA once
``ma_clock.rises >= target_rises``, with ``target_rises`` = Start slot + frame bits + 4 (17 bits)
but ``MaClock.rises`` saturating at 65535. With a large ``cfg_ack_limit`` (``timer_width`` bits,
24 by default) Start may come so late that the target exceeds 65535, and ``ma_enough`` never
comes. The cycle still ends: the frame is reported from the sampler's slots (not from MA),
TAIL waits for the stop-bit sample, and END does not drive ``run``, so MaClock finishes its
period and the master goes idle. This simulation confirms it with Start in slot 65530 (about
262k clocks at a half period of 2): ``idle_before_abort`` is True. Run time about 35 s.

A tiny encoder written in Amaranth (fast) answers every MA rising edge: rises 2 .. s+1 Ack (low),
s+2 Start, s+3 CDS (0), then the data bits and CRC (all 1; the CRC verdict does not matter),
then SLO high (timeout over).

    python tb/formal/long_ack.py [start_slot]
"""

import sys

from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.sim import Simulator

from bissmaster.master import BissMaster
from bissmaster.params import Crc, MasterParams

PARAMS = MasterParams(max_data_bits=(2,), word_crcs=((Crc.CRC6,),))
DATA_BITS = 2
FRAME_BITS = DATA_BITS + 6           # no nE/nW, no LC, CRC-6
HALF_PERIOD = 2


class _Bench(Elaboratable):
    def __init__(self, start_slot):
        self.start_slot = start_slot
        self.dut = BissMaster(PARAMS)

    def elaborate(self, platform):
        m = Module()
        m.submodules.dut = dut = self.dut
        ma_prev = Signal(init=1)
        rises = Signal(20)
        m.d.sync += ma_prev.eq(dut.ma)
        with m.If(dut.ma & ~ma_prev):
            m.d.sync += rises.eq(rises + 1)
        with m.If(~dut.busy):
            m.d.sync += rises.eq(0)
        s = self.start_slot
        slo = Signal(init=1)
        with m.If((rises >= 2) & (rises <= s + 1)):
            m.d.comb += slo.eq(0)                           # Ack
        with m.Elif(rises == s + 3):
            m.d.comb += slo.eq(0)                           # CDS
        with m.Else():
            m.d.comb += slo.eq(1)                           # Start, data, CRC, then ready
        m.d.comb += [
            dut.slo.eq(slo),
            dut.cfg_ma_half_period.eq(HALF_PERIOD),
            dut.cfg_ack_limit.eq(2**PARAMS.timer_width - 1),     # the longest Ack limit
            dut.cfg_w0_data_bits.eq(DATA_BITS),
            dut.cfg_w0_crc.eq(Crc.CRC6),
        ]
        return m


def run(start_slot, clocks_after=2 * PARAMS.break_default + 1000):
    """Simulates one request cycle whose Start comes in slot ``start_slot``. After ``done``:
    did the master go idle within ``clocks_after // 2`` clocks; then ``abort_cycle`` is pulsed:
    is it idle at the end (after the break); how many MA edges were seen after ``done``."""
    bench = _Bench(start_slot)
    dut = bench.dut
    result = {}

    async def testbench(ctx):
        ctx.set(dut.start, 1)
        await ctx.tick().repeat(5000)          # break, then the request is accepted
        ctx.set(dut.start, 0)
        limit = (start_slot + FRAME_BITS + 64) * 2 * HALF_PERIOD + 10000
        n = 0
        while not ctx.get(dut.done):
            await ctx.tick()
            n += 1
            assert n < limit, "no done"
        result["status"] = ctx.get(dut.status)
        edges, ma_prev, idle_seen = 0, ctx.get(dut.ma), False
        for i in range(clocks_after):
            if i < clocks_after // 2 and not ctx.get(dut.busy):
                idle_seen = True
            if i == clocks_after // 2:
                ctx.set(dut.abort_cycle, 1)     # try to get out
            if i == clocks_after // 2 + 4:
                ctx.set(dut.abort_cycle, 0)
            await ctx.tick()
            ma = ctx.get(dut.ma)
            edges += ma != ma_prev
            ma_prev = ma
        result["idle_before_abort"] = idle_seen
        result["idle_after_abort"] = not ctx.get(dut.busy)
        result["ma_edges_after_done"] = edges

    sim = Simulator(bench)
    sim.add_clock(1e-8)
    sim.add_testbench(testbench)
    sim.run()
    return result


if __name__ == "__main__":
    slot = int(sys.argv[1]) if len(sys.argv) > 1 else 65530
    print(f"start slot {slot}: {run(slot)}")
