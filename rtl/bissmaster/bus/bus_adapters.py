"""AXI4-Lite and Wishbone B4 in front of the register bank's internal bus.

Each adapter turns one bus protocol into :class:`~bissmaster.bus.register_bank.RegisterBus`
transactions and nothing else: no register knowledge, no address decoding. 32-bit data,
byte strobes (AXI ``wstrb``, Wishbone ``sel``) passed through, every transaction answered (an
unmapped address reads 0, docs/bus.md).
"""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .register_bank import STROBES, RegisterBus
from .regmap import DATA_WIDTH

#: AXI response codes (AMBA AXI, xRESP): the bank answers every address.
RESP_OKAY = 0b00


class AxiLiteSignature(wiring.Signature):
    """AXI4-Lite, as the manager (CPU side) sees it; byte addresses. No AxPROT: the bank has
    no privileged registers."""

    def __init__(self, addr_width):
        self.addr_width = addr_width
        super().__init__({
            "awaddr": Out(addr_width), "awvalid": Out(1), "awready": In(1),
            "wdata": Out(DATA_WIDTH), "wstrb": Out(STROBES), "wvalid": Out(1), "wready": In(1),
            "bresp": In(2), "bvalid": In(1), "bready": Out(1),
            "araddr": Out(addr_width), "arvalid": Out(1), "arready": In(1),
            "rdata": In(DATA_WIDTH), "rresp": In(2), "rvalid": In(1), "rready": Out(1),
        })


class WishboneSignature(wiring.Signature):
    """Wishbone B4, classic and pipelined, as the master sees it: 32-bit port, 8-bit
    granularity, word addresses (``adr`` holds byte-address bits [n:2])."""

    def __init__(self, addr_width):
        self.addr_width = addr_width
        super().__init__({
            "cyc": Out(1), "stb": Out(1), "we": Out(1), "adr": Out(addr_width),
            "dat_w": Out(DATA_WIDTH), "sel": Out(STROBES),
            "dat_r": In(DATA_WIDTH), "ack": In(1), "stall": In(1),
        })


class AxiLiteAdapter(wiring.Component):
    """AXI4-Lite subordinate -> register bus.

    Writes: the address and the data channel are taken independently (each may come first)
    into one holding register each; the write goes to the bank in a clock both are held, no
    earlier write is waiting for the bank (``w_busy``) and no earlier response is waiting;
    its response (OKAY) follows in the clock after the bank's ``w_busy`` is seen low (at the
    earliest the third clock after the write; later for a channel's configuration while its
    core is in a cycle), when the write has acted: a read whose address comes after the
    response sees the write. A new address and data can be taken while the write waits.
    Reads: two steps, as the bank's read
    (:class:`~bissmaster.bus.register_bank.RegisterBus`): the address taken in a clock
    (``arvalid & arready``, the bank's ``r_en``) is pending in the next; a pending read's
    data is loaded (``r_load``) and ``rvalid`` rises in the following clock, unless read data
    is still waiting (``rvalid`` without ``rready``). The address is taken whenever no read
    is pending or the pending one is loaded in the same clock, so reads run back to back,
    one per clock, and the data follows two clocks after the address (one wait state).
    """

    def __init__(self, addr_width):
        super().__init__({
            "axil": In(AxiLiteSignature(addr_width)),
            "regs": Out(RegisterBus(addr_width - 2)),
        })

    def elaborate(self, platform):
        m = Module()
        axil, regs = self.axil, self.regs

        # Write address and data, held until the write is done.
        aw_held, w_held = Signal(), Signal()
        aw_addr = Signal.like(regs.w_addr)
        w_data, w_strb = Signal.like(regs.w_data), Signal.like(regs.w_strb)
        m.d.comb += [axil.awready.eq(~aw_held), axil.wready.eq(~w_held)]
        with m.If(axil.awvalid & axil.awready):
            m.d.sync += [aw_held.eq(1), aw_addr.eq(axil.awaddr[2:])]
        with m.If(axil.wvalid & axil.wready):
            m.d.sync += [w_held.eq(1), w_data.eq(axil.wdata), w_strb.eq(axil.wstrb)]

        # The write, its wait for the bank, and its response.
        waiting, bvalid = Signal(), Signal()
        write = aw_held & w_held & ~waiting & (~axil.bvalid | axil.bready)
        m.d.comb += [regs.w_en.eq(write), regs.w_addr.eq(aw_addr), regs.w_data.eq(w_data),
                     regs.w_strb.eq(w_strb), axil.bresp.eq(RESP_OKAY)]
        m.d.comb += axil.bvalid.eq(bvalid)
        with m.If(write):
            m.d.sync += [aw_held.eq(0), w_held.eq(0), waiting.eq(1)]
        acted = waiting & ~regs.w_busy
        with m.If(acted):
            m.d.sync += [waiting.eq(0), bvalid.eq(1)]
        with m.Elif(axil.bready):
            m.d.sync += bvalid.eq(0)

        # Reads: the address to the bank (r_en), pending one clock or more, then the data
        # (r_load) when the R channel is free.
        pending, rvalid = Signal(), Signal()
        load = pending & (~rvalid | axil.rready)
        read = axil.arvalid & axil.arready
        m.d.comb += [
            axil.arready.eq(~pending | load),
            regs.r_en.eq(read), regs.r_addr.eq(axil.araddr[2:]), regs.r_load.eq(load),
            axil.rvalid.eq(rvalid), axil.rdata.eq(regs.r_data), axil.rresp.eq(RESP_OKAY),
        ]
        with m.If(read):
            m.d.sync += pending.eq(1)
        with m.Elif(load):
            m.d.sync += pending.eq(0)
        with m.If(load):
            m.d.sync += rvalid.eq(1)
        with m.Elif(axil.rready):
            m.d.sync += rvalid.eq(0)
        return m


class WishboneAdapter(wiring.Component):
    """Wishbone B4 slave (classic and pipelined) -> register bus.

    A request (``cyc & stb``) is taken in a clock without ``stall``. A write is answered with
    ``ack`` in the clock after the bank's ``w_busy`` is seen low (at the earliest the third
    clock after it is taken; later for a channel's configuration while its core is in a
    cycle), when the write has acted, so the next request, taken after the ``ack``, sees it;
    a read, in two steps as the bank's read (:class:`~bissmaster.bus.register_bank.RegisterBus`),
    two clocks after it is taken (one wait
    state), with the read data. ``stall`` is high from the clock after a request is taken
    up to its ``ack`` clock: a classic master, which holds ``stb`` until ``ack``, is never
    seen twice, and a pipelined master puts its next request in the clock after the ``ack``.
    At most one write per four clocks, one read per three, either way; never ``err`` or
    ``rty`` (an unmapped address reads 0).
    """

    def __init__(self, addr_width):
        super().__init__({
            "wb": In(WishboneSignature(addr_width - 2)),
            "regs": Out(RegisterBus(addr_width - 2)),
        })

    def elaborate(self, platform):
        m = Module()
        wb, regs = self.wb, self.regs
        # pending: a read taken in the last clock, its data loaded now and acked next clock;
        # writing: a write taken, waiting for the bank to act on it (w_busy).
        ack, pending, writing = Signal(), Signal(), Signal()
        busy = ack | pending | writing
        take = wb.cyc & wb.stb & ~busy
        acted = writing & ~regs.w_busy
        m.d.sync += [ack.eq(acted | pending), pending.eq(take & ~wb.we),
                     writing.eq((take & wb.we) | (writing & regs.w_busy))]
        m.d.comb += [
            regs.r_en.eq(take & ~wb.we), regs.r_addr.eq(wb.adr), regs.r_load.eq(pending),
            regs.w_en.eq(take & wb.we), regs.w_addr.eq(wb.adr),
            regs.w_data.eq(wb.dat_w), regs.w_strb.eq(wb.sel),
            wb.ack.eq(ack), wb.stall.eq(busy), wb.dat_r.eq(regs.r_data),
        ]
        return m
