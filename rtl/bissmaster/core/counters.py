"""Saturating event counters."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
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


class CounterBank(wiring.Component):
    """One :class:`SaturatingCounter` per name, cleared together, behind one register stage.

    ``events`` and ``clear`` are taken into flip-flops first, so every count changes one clock
    after its event or clear (in the master: the clock after ``done``), and a clear still wins
    over an event of its own clock. The stage is for timing: the events are decided at a
    frame's end, several logic levels deep, and with several channels behind a bus the route
    from that decision into every counter's enable was a critical path (docs/performance.md).

    Parameters
    ----------
    names : tuple of str
        The counters, in order.
    width : int
        Bits per counter.

    Attributes
    ----------
    events : In(StructLayout of 1-bit members)
        One strobe per counter.
    clear : In(1)
        Overrides counting while high (one clock later, as the events).
    counts : Out(StructLayout of ``width``-bit members)
    """

    def __init__(self, names, width):
        self._names = tuple(names)
        self._width = width
        super().__init__({
            "events": In(data.StructLayout({name: 1 for name in self._names})),
            "clear": In(1),
            "counts": Out(data.StructLayout({name: width for name in self._names})),
        })

    def elaborate(self, platform):
        m = Module()
        events = Signal.like(self.events, name="events_reg")
        clear = Signal(name="clear_reg")
        m.d.sync += [events.eq(self.events), clear.eq(self.clear)]
        for name in self._names:
            m.submodules[f"count_{name}"] = counter = SaturatingCounter(self._width)
            m.d.comb += [
                counter.inc.eq(events[name]),
                counter.clear.eq(clear),
                self.counts[name].eq(counter.count),
            ]
        return m
