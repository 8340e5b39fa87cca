"""SnapshotPages (the result memory of the register bank) against a model of its contract,
written here from docs/bus.md ("The result snapshot"), not from the RTL:

- ``capture`` in clock c copies word i of the live words as they are in clock c + 1 + i;
- the copy is published (``published`` high) in clock c + count + 1 unless another ``capture``
  came in c + 1 .. c + count, which starts the copy again (the cut copy is never published);
- a read with ``read_take`` in clock t returns (in t + 1) word ``addr`` of the newest set
  published in clock t or before, and makes that set the host's; a read without it returns
  word ``addr`` of the host's set; 0 while there is no such set (also after a reset, whatever
  the memory holds).

Random captures (also back to back and cut short), random live words changing in every clock,
random reads, a reset half way that leaves the memory as it was, on Amaranth's simulator.
"""

import random

import pytest
from amaranth.hdl import ClockDomain, Module
from amaranth.sim import Simulator

from bissmaster.bus.snapshot_pages import SnapshotPages


class PagesModel:
    def __init__(self, count):
        self.count = count
        self.copy = None            # (words so far, clocks since capture)
        self.latest = None          # the newest published set
        self.host = None            # the host's set

    def clock(self, live, capture):
        """One clock: ``live`` the words in it, ``capture`` its input; returns whether
        ``published`` is high in it."""
        published = False
        if self.copy is not None and len(self.copy) == self.count:
            self.latest, self.copy = tuple(self.copy), None
            published = True
        if self.copy is not None:
            self.copy.append(live[len(self.copy)])
        if capture:
            self.copy = []
        return published

    def reset(self):
        """A reset: registers cleared, the memory kept; nothing written before it is read."""
        self.__init__(self.count)

    def read(self, addr, take):
        if take:
            self.host = self.latest
        return 0 if self.host is None else self.host[addr]


@pytest.mark.parametrize("count,seed", [(8, 1), (8, 2), (4, 3), (1, 4), (5, 5)])
def test_pages_follow_the_model(count, seed):
    rng = random.Random(seed)
    dut = SnapshotPages(count)
    model = PagesModel(count)
    top = Module()
    top.domains.sync = sync = ClockDomain()
    rst = sync.rst
    top.submodules.dut = dut
    sim = Simulator(top)
    sim.add_clock(1e-8)
    seen = {"published": 0, "cut": 0, "takes": 0, "stale": 0}

    async def bench(ctx):
        expect_read = None
        for clock in range(4000):
            if clock == 2500:
                # A reset that leaves the memory as it was (a warm reset on an FPGA).
                ctx.set(rst, 1)
                await ctx.tick()
                ctx.set(rst, 0)
                model.reset()
                expect_read = None
            live = [rng.getrandbits(32) for _ in range(count)]
            # Captures: mostly a cycle's end far apart, sometimes one that cuts a copy short.
            capture = rng.random() < (0.25 if rng.random() < 0.2 else 0.04)
            read_en = rng.random() < 0.6
            take = read_en and rng.random() < 0.3
            addr = rng.randrange(count)
            ctx.set(dut.words, live)
            ctx.set(dut.capture, capture)
            ctx.set(dut.read_en, read_en)
            ctx.set(dut.read_take, take)
            ctx.set(dut.read_addr, addr)
            if capture and model.copy is not None:
                seen["cut"] += 1
            published = model.clock(live, capture)
            assert ctx.get(dut.published) == published, clock
            seen["published"] += published
            if expect_read is not None:
                assert ctx.get(dut.read_data) == expect_read, clock
            if read_en:
                before = model.host
                expect_read = model.read(addr, take)
                seen["takes"] += take
                seen["stale"] += take and before is not None and model.host is not before
            await ctx.tick()
        # The random run reached every case it is meant to check.
        assert seen["published"] > 50 and seen["cut"] > 10 and seen["takes"] > 300
        assert seen["stale"] > 20                   # takes that moved the host to a newer set

    sim.add_testbench(bench)
    sim.run()


@pytest.mark.filterwarnings("ignore::amaranth.hdl.UnusedElaboratable")
def test_count_is_checked():
    for bad in (0, -1, 1 << 17, 2.0):
        with pytest.raises(ValueError, match="count"):
            SnapshotPages(bad)
