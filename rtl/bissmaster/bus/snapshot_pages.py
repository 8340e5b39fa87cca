"""A snapshot group of the register map (the result) kept in a memory of pages, not in
flip-flops: a triple buffer between the hardware, which writes a complete set after each event,
and the host, which reads one set without tearing."""

from amaranth.hdl import *
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .regmap import DATA_WIDTH

#: Pages of the memory: one being written, the latest complete one, the one the host reads.
#: Four, not three: a page index is two bits either way, and the free page is then found
#: without a case for "all three taken".
PAGES = 4


class SnapshotPages(wiring.Component):
    """The words of a snapshot group, copied into a memory page after each ``capture`` and read
    from one page at a time.

    Writing: ``capture`` (a one-clock pulse) starts a copy of ``words`` into a free page, one
    word per clock from the next clock on, word 0 first: word ``i`` is taken from ``words`` in
    the ``i``-th clock after ``capture``, so ``words`` must hold from the clock after
    ``capture`` for ``count`` clocks. When the last word is written the page becomes the latest
    (``published`` high for one clock, registered). A ``capture`` while a copy runs starts it
    again from word 0 and that copy is never published: a page is published only if it was
    written without interruption, so it never mixes two sets (the copy that was cut short
    reads as the page before it). The free page is neither the latest nor the host's: the
    host never reads a page being written.

    Reading (a registered read port, as the register bank's windows): ``read_en`` and
    ``read_addr`` in one clock, the word on ``read_data`` from the next, held until the next
    read. A read with ``read_take`` high (the bank gives it for the group's first register)
    reads the latest page and makes it the host's; every other read reads the host's page. So
    the words read after the first belong to the set the first read belonged to, however many
    sets are published meanwhile. A word reads 0 (the reset values of the map's result fields)
    while no set has been published, and so does every word but the first before the first
    read of the first word that found one: also after a reset that leaves the memory as it
    was, no stale word is read.

    Parameters
    ----------
    count : int
        Words in the group, 1 .. 2**16; the page is the next power of two.

    Attributes
    ----------
    words : In(ArrayLayout(32, count))
        The group's words, live.
    capture : In(1)
    published : Out(1)
    read_addr : In(range(page size))
    read_en, read_take : In(1)
    read_data : Out(32)
    """

    def __init__(self, count):
        if not isinstance(count, int) or not 1 <= count <= 1 << 16:
            raise ValueError(f"count must be an integer from 1 to 65536, not {count!r}")
        self.count = count
        self.page_bits = (count - 1).bit_length()
        super().__init__({
            "words": In(data.ArrayLayout(DATA_WIDTH, count)),
            "capture": In(1),
            "published": Out(1),
            "read_addr": In(max(self.page_bits, 1)),
            "read_en": In(1),
            "read_take": In(1),
            "read_data": Out(DATA_WIDTH),
        })

    def elaborate(self, platform):
        m = Module()
        bits = self.page_bits
        page_bits = (PAGES - 1).bit_length()
        # init=[]: zero in simulation and in an FPGA's configuration; nothing relies on it
        # (``ready`` masks the reads until a page is published).
        m.submodules.memory = memory = Memory(shape=DATA_WIDTH, depth=PAGES << bits, init=[])
        write = memory.write_port()
        read = memory.read_port()

        latest = Signal(page_bits, name="latest_page")      # the newest complete page
        host = Signal(page_bits, name="host_page")          # the page the host reads
        target = Signal(page_bits, name="target_page")      # the page being written
        writing = Signal()
        index = Signal(range(self.count), name="word_index")
        ready = Signal()                                    # a page has been published

        # The free page: the lowest that is neither the latest nor the host's.
        free = Signal(page_bits, name="free_page")
        with m.If((latest != 0) & (host != 0)):
            m.d.comb += free.eq(0)
        with m.Elif((latest != 1) & (host != 1)):
            m.d.comb += free.eq(1)
        with m.Else():
            m.d.comb += free.eq(2)

        m.d.sync += self.published.eq(0)
        with m.If(self.capture):
            m.d.sync += [writing.eq(1), index.eq(0), target.eq(free)]
        with m.Elif(writing):
            m.d.sync += index.eq(index + 1)
            with m.If(index == self.count - 1):
                m.d.sync += [writing.eq(0), latest.eq(target), ready.eq(1),
                             self.published.eq(1)]
        m.d.comb += [
            write.addr.eq(Cat(index if bits else C(0, 0), target)),
            write.data.eq(self.words[index]),
            write.en.eq(writing),
        ]

        page = Mux(self.read_take, latest, host)
        host_ready = Signal()                               # the host's page was published
        with m.If(self.read_en & self.read_take):
            m.d.sync += [host.eq(latest), host_ready.eq(ready)]
        # Whether the read found a published page, registered with the read's data.
        read_ready = Signal()
        with m.If(self.read_en):
            m.d.sync += read_ready.eq(Mux(self.read_take, ready, host_ready))
        m.d.comb += [
            read.addr.eq(Cat(self.read_addr[:bits] if bits else C(0, 0), page)),
            read.en.eq(self.read_en),
            self.read_data.eq(Mux(read_ready, read.data, 0)),
        ]
        return m
