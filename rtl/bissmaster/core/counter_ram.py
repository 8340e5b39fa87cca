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
    then added to its counter's pending count. The words take turns, one per clock, whether or
    not they have anything to add: in its turn a word is read from the memory and its pending
    counts are taken, and in the next clock both its counts plus those events, saturating at
    ``2**width - 1``, are written back. A count is therefore in the memory at most
    ``words + 2`` clocks after its event's clock, and a read issued ``words + 3`` clocks after
    it (11 for 16 counters; the turns run over two words at least) returns it (``settle``, :func:`~bissmaster.params.counter_settle`;
    at least 4 clocks after it, when the event comes just before its word's turn). A counter's
    events between two turns of its word are added together; its pending count has room for
    one in every clock, so none is lost, however fast a source strobes.

    Clearing: ``clear`` (registered like the events, and winning over the events of its own
    clock) drops the pending counts and marks every word; a marked word is written with its
    events since the clear instead of its counts plus them. So every count reads its events
    since the clear from ``words + 3`` clocks after it, and never mixes counts from before it
    with those after. Reset marks every word too: the memory, which a reset does not clear, is
    zeroed, and a read issued ``words + 2`` clocks after the reset's clock reads 0.

    Reading: ``read_addr`` and ``read_en`` in one clock, the word on ``read_data`` from the
    next, held until the next read (a registered read port: the register map's window). It
    is the word as written up to the clock before the read.

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
        High in a reset's clock, and while an event or a clear may not yet be in the memory:
        from the clock after its own to the last before ``settle`` clocks after it. Low, a
        read issued in that clock returns every event before it.
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
        # The turns run over two words at least: a word's read in its turn must see the write
        # of its previous turn, issued in the clock after it (a one-word memory is given a
        # second word that nothing reads).
        turns = max(words, 2)
        names = self._names
        # A memory, not registers (issue 27): Yosys maps it to distributed RAM on ECP5
        # (TRELLIS_DPR16X4) and Xilinx (RAM32M), to MLABs on Cyclone V (Vivado and Quartus not
        # run here: docs/ports.md, "Clock and reset"); the two read ports (counting, the host's
        # reads) become two copies of it. A whole word is written each time, both counts
        # updated together.
        # iCE40 has no distributed RAM, and Yosys builds a memory this small from flip-flops
        # there (+576 logic cells on the iCEBreaker) unless told to use a block (EBR), whose
        # read ports are registered: both ports here are. Only when elaborated for an iCE40
        # platform (the board designs): the generated Verilog keeps the choice to the tool
        # (docs/ports.md, Counters).
        ice40 = getattr(platform, "family", None) == "iCE40"
        m.submodules.memory = memory = Memory(shape=WORD_BITS, depth=turns, init=[],
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
        slots = self._slots + (None,) * (2 * turns - len(self._slots))
        event = [events[name] if name is not None else C(0) for name in slots]

        # Every register below feeds itself, so each is reset-less with its reset as a plain
        # multiplexer: Icarus may not run a register's reset process before the first clock
        # edge, and an X here would never leave (hardware and Verilator behave the same either
        # way). Their initial values are their reset values: the memory is zeroed after
        # power-up as after a reset.
        reset = ResetSignal()
        drop = reset | clear
        # The word whose turn it is, and the same one-hot.
        turn = Signal(range(turns), reset_less=True)
        m.d.sync += turn.eq(Mux(reset | (turn == turns - 1), 0, turn + 1))
        now = Signal(turns)
        m.d.comb += now.eq(Cat(turn == w for w in range(turns)))
        # A slot's events since its word's last turn: at most one per clock of a round.
        pending = [Signal(range(turns + 1), name=f"pending_{i}", reset_less=True)
                   for i in range(2 * turns)]
        for i in range(2 * turns):
            m.d.sync += pending[i].eq(Mux(drop, 0, Mux(now[i // 2], 0, pending[i]) + event[i]))
        # Words to be written with their events alone (cleared): every word after a clear or
        # a reset, until its next turn.
        marked = Signal(turns, init=2**turns - 1, reset_less=True)
        m.d.sync += marked.eq(Mux(drop, 2**turns - 1, marked & ~now))

        # The turn: the word read, its pending counts and its mark taken (an AND-OR on the
        # one-hot; a case block in the Verilog would run only once an input changes in Icarus).
        def chosen(values):
            out = 0
            for w, value in enumerate(values):
                out = out | Mux(now[w], value, 0)
            return out

        address = Signal(range(turns), reset_less=True)
        zero = Signal(init=1, reset_less=True)
        amount = [Signal.like(pending[0], name=f"amount_{h}", reset_less=True) for h in range(2)]
        m.d.comb += [update.addr.eq(turn), update.en.eq(1)]
        m.d.sync += [address.eq(turn), zero.eq(reset | (marked & now).any())]
        m.d.sync += [amount[h].eq(Mux(reset, 0, chosen(pending[2 * w + h] for w in range(turns))))
                     for h in range(2)]

        # The clock after: each half of the word read plus its events, saturating (or just
        # its events, when marked), written back.
        halves = []
        for h in range(2):
            old = update.data[h * HALF_BITS:h * HALF_BITS + self._width]
            total = Signal(self._width + len(amount[h]), name=f"total_{h}")
            m.d.comb += total.eq(Mux(zero, 0, old) + amount[h])
            halves += [total[:self._width] | total[self._width:].any().replicate(self._width),
                       C(0, HALF_BITS - self._width)]
        m.d.comb += [write.addr.eq(address), write.data.eq(Cat(*halves)), write.en.eq(1)]

        # Busy: a countdown of a round and the write after the last event, clear or reset (a
        # counter, not the OR of every pending count: the turns do not skip idle words, so the
        # bound is the same and the OR cost about 100 LUT4 on ECP5).
        left = Signal(range(turns + 2), init=turns + 1, reset_less=True)
        start = reset | events.as_value().any() | clear
        m.d.sync += left.eq(Mux(start, turns + 1, Mux(left != 0, left - 1, 0)))
        m.d.comb += self.busy.eq((left != 0) | start)
        return m
