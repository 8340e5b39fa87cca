"""Saturating event counters kept in a memory, two counts per 32-bit word."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

# Each memory word holds two counts, the even slot in its low half: the shared definitions
# (params) give the widths and the settle bound, which the bus tops rely on as well.
from ..params import (COUNTER_HALF_BITS as HALF_BITS, COUNTER_WORD_BITS as WORD_BITS,
                      counter_settle, counter_words)


class CounterRam(wiring.Component):
    """Error counters in one read-modify-write memory instead of one register each.

    Slot ``i`` of ``slots`` is the count in half ``i % 2`` of memory word ``i // 2`` (the low
    half for even ``i``), the layout of the register map's counter registers. A slot named
    ``None`` has no event and reads 0.

    Counting: each event is taken into a flip-flop (as :class:`~.counters.CounterBank` does),
    then added to its counter's pending count. Each clock one word with pending events or a
    clear to do, and not already on its way, is picked, in turn: the first such word above the
    one picked last, else the first from word 0. In the next clock it is read from the memory
    and its pending events taken; in the one after, both its counts plus their events,
    saturating at ``2**width - 1``, are written back. So a word waits for each other word at
    most once: a read issued 6 clocks after an event's clock returns its count when no other
    count waits, and one issued ``words + 7`` clocks after it (15 for 16 counters) in any case
    (``settle``, :func:`~bissmaster.params.counter_settle`).
    The events of a counter that come while it waits are added together; its pending count has
    room for an event in every clock of the longest wait, so none is lost, however fast a
    source strobes.

    Clearing: ``clear`` (registered like the events, and winning over the events of its own
    clock) drops the pending counts and marks every slot; a marked slot is written with its
    events since the clear instead of its count plus them. So every count reads its events
    since the clear from ``words + 6`` clocks after it, and never mixes counts from before it
    with those after. Reset marks every slot too: the memory, which a reset does not clear, is
    zeroed within ``words + 4`` clocks.

    Reading: ``read_addr`` and ``read_en`` in one clock, the word on ``read_data`` from the
    next, held until the next read (a registered read port: the register map's window).

    Parameters
    ----------
    slots : tuple of (str or None)
        The counters, in memory order.
    width : int
        Bits per count, 1..16.

    Attributes
    ----------
    events : In(StructLayout of 1-bit members, one per named slot)
    clear : In(1)
    read_addr : In(range of the words)
    read_en : In(1)
    read_data : Out(32)
    busy : Out(1)
        High while an event or a clear is not yet in the memory (registered, pending, or on
        its way to the write): low, a read issued in that clock returns every event before it.
    """

    def __init__(self, slots, width):
        if not 1 <= width <= HALF_BITS:
            raise ValueError(f"a counter in memory is 1 to {HALF_BITS} bits, not {width}")
        self._slots = tuple(slots)
        self._width = width
        self.words = counter_words(len(self._slots))
        #: A read issued this many clocks after an event's clock returns it in any case.
        self.settle = counter_settle(self.words)
        self._names = names = [name for name in self._slots if name is not None]
        if len(set(names)) != len(names):
            raise ValueError(f"counter names repeat: {self._slots}")
        super().__init__({
            "events": In(data.StructLayout({name: 1 for name in names})),
            "clear": In(1),
            "read_addr": In(range(self.words)),
            "read_en": In(1),
            "read_data": Out(WORD_BITS),
            "busy": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        words = self.words
        names = self._names
        full = 2**self._width - 1
        # A memory, not registers (issue 27): Yosys maps it to distributed RAM on ECP5
        # (TRELLIS_DPR16X4) and Xilinx (RAM32M), to MLABs on Cyclone V (Vivado and Quartus not
        # run here: docs/ports.md, "Clock and reset"); the two read ports (counting, the host's
        # reads) become two copies of it. A whole word is
        # written each time, both counts updated together: one write port serves the counters
        # a word per clock, so a counter waits for at most ``words - 1`` others.
        # iCE40 has no distributed RAM, and Yosys builds a memory this small from flip-flops
        # there (+576 logic cells on the iCEBreaker) unless told to use a block (EBR). Only
        # when elaborated for an iCE40 platform (the board designs): the generated Verilog keeps
        # the choice to the tool (docs/ports.md, Counters).
        ice40 = getattr(platform, "family", None) == "iCE40"
        m.submodules.memory = memory = Memory(shape=WORD_BITS, depth=words, init=[],
                                              attrs={"ram_style": "block"} if ice40 else None)
        write = memory.write_port()
        update = memory.read_port()
        host = memory.read_port()
        m.d.comb += [host.addr.eq(self.read_addr), host.en.eq(self.read_en),
                     self.read_data.eq(host.data)]

        # The events and the clear are taken into flip-flops first, as CounterBank does: they
        # are decided at a frame's end, several logic levels deep, and straight into the
        # pending counts' adders they were the bus top's critical path.
        # Reset-less, for Icarus as the pending counts below, and taken through an `if`: the
        # core's event strobes read X in Icarus until its power-up break ends (README, Notes),
        # and an X event added to a pending count would stay there; an `if` on X is not
        # taken. With the reset in the condition, Icarus runs the process when reset falls.
        events = Signal.like(self.events, name="events_reg", reset_less=True)
        clear = Signal(name="clear_reg", reset_less=True)

        def take(strobe, reg):
            with m.If(ResetSignal()):
                m.d.sync += reg.eq(0)
            with m.Elif(strobe):
                m.d.sync += reg.eq(1)
            with m.Else():
                m.d.sync += reg.eq(0)

        for name in names:
            take(self.events[name], events[name])
        take(self.clear, clear)
        slots = self._slots + (None,) * (2 * words - len(self._slots))
        event = [events[name] if name is not None else C(0) for name in slots]
        # A word is taken again at most ``words + 3`` clocks after it was, with at most an
        # event in each of them and in the clock it was taken: ``words + 3`` events.
        pending = [Signal(range(words + 4), name=f"pending_{i}", reset_less=True)
                   for i in range(2 * words)]
        # Every slot starts marked, so the memory is zeroed after reset.
        marked = Signal(2 * words, init=2**(2 * words) - 1, reset_less=True)
        # Three stages, each with its own one-hot register of its word (0: none): a word is
        # picked (``sel`` from the next clock), then read and its pending events and marks
        # taken (``writing`` from the next clock), then written. The pick is registered before
        # anything uses it: taken straight into the memory address, the pending counts and
        # the marks, its logic was copied into each of them (4x the LUTs) and was the bus top's
        # critical path.
        sel = Signal(words)
        sel_addr = Signal(range(words))
        writing = Signal(words)
        word = Signal(range(words))
        amount = [Signal.like(pending[0], name=f"amount_{h}") for h in range(2)]
        zero = Signal(2)

        def lowest(v):
            """One-hot of the lowest set bit of ``v`` (0 if none), without a carry chain."""
            return Cat(v[w] & ~v[:w].any() if w else v[0] for w in range(len(v)))

        # Pick: a word with pending events or marks, not in the later stages; in turn, the
        # first such word above the last one picked (``above``, a register), else the first.
        # Which words have something to write is registered (a clock late, for timing: the
        # pick is the longest path of the block). A stale "due" is harmless: the word just
        # taken is still excluded as ``sel`` or ``writing``, and a word picked with nothing to
        # write is written unchanged.
        waiting = Signal(words)
        m.d.sync += waiting.eq(Cat((pending[2 * w] != 0) | (pending[2 * w + 1] != 0)
                                   | marked[2 * w] | marked[2 * w + 1] for w in range(words)))
        due = Signal(words)
        m.d.comb += due.eq(waiting & ~sel & ~writing)
        above = Signal(words, reset_less=True)      # feeds itself: see the pending counts
        pick = Signal(words)
        # No pick in the first clock after reset: Icarus evaluates ``waiting``'s register input
        # only once reset falls, so it reads X for that one clock, and an X pick would feed
        # itself for ever through ``sel`` and the pending counts (hardware and Verilator do
        # not care; the cost is one flip-flop and a clock). Reset-less, so that no process of
        # its own can leave it X in that simulator.
        running = Signal(reset_less=True)
        m.d.sync += running.eq(~ResetSignal())
        m.d.comb += pick.eq(Mux(running & (due & above).any(), lowest(due & above),
                                Mux(running, lowest(due), 0)))
        m.d.sync += [sel.eq(pick),
                     sel_addr.eq(Cat(Cat(pick[w] for w in range(words) if w >> b & 1).any()
                                     for b in range(len(sel_addr))))]
        m.d.sync += above.eq(Mux(due.any(), Cat(pick[:w].any() if w else 0 for w in range(words)),
                                 above))

        # Read and take.
        def chosen(values):
            """The value of the word ``sel`` holds among ``values`` (an AND-OR on one-hot)."""
            out = 0
            for w, value in enumerate(values):
                out = out | Mux(sel[w], value, 0)
            return out

        m.d.comb += [update.addr.eq(sel_addr), update.en.eq(sel.any())]
        m.d.sync += [writing.eq(sel), word.eq(sel_addr),
                     zero.eq(chosen(marked[2 * w:2 * w + 2] for w in range(words)))]
        m.d.sync += [amount[h].eq(chosen(pending[2 * w + h] for w in range(words)))
                     for h in range(2)]

        # The pending counts: added to by an event, taken with their word (the event of that
        # clock stays pending); a clear drops them, winning over the events of its clock.
        # The pending counts and the marks feed themselves, so they are reset-less registers
        # whose reset is a plain multiplexer: Icarus may not run a register's reset process
        # before the first clock edge, and an X here would never leave (hardware and Verilator
        # behave the same either way).
        drop = ResetSignal() | clear
        for i in range(2 * words):
            m.d.sync += pending[i].eq(Mux(drop, 0, Mux(sel[i // 2], 0, pending[i]) + event[i]))
        m.d.sync += marked.eq(Mux(drop, 2**(2 * words) - 1,
                                  marked & ~Cat(sel[w].replicate(2) for w in range(words))))

        # The write: each half of the word read plus its pending events, saturating (or just
        # its events since a clear).
        halves = []
        for h in range(2):
            old = update.data[h * HALF_BITS:h * HALF_BITS + self._width]
            total = Signal(self._width + len(amount[h]), name=f"total_{h}")
            m.d.comb += total.eq(Mux(zero[h], 0, old) + amount[h])
            halves += [total[:self._width] | total[self._width:].any().replicate(self._width),
                       C(0, HALF_BITS - self._width)]
        m.d.comb += [write.addr.eq(word), write.data.eq(Cat(*halves)), write.en.eq(writing.any())]
        # Busy: the state one clock ago (a register, for timing: the wide OR is not in front
        # of what the user does with it), or an event taken since. Low in a clock, nothing was
        # pending or on its way in the last one and no event came in it, so every event before
        # this clock is in the memory.
        was_busy = Signal(init=1)         # after reset: the memory is being zeroed
        m.d.sync += was_busy.eq(events.as_value().any() | clear | marked.any() | sel.any()
                                | writing.any() | Cat(p != 0 for p in pending).any())
        m.d.comb += self.busy.eq(was_busy | events.as_value().any() | clear)
        return m
