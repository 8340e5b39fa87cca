"""Saturating event counters kept in a memory, two counts per 32-bit word."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

#: Bits of a memory word; each word holds two counts, the even slot in its low half.
WORD_BITS = 32
HALF_BITS = WORD_BITS // 2


class CounterRam(wiring.Component):
    """Error counters in one read-modify-write memory instead of one register each.

    Slot ``i`` of ``slots`` is the count in half ``i % 2`` of memory word ``i // 2`` (the low
    half for even ``i``), the layout of the register map's counter registers. A slot named
    ``None`` has no event and reads 0.

    Counting: each event adds to its counter's pending count, a register (the timing stage
    that :class:`~.counters.CounterBank` gets from registering its events). Each clock one word
    with pending events or a clear to do, whose write is not under way, is read from the
    memory, in turn: the first such word above the one taken last, else the first from word 0.
    In the next clock both its counts plus their pending events, saturating at
    ``2**width - 1``, are written back. So a word waits for each other word at most once: a
    read issued 3 clocks after an event's clock returns its count when no other count waits,
    and one issued ``words + 3`` clocks after it (11 for 16 counters) in any case. The events of
    a counter that come while it waits are added together; its pending count has room for an
    event in every clock of the longest wait, so none is lost, however fast a source strobes.

    Clearing: ``clear`` (winning over the events of its own clock) drops the pending counts
    and marks every slot; a marked slot is written with its events since the clear instead of
    its count plus them. So every count reads its events since the clear from ``words + 2``
    clocks after it, and never mixes counts from before it with those after. Reset marks every
    slot too: the memory, which a reset does not clear, is zeroed within ``words + 1`` clocks.

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
    """

    def __init__(self, slots, width):
        if not 1 <= width <= HALF_BITS:
            raise ValueError(f"a counter in memory is 1 to {HALF_BITS} bits, not {width}")
        self._slots = tuple(slots)
        self._width = width
        self.words = (len(self._slots) + 1) // 2
        names = [name for name in self._slots if name is not None]
        if len(set(names)) != len(names):
            raise ValueError(f"counter names repeat: {self._slots}")
        super().__init__({
            "events": In(data.StructLayout({name: 1 for name in names})),
            "clear": In(1),
            "read_addr": In(range(self.words)),
            "read_en": In(1),
            "read_data": Out(WORD_BITS),
        })

    def elaborate(self, platform):
        m = Module()
        words = self.words
        full = 2**self._width - 1
        # A memory, not registers (issue 27): Yosys maps it to distributed RAM on ECP5
        # (TRELLIS_DPR16X4) and Vivado/Quartus infer the same from the generated Verilog; the
        # two read ports (counting, the host's reads) become two copies of it. A whole word is
        # written each time, both counts updated together: one write port serves the counters
        # a word per clock, so a counter waits for at most ``words - 1`` others.
        m.submodules.memory = memory = Memory(shape=WORD_BITS, depth=words, init=[])
        write = memory.write_port()
        update = memory.read_port()
        host = memory.read_port()
        m.d.comb += [host.addr.eq(self.read_addr), host.en.eq(self.read_en),
                     self.read_data.eq(host.data)]

        slots = self._slots + (None,) * (2 * words - len(self._slots))
        event = [self.events[name] if name is not None else C(0) for name in slots]
        # A due word is taken within ``words`` clocks of its last write, with at most an
        # event in each of them and in the clock of that write: ``words + 1`` events.
        pending = [Signal(range(words + 2), name=f"pending_{i}") for i in range(2 * words)]
        # Every slot starts marked, so the memory is zeroed after reset.
        marked = Signal(2 * words, init=2**(2 * words) - 1)
        # The word being written this clock (read in the last one), with its two halves'
        # pending events and marks as taken.
        busy = Signal()
        word = Signal(range(words))
        amount = [Signal.like(pending[0], name=f"amount_{h}") for h in range(2)]
        zero = Signal(2)

        due = Signal(words)
        m.d.comb += due.eq(Cat((pending[2 * w] != 0) | (pending[2 * w + 1] != 0)
                               | marked[2 * w] | marked[2 * w + 1] for w in range(words))
                           & ~Mux(busy, 1 << word, 0))
        # In turn: the first due word above the last one taken, else the first due word.
        last = Signal(range(words))
        above = Signal(words)
        m.d.comb += above.eq(due & ~((2 << last) - 1))
        pick = Signal(range(words))
        for w in reversed(range(words)):
            with m.If(due[w]):
                m.d.comb += pick.eq(w)
        with m.If(above.any()):
            for w in reversed(range(words)):
                with m.If(above[w]):
                    m.d.comb += pick.eq(w)
        picked = due.any()

        m.d.comb += [update.addr.eq(pick), update.en.eq(picked)]
        m.d.sync += busy.eq(picked)
        with m.If(picked):
            m.d.sync += [word.eq(pick), last.eq(pick),
                         amount[0].eq(Array(pending[0::2])[pick]),
                         amount[1].eq(Array(pending[1::2])[pick]),
                         zero.eq(marked.word_select(pick, 2))]

        # The pending counts: added to by an event, taken with their word (the event of that
        # clock stays pending); a clear drops them, winning over the events of its clock.
        for i in range(2 * words):
            taken = picked & (pick == i // 2)
            with m.If(self.clear):
                m.d.sync += pending[i].eq(0)
            with m.Else():
                m.d.sync += pending[i].eq(Mux(taken, 0, pending[i]) + event[i])
        with m.If(self.clear):
            m.d.sync += marked.eq(2**(2 * words) - 1)
        with m.Elif(picked):
            m.d.sync += marked.word_select(pick, 2).eq(0)

        # The write: each half of the word read plus its pending events, saturating (or just
        # its events since a clear).
        halves = []
        for h in range(2):
            old = update.data[h * HALF_BITS:h * HALF_BITS + self._width]
            total = Signal(self._width + len(amount[h]), name=f"total_{h}")
            m.d.comb += total.eq(Mux(zero[h], 0, old) + amount[h])
            halves += [Mux(total > full, full, total)[:self._width],
                       C(0, HALF_BITS - self._width)]
        m.d.comb += [write.addr.eq(word), write.data.eq(Cat(*halves)), write.en.eq(busy)]
        return m
