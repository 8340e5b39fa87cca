"""RegisterBank and the AXI4-Lite adapter on Amaranth's simulator, with the real register map:
the fast tier under the cocotb bus scenarios (sim/scenarios/bus.py).

Expected values are written here from docs/bus.md and the SystemRDL source's field kinds:
storage per byte lane, the write acting in the clock after w_en (the registered request),
write-1 pulses one clock after that, sticky interrupts (a set wins
over a clear in the same clock), the snapshot taken by reading result.status, unmapped reads 0,
the register-access windows (ca.wbuf, ca.rbuf) as ports of a 16 x 32 memory with byte lanes
(a memory of the test's own, lib.memory), read with the registers' latency.
"""

import pytest
from amaranth.sim import Simulator
from amaranth.hdl import ClockDomain, Module
from amaranth.lib import wiring
from amaranth.lib.memory import Memory

from bissmaster.bus import regmap
from bissmaster.bus.bus_adapters import AxiLiteAdapter, WishboneAdapter
from bissmaster.bus.register_bank import RegisterBank
from testkit.block_sim import simulate_with_reset

MAP = regmap.load()
CH0 = MAP.channel_base


def offset(path):
    return CH0 + next(r for r in MAP.channel if r.path == path).offset


def run(bench, channels=1, buffers=False, absent=None, held=None, tables=None):
    """``buffers``: channel 0's windows on one memory of the test (16 words, byte lanes): the
    write window writes it, the read window reads it through a registered port. ``absent``:
    the bank's per-channel signals the core lacks; ``held``: those it reads without a copy."""
    top = Module()
    top.domains.sync = ClockDomain()
    top.submodules.bank = bank = RegisterBank(MAP, channels, absent, held, tables)
    if buffers:
        top.submodules.mem = mem = Memory(shape=32, depth=16, init=[])
        wr, rd = mem.write_port(granularity=8), mem.read_port()
        ch = bank.ch0
        top.d.comb += [wr.addr.eq(ch.ca_wbuf_addr), wr.data.eq(ch.ca_wbuf_data),
                       wr.en.eq(ch.ca_wbuf_en), rd.addr.eq(ch.ca_rbuf_addr),
                       rd.en.eq(ch.ca_rbuf_en), ch.ca_rbuf_data.eq(rd.data)]
    sim = Simulator(top)
    sim.add_clock(1e-8)
    async def testbench(ctx):
        await bench(ctx, bank)
    sim.add_testbench(testbench)
    sim.run()


def run_adapter(adapter, bench, held=None):
    """One channel's bank behind a bus adapter (AxiLiteAdapter or WishboneAdapter); ``bench``
    gets (ctx, the adapter's bus side, the bank). ``held``: as for :func:`run`."""
    top = Module()
    top.domains.sync = ClockDomain()
    top.submodules.bank = bank = RegisterBank(MAP, 1, None, held)
    top.submodules.adapter = dut = adapter(MAP.addr_width)
    wiring.connect(top, dut.regs, bank.bus)
    bus = dut.axil if adapter is AxiLiteAdapter else dut.wb
    sim = Simulator(top)
    sim.add_clock(1e-8)
    async def testbench(ctx):
        await bench(ctx, bus, bank)
    sim.add_testbench(testbench)
    sim.run()


async def write(ctx, bank, addr, value, strb=0xF):
    """A write: w_en for one clock; the bank registers the request and the write acts in the
    next clock (a pulse, an interrupt clear), or a clock later for a configuration register,
    so its result is there after three clock edges."""
    ctx.set(bank.bus.w_en, 1)
    ctx.set(bank.bus.w_addr, addr // 4)
    ctx.set(bank.bus.w_data, value)
    ctx.set(bank.bus.w_strb, strb)
    await ctx.tick()
    ctx.set(bank.bus.w_en, 0)
    await ctx.tick()
    await ctx.tick()


async def read(ctx, bank, addr):
    """A read in the bank's two steps: r_en (the register read), then r_load (the data)."""
    ctx.set(bank.bus.r_en, 1)
    ctx.set(bank.bus.r_addr, addr // 4)
    await ctx.tick()
    ctx.set(bank.bus.r_en, 0)
    ctx.set(bank.bus.r_load, 1)
    await ctx.tick()
    ctx.set(bank.bus.r_load, 0)
    return ctx.get(bank.bus.r_data)


def test_storage_lanes_and_unmapped():
    async def bench(ctx, bank):
        period = offset("cfg_period")
        await write(ctx, bank, period, 0x00ABCDEF)
        assert ctx.get(bank.ch0.cfg_request_period) == 0xABCDEF
        await write(ctx, bank, period, 0x00001100, strb=0b0010)
        assert await read(ctx, bank, period) == 0xAB11EF
        await write(ctx, bank, period, 0xFFFFFFFF)
        assert await read(ctx, bank, period) == 0xFFFFFF        # 24-bit field only
        for addr in (0x14, CH0 + 0x118, CH0 + 0x1C0, CH0 + MAP.channel_stride, MAP.size - 4):
            await write(ctx, bank, addr, 0xFFFFFFFF)
            assert await read(ctx, bank, addr) == 0
        assert await read(ctx, bank, 0) == 0x42695353           # id
    run(bench)


def test_settings_the_core_lacks_are_not_stored():
    """docs/bus.md: a configuration field whose signal the channel's core does not have (a
    one-word build's word 1, no SSI) reads its reset value and ignores writes, per channel;
    the fields beside it in the same register are stored as ever."""
    absent = [{"cfg_w1_data_bits", "cfg_w1_enable", "cfg_ssi", "cfg_ssi_delay"}, set()]

    async def bench(ctx, bank):
        words, ssi = offset("cfg_words"), offset("cfg_ssi")
        for ch in (0, 1):
            base = ch * MAP.channel_stride
            await write(ctx, bank, base + words, 0xFFFFFFFF)
            await write(ctx, bank, base + ssi, 0xFFFFFFFF)
        w1_bits = 0x7F << 16 | 1 << 31              # w1_data_bits [22:16], w1_enable [31]
        assert await read(ctx, bank, words) == 0xFFFFFFFF & ~w1_bits & _mask("cfg_words")
        assert await read(ctx, bank, ssi) == 0b1110                # error, error_low, double
        assert ctx.get(bank.ch0.cfg_w1_enable) == 0 and ctx.get(bank.ch0.cfg_ssi_delay) == 0
        assert ctx.get(bank.ch0.cfg_w0_data_bits) == 0x7F
        ch1 = MAP.channel_stride
        assert await read(ctx, bank, ch1 + words) == _mask("cfg_words")
        assert await read(ctx, bank, ch1 + ssi) == _mask("cfg_ssi")
        assert ctx.get(bank.ch1.cfg_w1_enable) == 1 and ctx.get(bank.ch1.cfg_ssi_delay) == 0xFFF
    run(bench, channels=2, absent=absent)


def _mask(path):
    """The bits of a register's fields (from the map's source)."""
    reg = next(r for r in MAP.channel if r.path == path)
    return sum(((1 << f.width) - 1) << f.lsb for f in reg.fields)


def test_configuration_register_holds_the_new_value_from_the_third_clock():
    """A configuration register's write goes through a second register stage: the value is
    there from the third clock after w_en (the clock after the bank's response to a bus write,
    the earliest a bus read after the response could load it). ctrl, which holds pulses too,
    is written in one stage with them."""
    async def bench(ctx, bank):
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, offset("cfg_period") // 4)
        ctx.set(bank.bus.w_data, 0x123456)
        ctx.set(bank.bus.w_strb, 0b0101)                # bytes 0 and 2 only
        seen = []
        for _ in range(4):
            await ctx.tick()
            ctx.set(bank.bus.w_en, 0)
            ctx.set(bank.bus.w_data, 0xFFFFFF)          # the request is taken, not the bus
            ctx.set(bank.bus.w_strb, 0xF)
            seen.append(ctx.get(bank.ch0.cfg_request_period))
        assert seen == [0, 0, 0x120056, 0x120056]
        # ctrl holds pulses too: its configuration acts with them, in the second clock.
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, offset("ctrl") // 4)
        ctx.set(bank.bus.w_data, 0x101)                 # periodic, start
        seen = []
        for _ in range(3):
            await ctx.tick()
            ctx.set(bank.bus.w_en, 0)
            seen.append((ctx.get(bank.ch0.periodic), ctx.get(bank.ch0.start)))
        assert seen == [(0, 0), (1, 1), (1, 0)]
    run(bench)


def test_pulse_is_one_clock_after_the_registered_write():
    """The write acts in the clock after w_en (the registered request); its pulses are
    registered too: high in the second clock after w_en, for one clock."""
    async def bench(ctx, bank):
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, offset("ctrl") // 4)
        ctx.set(bank.bus.w_data, 0b101)                 # start, clear_counters
        ctx.set(bank.bus.w_strb, 0xF)
        seen = []
        for _ in range(4):
            await ctx.tick()
            ctx.set(bank.bus.w_en, 0)
            seen.append((ctx.get(bank.ch0.start), ctx.get(bank.ch0.clear_counters),
                         ctx.get(bank.ch0.abort_cycle)))
        assert seen == [(0, 0, 0), (1, 1, 0), (0, 0, 0), (0, 0, 0)]
        assert await read(ctx, bank, offset("ctrl")) == 0
    run(bench)


def test_interrupt_set_wins_over_clear_and_irq_follows_enable():
    async def bench(ctx, bank):
        status, enable = offset("irq_status"), offset("irq_enable")
        ctx.set(bank.ch0.frame_done, 1)
        ctx.set(bank.ch0.frame_error, 1)                # two causes, one clock
        await ctx.tick()
        ctx.set(bank.ch0.frame_done, 0)
        ctx.set(bank.ch0.frame_error, 0)
        assert await read(ctx, bank, status) == 0b11
        assert ctx.get(bank.irq) == 0                   # nothing enabled
        await write(ctx, bank, enable, 0b10)
        assert ctx.get(bank.irq) == 1
        # Clear both while done sets again in the same clock: done stays, error goes.
        ctx.set(bank.ch0.frame_done, 1)
        await write(ctx, bank, status, 0b11)
        ctx.set(bank.ch0.frame_done, 0)
        assert await read(ctx, bank, status) == 0b01
        assert ctx.get(bank.irq) == 0
        await write(ctx, bank, status, 0b01, strb=0b0010)    # lane 1 only: no clear
        assert await read(ctx, bank, status) == 0b01
    run(bench)


def test_snapshot_taken_by_reading_result_status():
    async def bench(ctx, bank):
        ctx.set(bank.ch0.word0_position, 0x12_3456_789A)
        ctx.set(bank.ch0.status, 3)
        assert await read(ctx, bank, offset("result.status")) & 0xF == 3
        ctx.set(bank.ch0.word0_position, 0x7F_FFFF_FFFF)  # a new frame after the snapshot
        ctx.set(bank.ch0.status, 0)
        assert await read(ctx, bank, offset("result.w0_lo")) == 0x3456_789A
        assert await read(ctx, bank, offset("result.w0_hi")) == 0x12
        assert await read(ctx, bank, offset("result.status")) & 0xF == 0
        assert await read(ctx, bank, offset("result.w0_hi")) == 0x7F
    run(bench)


def test_axil_reads_back_to_back_and_write_with_address_after_data():
    async def bench(ctx, bus, bank):
        # W first, AW two clocks later; then the response.
        ctx.set(bus.wvalid, 1)
        ctx.set(bus.wdata, 0x1234)
        ctx.set(bus.wstrb, 0xF)
        await ctx.tick()
        ctx.set(bus.wvalid, 0)
        await ctx.tick()
        ctx.set(bus.awvalid, 1)
        ctx.set(bus.awaddr, offset("cfg_ma"))
        await ctx.tick()
        ctx.set(bus.awvalid, 0)
        ctx.set(bus.bready, 1)
        for _ in range(4):
            if ctx.get(bus.bvalid):
                break
            await ctx.tick()
        assert ctx.get(bus.bvalid) and ctx.get(bus.bresp) == 0
        await ctx.tick()
        # Three reads in three clocks, rready held: one datum per clock, each two clocks
        # after its address (one wait state). The first, in the clock after the B
        # handshake, already reads what was written.
        ctx.set(bus.rready, 1)
        got = []
        for clock, addr in enumerate((offset("cfg_ma"), 0, 4, None, None)):
            ctx.set(bus.arvalid, addr is not None)
            ctx.set(bus.araddr, addr or 0)
            assert ctx.get(bus.arready)
            await ctx.tick()
            if ctx.get(bus.rvalid):
                got.append((clock + 1, ctx.get(bus.rdata)))
        assert got == [(2, 0x1234), (3, 0x42695353), (4, 0x00020000)]    # version 2.0

    run_adapter(AxiLiteAdapter, bench)


def test_axil_read_backpressure_reads_each_register_once():
    """Reads issued back to back while rready follows a pattern: every read's data comes once,
    in order, held while rready is low; arready is low while a read waits behind held data.
    The snapshot (reading result.status) is taken once, in the clock its data is loaded (the
    clock before its rvalid): the position changed after the AR handshake but before that is
    what result.w0_lo and w0_hi read, the one changed after it is not."""
    reads = [0, offset("result.status"), offset("result.w0_lo"), offset("result.w0_hi"), 4,
             offset("result.w0_lo")]
    ready = [0, 0, 0, 1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0, 1] + [1] * 8

    async def bench(ctx, bus, bank):
        ctx.set(bank.ch0.word0_position, 0x12_3456_789A)
        ctx.set(bank.ch0.status, 3)
        issued, got, held, status_seen = 0, [], None, False
        for r in ready:
            ctx.set(bus.arvalid, issued < len(reads))
            ctx.set(bus.araddr, reads[issued] if issued < len(reads) else 0)
            ctx.set(bus.rready, r)
            took = issued < len(reads) and ctx.get(bus.arready)
            if ctx.get(bus.rvalid):
                if held is not None:
                    assert ctx.get(bus.rdata) == held      # held while rready was low
                if r:
                    got.append(ctx.get(bus.rdata))
                    held = None
                else:
                    held = ctx.get(bus.rdata)
            await ctx.tick()
            if took:
                if reads[issued] == offset("result.status"):
                    ctx.set(bank.ch0.word0_position, 0x55_0000_00AA)
                issued += 1
            # The word on R now is the (len(got))th: those before it were all taken.
            if ctx.get(bus.rvalid) and len(got) == 1 and not status_seen:
                status_seen = True                      # result.status's data is out
                ctx.set(bank.ch0.word0_position, 0x7F_FFFF_FFFF)
        assert issued == len(reads) and status_seen
        assert [g & 0xF if n == 1 else g for n, g in enumerate(got)] == [
            0x42695353, 3, 0x0000_00AA, 0x55, 0x00020000, 0x0000_00AA]

    run_adapter(AxiLiteAdapter, bench)


def test_wishbone_read_waits_one_state_and_write_two():
    """Wishbone classic: a write is acked three clocks after it is taken (once the bank's
    w_busy is low: the write has acted), a read two clocks after (one wait state), with its
    data; stall is high up to the ack, so a request held through the ack is taken once."""
    async def cycle(ctx, bus, addr, data=None):
        ctx.set(bus.cyc, 1)
        ctx.set(bus.stb, 1)
        ctx.set(bus.we, data is not None)
        ctx.set(bus.adr, addr // 4)
        ctx.set(bus.dat_w, data or 0)
        ctx.set(bus.sel, 0xF)
        stalls = []
        for clock in range(1, 6):
            await ctx.tick()
            stalls.append(ctx.get(bus.stall))
            if ctx.get(bus.ack):
                value = ctx.get(bus.dat_r)
                ctx.set(bus.cyc, 0)
                ctx.set(bus.stb, 0)
                await ctx.tick()
                assert not ctx.get(bus.ack)             # one ack per request
                return clock, stalls, value
        raise AssertionError("no ack")

    async def bench(ctx, bus, bank):
        assert (await cycle(ctx, bus, offset("cfg_ma"), 0x0777))[:2] == (3, [1, 1, 1])
        assert await cycle(ctx, bus, offset("cfg_ma")) == (2, [1, 1], 0x0777)
        assert await cycle(ctx, bus, 0) == (2, [1, 1], 0x42695353)

    run_adapter(WishboneAdapter, bench)


def test_windows_byte_lanes_and_read_latency():
    """ca.wbuf word n with byte strobes reaches the memory's word n, only the strobed lanes;
    ca.rbuf word n reads it with the latency of a register (r_en, then r_load) and keeps it
    until the next read, even when the memory changes meanwhile."""
    wbuf, rbuf = offset("ca.wbuf"), offset("ca.rbuf")

    async def bench(ctx, bank):
        for n in range(16):
            await write(ctx, bank, wbuf + 4 * n, 0x03020100 + 0x04040404 * n)
        await write(ctx, bank, wbuf + 4 * 5, 0xEEDDCCBB, strb=0b0101)   # bytes 20 and 22
        await write(ctx, bank, wbuf + 4 * 15, 0xFF000000, strb=0b1000)  # byte 63
        expect = bytearray(range(64))
        expect[20], expect[22], expect[63] = 0xBB, 0xDD, 0xFF
        for n in range(16):
            assert await read(ctx, bank, rbuf + 4 * n) == int.from_bytes(expect[4 * n:4 * n + 4],
                                                                      "little"), n
        # A write never reads back through the write window; a write to the read window is
        # ignored (no strobe reaches the memory).
        assert await read(ctx, bank, wbuf) == 0
        await write(ctx, bank, rbuf + 4, 0xFFFFFFFF)
        assert await read(ctx, bank, rbuf + 4) == int.from_bytes(expect[4:8], "little")
        # The read data holds until the next read: the word changes, the data does not.
        word2 = int.from_bytes(expect[8:12], "little")
        assert await read(ctx, bank, rbuf + 8) == word2
        await write(ctx, bank, wbuf + 8, 0x12345678)
        await ctx.tick()
        assert ctx.get(bank.bus.r_data) == word2
        # Back to back: a register, the window, a register.
        assert await read(ctx, bank, 0) == 0x42695353
        assert await read(ctx, bank, rbuf + 8) == 0x12345678
        assert await read(ctx, bank, 0) == 0x42695353
    run(bench, buffers=True)


def test_access_registers_and_done_interrupt():
    """ca.request drives the request ports, ca.ctrl.start and abort are pulses, ca.state reads
    the engine's busy, status and bytes done live, and ca_done sets irq_status.access_done."""
    async def bench(ctx, bank):
        ch = bank.ch0
        await write(ctx, bank, offset("ca.request"), 5 | 0x41 << 8 | 3 << 16 | 1 << 24)
        assert (ctx.get(ch.ca_slave_id), ctx.get(ch.ca_address), ctx.get(ch.ca_count),
                ctx.get(ch.ca_write)) == (5, 0x41, 3, 1)
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, offset("ca.ctrl") // 4)
        ctx.set(bank.bus.w_data, 0b11)
        ctx.set(bank.bus.w_strb, 0xF)
        await ctx.tick()
        ctx.set(bank.bus.w_en, 0)
        assert (ctx.get(ch.ca_start), ctx.get(ch.ca_abort)) == (0, 0)     # request registered
        await ctx.tick()
        assert (ctx.get(ch.ca_start), ctx.get(ch.ca_abort)) == (1, 1)
        await ctx.tick()
        assert (ctx.get(ch.ca_start), ctx.get(ch.ca_abort)) == (0, 0)
        ctx.set(ch.ca_busy, 1)
        ctx.set(ch.ca_status, 3)
        ctx.set(ch.ca_bytes_done, 64)
        assert await read(ctx, bank, offset("ca.state")) == 1 | 3 << 4 | 64 << 8
        ctx.set(ch.ca_done, 1)
        await ctx.tick()
        ctx.set(ch.ca_done, 0)
        assert await read(ctx, bank, offset("irq_status")) == 0b100
        await write(ctx, bank, offset("irq_enable"), 0b100)
        assert ctx.get(bank.irq) == 1
    run(bench)


def _run_with_reset(bench, bank=None):
    """``bank`` (default: one channel's bank of the map); ``bench`` gets (ctx, bank, the clock
    domain's reset)."""
    bank = bank or RegisterBank(MAP, 1)
    simulate_with_reset(bank, lambda ctx, rst: bench(ctx, bank, rst))


def test_configuration_reads_its_reset_value_after_a_reset():
    """Configuration registers are read back from a memory (docs/bus.md, Area), which a reset
    does not clear: after a reset a register reads its reset value, not what the memory still
    holds, and a write of one byte lane then reads that lane with the others at their reset
    values. The next write of another lane keeps the first."""
    async def bench(ctx, bank, rst):
        period, quiet = offset("cfg_period"), offset("cfg_quiet")
        await write(ctx, bank, period, 0x00ABCDEF)
        await write(ctx, bank, quiet, 0x00000ABC)
        assert await read(ctx, bank, period) == 0xABCDEF
        ctx.set(rst, 1)
        await ctx.tick()
        ctx.set(rst, 0)
        assert await read(ctx, bank, period) == 0
        assert await read(ctx, bank, quiet) == 0
        assert ctx.get(bank.ch0.cfg_request_period) == 0
        await write(ctx, bank, period, 0x00000011, strb=0b0001)
        assert await read(ctx, bank, period) == 0x000011
        await write(ctx, bank, period, 0x00220000, strb=0b0100)
        assert await read(ctx, bank, period) == 0x220011
        assert ctx.get(bank.ch0.cfg_request_period) == 0x220011
        assert await read(ctx, bank, quiet) == 0
    _run_with_reset(bench)


def test_configuration_read_returns_the_value_of_its_load_clock():
    """A read of a configuration register returns the value of its r_load clock, as a
    flip-flop's word would. r_en in the clock after w_en: with r_load two clocks later (the
    first clock the register's flip-flops hold the write) it reads the new value, with r_load
    one clock later (the clock the write reaches them) the old one."""
    async def bench(ctx, bank):
        period = offset("cfg_period")
        await write(ctx, bank, period, 0x000001)
        # (clocks from r_en to r_load, the value written, the value the read returns)
        for load_after, value, want in ((2, 0x000002, 0x000002), (1, 0x000003, 0x000002)):
            ctx.set(bank.bus.w_en, 1)
            ctx.set(bank.bus.w_addr, period // 4)
            ctx.set(bank.bus.w_data, value)
            ctx.set(bank.bus.w_strb, 0xF)
            await ctx.tick()                            # clock 1: the request registered
            ctx.set(bank.bus.w_en, 0)
            ctx.set(bank.bus.r_en, 1)                   # r_en in clock 1
            ctx.set(bank.bus.r_addr, period // 4)
            for _ in range(load_after):
                await ctx.tick()
                ctx.set(bank.bus.r_en, 0)
            ctx.set(bank.bus.r_load, 1)                 # r_load in clock 1 + load_after
            await ctx.tick()
            ctx.set(bank.bus.r_load, 0)
            assert ctx.get(bank.bus.r_data) == want, (load_after, hex(ctx.get(bank.bus.r_data)))
            await ctx.tick()
            await ctx.tick()
        assert await read(ctx, bank, period) == 0x000003
    run(bench)


def test_first_write_after_a_reset_reads_back_in_its_first_clock():
    """The first write of a configuration register since reset reads back from the first clock
    its flip-flops hold it (r_load two clocks after an r_en in the clock after w_en), as every
    later write does: the read-back memory's written-since-reset flag is current in that
    clock, not a clock late (the reset value would be read)."""
    async def bench(ctx, bank, rst):
        period = offset("cfg_period")
        await write(ctx, bank, period, 0x000005)
        ctx.set(rst, 1)
        await ctx.tick()
        ctx.set(rst, 0)
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, period // 4)
        ctx.set(bank.bus.w_data, 0x000123)
        ctx.set(bank.bus.w_strb, 0xF)
        await ctx.tick()                                # clock 1: the request registered
        ctx.set(bank.bus.w_en, 0)
        ctx.set(bank.bus.r_en, 1)                       # r_en in clock 1
        ctx.set(bank.bus.r_addr, period // 4)
        await ctx.tick()
        ctx.set(bank.bus.r_en, 0)
        await ctx.tick()
        ctx.set(bank.bus.r_load, 1)                     # r_load in clock 3
        await ctx.tick()
        ctx.set(bank.bus.r_load, 0)
        assert ctx.get(bank.bus.r_data) == 0x000123
    _run_with_reset(bench)


#: A channel's held configuration in these tests: the request period (register cfg_period).
HELD = [{"cfg_request_period"}]


def test_held_configuration_waits_for_the_idle_core():
    """docs/bus.md, "Configuration writes": a write of a held register waits at its second
    stage while the core is busy (cfg_free low), holds the core (cfg_hold) and keeps w_busy
    high; the flip-flops and the read-back take it in the clock after the first clock the core
    is idle (so with the core idle, from the fourth clock after w_en, one later than another
    configuration register). Other registers of the channel do not wait."""
    async def bench(ctx, bank):
        ch, bus = bank.ch0, bank.bus
        # Idle core: the value from the fourth clock; w_busy 1, 1, 1, 0.
        ctx.set(bank.cfg_free, 1)
        ctx.set(bus.w_en, 1)
        ctx.set(bus.w_addr, offset("cfg_period") // 4)
        ctx.set(bus.w_data, 0x000111)
        ctx.set(bus.w_strb, 0xF)
        seen = []
        for _ in range(4):
            await ctx.tick()
            ctx.set(bus.w_en, 0)
            seen.append((ctx.get(ch.cfg_request_period), ctx.get(bus.w_busy),
                         ctx.get(bank.cfg_hold)))
        assert seen == [(0, 1, 0), (0, 1, 1), (0, 1, 1), (0x111, 0, 0)]
        # Busy core: the write waits, holding the core, as long as it is busy.
        ctx.set(bank.cfg_free, 0)
        ctx.set(bus.w_en, 1)
        ctx.set(bus.w_data, 0x000222)
        await ctx.tick()
        ctx.set(bus.w_en, 0)
        for _ in range(30):
            await ctx.tick()
            assert ctx.get(ch.cfg_request_period) == 0x111
            assert ctx.get(bus.w_busy) and ctx.get(bank.cfg_hold)
        assert await read(ctx, bank, offset("cfg_period")) == 0x111   # the read-back too
        ctx.set(bank.cfg_free, 1)                  # the cycle ends: acts in the next clock
        await ctx.tick()
        assert ctx.get(ch.cfg_request_period) == 0x111 and ctx.get(bank.cfg_hold)
        await ctx.tick()
        assert ctx.get(ch.cfg_request_period) == 0x222
        assert not ctx.get(bus.w_busy) and not ctx.get(bank.cfg_hold)
        assert await read(ctx, bank, offset("cfg_period")) == 0x222
        # A register without a held field (irq_enable) does not wait for a busy core.
        ctx.set(bank.cfg_free, 0)
        await write(ctx, bank, offset("irq_enable"), 1)
        assert not ctx.get(bus.w_busy) and not ctx.get(bank.cfg_hold)
        assert await read(ctx, bank, offset("irq_enable")) & 1 == 1
    run(bench, held=HELD)


async def _answered_after_release(ctx, bank, answered):
    """With the core busy (cfg_free low) for 40 clocks nothing is ``answered()``; then the
    core is idle: the clocks until it is (at most 10)."""
    for _ in range(40):
        await ctx.tick()
        assert not answered()
    ctx.set(bank.cfg_free, 1)
    for clocks in range(1, 11):
        await ctx.tick()
        if answered():
            return clocks
    raise AssertionError("no answer 10 clocks after the core became idle")


def test_bus_response_waits_for_a_held_write():
    """AXI4-Lite and Wishbone: the response to a held write comes only once it has acted
    (the core idle), three clocks after."""
    async def axil(ctx, bus, bank):
        ctx.set(bank.cfg_free, 0)
        ctx.set(bus.bready, 1)
        ctx.set(bus.awvalid, 1)
        ctx.set(bus.awaddr, offset("cfg_period"))
        ctx.set(bus.wvalid, 1)
        ctx.set(bus.wdata, 0x345)
        ctx.set(bus.wstrb, 0xF)
        await ctx.tick()
        ctx.set(bus.awvalid, 0)
        ctx.set(bus.wvalid, 0)
        assert await _answered_after_release(ctx, bank, lambda: ctx.get(bus.bvalid)) == 3
        assert ctx.get(bank.ch0.cfg_request_period) == 0x345
    run_adapter(AxiLiteAdapter, axil, held=HELD)

    async def wishbone(ctx, bus, bank):
        ctx.set(bank.cfg_free, 0)
        for name, value in (("cyc", 1), ("stb", 1), ("we", 1), ("adr", offset("cfg_period") // 4),
                            ("dat_w", 0x678), ("sel", 0xF)):
            ctx.set(getattr(bus, name), value)
        # stall high through the wait: the request held on the bus is taken once.
        answered = lambda: ctx.get(bus.ack) or not ctx.get(bus.stall)
        assert await _answered_after_release(ctx, bank, answered) == 3
        assert ctx.get(bus.ack) and ctx.get(bank.ch0.cfg_request_period) == 0x678
    run_adapter(WishboneAdapter, wishbone, held=HELD)


#: A CRC table as the bus tops give it (docs/bus.md, "The CRC table"), written here from the
#: map: entry N holds word N's polynomial in bits 0..15, its start value in 16..31 and its
#: inversion in bit 32.
TABLE = {f"cfg_w{w}_crc_{name}": ("crc", w, lsb) for w in range(8)
         for name, lsb in (("poly", 0), ("start", 16), ("inverted", 32))}
TABLE_REGISTERS = {0: ("cfg_crc0", "cfg_crc0_start"), 1: ("cfg_crc1", "cfg_crc1_start"),
                   **{w: (f"cfg_w{w}_crc", f"cfg_w{w}_crc_start") for w in range(2, 8)}}


def _entry(poly, start, inverted):
    return poly | start << 16 | inverted << 32


async def _table(ctx, bank, entry):
    ctx.set(bank.ch0_crc_addr, entry)
    await ctx.delay(1e-9)
    return ctx.get(bank.ch0_crc_data)


def test_crc_table_holds_each_words_crc_in_memory():
    """docs/bus.md, "The CRC table": the polynomial, start value and inversion of each word's
    custom CRC are written into entry N of the channel's table (byte lane by byte lane, as a
    flip-flop register is) and read combinationally by the core; the registers read back what
    was written; the width beside them stays a flip-flop setting. Held like the rest: with the
    core busy, a write changes nothing until it is idle."""
    async def bench(ctx, bank):
        ctx.set(bank.cfg_free, 1)
        for _ in range(10):                             # the clear after reset
            await ctx.tick()
        written = {}
        for w, (crc_reg, start_reg) in TABLE_REGISTERS.items():
            poly, start, inverted = 0x1021 + 7 * w, 0xFFFF - w, w % 2
            await write(ctx, bank, offset(crc_reg), poly | (5 + w) << 16 | inverted << 24)
            await ctx.tick()
            await write(ctx, bank, offset(start_reg), start)
            await ctx.tick()
            written[w] = (poly, start, inverted)
        for w, value in written.items():
            assert await _table(ctx, bank, w) == _entry(*value), w
            crc_reg, start_reg = TABLE_REGISTERS[w]
            assert await read(ctx, bank, offset(crc_reg)) == (
                value[0] | (5 + w) << 16 | value[2] << 24)
            assert await read(ctx, bank, offset(start_reg)) == value[1]
            assert ctx.get(getattr(bank.ch0, f"cfg_w{w}_crc_width")) == 5 + w
        # One byte lane: only the polynomial's high byte changes.
        await write(ctx, bank, offset("cfg_w3_crc"), 0xAB00, strb=0b0010)
        await ctx.tick()
        poly, start, inverted = written[3]
        assert await _table(ctx, bank, 3) == _entry(0xAB00 | poly & 0xFF, start, inverted)
        assert await _table(ctx, bank, 4) == _entry(*written[4])
        # Busy core: the write waits, and the table keeps the old entry until it is idle.
        ctx.set(bank.cfg_free, 0)
        await write(ctx, bank, offset("cfg_crc0_start"), 0x1234)
        for _ in range(20):
            await ctx.tick()
            assert await _table(ctx, bank, 0) == _entry(*written[0])
        ctx.set(bank.cfg_free, 1)
        await ctx.tick()
        await ctx.tick()
        assert await _table(ctx, bank, 0) == _entry(written[0][0], 0x1234, written[0][2])
    run(bench, held=[set(TABLE) | {f"cfg_w{w}_crc_width" for w in range(8)}], tables=[TABLE])


def test_crc_table_is_cleared_after_a_reset():
    """A memory keeps its contents through a reset; the table must not: after a reset the bank
    writes every entry with its reset value (0), one per clock, holding the core in IDLE
    (cfg_hold) until then, and a write that comes meanwhile acts after it."""
    async def bench(ctx, bank, rst):
        ctx.set(bank.cfg_free, 1)
        for _ in range(10):
            await ctx.tick()
        await write(ctx, bank, offset("cfg_w7_crc_start"), 0xBEEF)
        await ctx.tick()
        assert await _table(ctx, bank, 7) == _entry(0, 0xBEEF, 0)
        ctx.set(rst, 1)
        await ctx.tick()
        ctx.set(rst, 0)
        # A write right after the reset: it waits for the clear.
        ctx.set(bank.bus.w_en, 1)
        ctx.set(bank.bus.w_addr, offset("cfg_crc1") // 4)
        ctx.set(bank.bus.w_data, 0x1_0007)
        ctx.set(bank.bus.w_strb, 0xF)
        holds = []
        for _ in range(14):
            await ctx.tick()
            ctx.set(bank.bus.w_en, 0)
            holds.append(ctx.get(bank.cfg_hold))
        assert holds[:8] == [1] * 8 and holds[-1] == 0, holds
        for w in range(8):
            want = _entry(0x0007, 0, 0) if w == 1 else 0
            assert await _table(ctx, bank, w) == want, w
        assert await read(ctx, bank, offset("cfg_w7_crc_start")) == 0
    _run_with_reset(bench, RegisterBank(MAP, 1, None, [set(TABLE)], [TABLE]))


@pytest.mark.filterwarnings("ignore::amaranth.hdl.UnusedElaboratable")
def test_crc_table_refuses_fields_it_cannot_hold():
    """A table field must be a held configuration signal of the map."""
    with pytest.raises(ValueError, match="held configuration"):
        RegisterBank(MAP, 1, None, [set()], [TABLE])
    with pytest.raises(ValueError, match="held configuration"):
        RegisterBank(MAP, 1, None, [{"nothing"}], [{"nothing": ("crc", 0, 0)}])
