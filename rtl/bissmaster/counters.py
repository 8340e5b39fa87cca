"""Saturating event counters."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class SaturatingCounter(wiring.Component):
    """Counts ``inc`` strobes, sticks at the maximum, returns to 0 on ``clear``."""

    def __init__(self, width):
        super().__init__({"inc": In(1), "clear": In(1), "count": Out(width)})

    def elaborate(self, platform):
        m = Module()
        # ``full`` is ``count.all()``, kept as a register so that no wide AND sits in the
        # count enable.
        full = Signal()
        with m.If(self.clear):
            m.d.sync += [self.count.eq(0), full.eq(0)]
        with m.Elif(self.inc & ~full):
            m.d.sync += [
                self.count.eq(self.count + 1),
                full.eq(self.count == 2**len(self.count) - 2),
            ]
        return m
