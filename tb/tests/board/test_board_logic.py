"""A board design's logic in the Amaranth simulator, at the board's own clock and baud rate
(iCEBreaker: 24 MHz, 115200 baud, 208 clocks per bit): it answers a PING and a READ of the
register map's ``id`` over its UART pins, byte for byte as docs/uart_bridge.md frames them, and
its transceiver enables are off in reset and on after it; with a faster UART, its status LEDs
follow a frame from an encoder and a cycle without one, and the host tool ``bissmaster`` itself
configures it and reads positions and counters over its UART pins. Everything of the board but
the PLL and the I/O buffers (tb/tests/board/test_board_designs.py elaborates those)."""

import pytest
from amaranth.hdl import ClockDomain, Module
from amaranth.sim import Simulator

from bissmaster.boards import BOARDS, BoardLogic
from bissmaster.boards.logic import PulseStretcher, heartbeat_half_clocks, led_hold_clocks
from bissmaster.bus import regmap
from bissmaster.host.link import crc8, encode_request
from master_contract import CRC_CODE
from testkit.limits_bench import FRAME, Encoder

MAP = regmap.load()
ID = next(r for r in MAP.globals if r.path == "id")
ID_VALUE = sum(f.reset << f.lsb for f in ID.fields)
ID_ADDRESS = ID.offset          # a global register: its offset is its byte address


def uart_levels(data, div):
    """8N1 line levels, one per clock, ``div`` clocks per bit."""
    out = []
    for byte in data:
        for bit in [0] + [(byte >> i) & 1 for i in range(8)] + [1]:
            out += [bit] * div
    return out


class Line:
    """Receives the design's ``uart_tx``: samples each bit in its middle."""

    def __init__(self, div):
        self.div, self.start, self.bits, self.bytes, self.clock = div, None, [], [], 0

    def sample(self, level):
        if self.start is None:
            if level == 0:
                self.start, self.bits = self.clock, []
        else:
            offset = self.clock - self.start
            if offset % self.div == self.div // 2 and offset > self.div:
                self.bits.append(level)
                if len(self.bits) == 9:
                    assert self.bits[8] == 1, "stop bit 0"
                    self.bytes.append(sum(b << i for i, b in enumerate(self.bits[:8])))
                    self.start = None
        self.clock += 1


@pytest.fixture(scope="module")
def icebreaker_session():
    """One simulation of the iCEBreaker's logic: reset, a PING, a READ of ``id``; what the
    design answered and the enables it showed."""
    board = BOARDS["icebreaker"]
    logic = board.logic()
    div = round(board.sys_clk_hz / board.baud)
    m = Module()
    m.domains.sync = sync = ClockDomain()
    m.submodules.logic = logic
    sim = Simulator(m)
    sim.add_clock(1 / board.sys_clk_hz)
    seen = {"div": div, "answers": []}

    async def bench(ctx):
        line = Line(div)
        ctx.set(sync.rst, 1)
        for _ in range(3):
            await ctx.tick()
        seen["enables_in_reset"] = (ctx.get(logic.ch0_de), ctx.get(logic.ch0_re))
        ctx.set(sync.rst, 0)
        for _ in range(3):
            await ctx.tick()
        seen["enables_running"] = (ctx.get(logic.ch0_de), ctx.get(logic.ch0_re))
        seen["ma_idle"] = ctx.get(logic.ch0_ma)
        for request, length in ((encode_request("PING", 3), 4),
                                (encode_request("READ", 4, ID_ADDRESS), 8)):
            before = len(line.bytes)
            for level in [1] * 25 * div + uart_levels(request, div):
                ctx.set(logic.uart_rx, level)
                line.sample(ctx.get(logic.uart_tx))
                await ctx.tick()
            for _ in range(12 * length * div):
                line.sample(ctx.get(logic.uart_tx))
                await ctx.tick()
                if len(line.bytes) - before == length and line.start is None:
                    break
            seen["answers"].append(bytes(line.bytes[before:]))

    sim.add_testbench(bench)
    sim.run()
    return seen


def test_board_answers_ping_over_its_uart_pins(icebreaker_session):
    answer = icebreaker_session["answers"][0]
    body = bytes([0x5A, 3 << 4 | 0x0, 0x00])          # SYNC_RESPONSE, tag 3 PING, OK
    assert answer == body + bytes([crc8(body)])


def test_board_reads_the_register_map_id(icebreaker_session):
    answer = icebreaker_session["answers"][1]
    body = bytes([0x5A, 4 << 4 | 0x1, 0x00]) + ID_VALUE.to_bytes(4, "little")
    assert ID_VALUE != 0
    assert answer == body + bytes([crc8(body)])


def test_transceiver_enabled_only_out_of_reset(icebreaker_session):
    assert icebreaker_session["enables_in_reset"] == (0, 0)
    assert icebreaker_session["enables_running"] == (1, 1)
    assert icebreaker_session["ma_idle"] == 1


def test_led_stretcher_holds_for_its_clocks():
    m = Module()
    m.domains.sync = ClockDomain()
    m.submodules.s = s = PulseStretcher(5)
    sim = Simulator(m)
    sim.add_clock(1e-8)
    trace = []

    async def bench(ctx):
        ctx.set(s.i, 1)
        await ctx.tick()
        ctx.set(s.i, 0)
        for _ in range(8):
            trace.append(ctx.get(s.o))
            await ctx.tick()
    sim.add_testbench(bench)
    sim.run()
    assert trace == [1] * 5 + [0] * 3


def test_led_times_at_the_board_clock():
    assert BOARDS["ulx3s-85f"].sys_clk_hz == 80_000_000
    assert led_hold_clocks(80_000_000) == 4_000_000           # 50 ms
    assert heartbeat_half_clocks(80_000_000) == 40_000_000    # 0.5 s
    assert heartbeat_half_clocks(24_000_000) == 12_000_000


# -- The status LEDs against frames -------------------------------------------------------------

def _field(path, name, value):
    reg = next(r for r in MAP.channel if r.path == path)
    return value << reg.field(name).lsb


def _channel_address(path):
    return MAP.channel_address(0, next(r for r in MAP.channel if r.path == path))


def icebreaker_logic(div=4):
    """The iCEBreaker's logic (its clock and core) in a simulator, the UART at ``div`` clocks per
    bit: ``(board, div, logic, sim)``."""
    board = BOARDS["icebreaker"]
    logic = BoardLogic(len(board.channels), board.params, baud=board.sys_clk_hz // div)
    m = Module()
    m.domains.sync = ClockDomain()
    m.submodules.logic = logic
    sim = Simulator(m)
    sim.add_clock(1 / board.sys_clk_hz)
    return board, div, logic, sim


def test_leds_follow_the_frames():
    """The iCEBreaker's logic (its clock and core), the UART at 4 clocks per bit to keep the run
    short: configured over the UART for a 4-bit BiSS C word with nE/nW and CRC-6, a cycle with
    an encoder (limits_bench.Encoder, frame bits from the independent encoder model) lights the
    valid LED and not the fault LED; a cycle with no encoder (SLO idle high) then lights the
    fault LED. Every register access is answered OK."""
    board, div, logic, sim = icebreaker_logic()
    hp = 4
    encoder = Encoder(hp=hp, bits=FRAME)
    seen = {}

    async def bench(ctx):
        line = Line(div)

        async def step():
            ctx.set(logic.ch0_slo, encoder.step(ctx.get(logic.ch0_ma)))
            line.sample(ctx.get(logic.uart_tx))
            await ctx.tick()

        async def write(tag, address, value):
            before = len(line.bytes)
            for level in [1] * 25 * div + uart_levels(encode_request("WRITE", tag, address, value), div):
                ctx.set(logic.uart_rx, level)
                await step()
            # The answer: a configuration write waits for the core to be idle (the break
            # after reset, 40 us; docs/bus.md, "Configuration writes").
            for _ in range(60 * div + 1000):
                await step()
                if len(line.bytes) - before == 4:
                    break
            body = bytes([0x5A, tag << 4 | 0x2, 0x00])
            assert bytes(line.bytes[before:]) == body + bytes([crc8(body)]), hex(address)

        async def cycle():
            for _ in range(2000):
                await step()

        await write(1, _channel_address("cfg_ma"), _field("cfg_ma", "ma_half_period", hp))
        await write(2, _channel_address("cfg_words"),
                    _field("cfg_words", "w0_data_bits", 4) | _field("cfg_words", "w0_nenw", 1)
                    | _field("cfg_words", "w0_crc", CRC_CODE["crc6"]))
        await write(3, _channel_address("ctrl"), _field("ctrl", "start", 1))
        await cycle()
        seen["after_frame"] = (ctx.get(logic.ch0_valid_led), ctx.get(logic.ch0_fault_led))
        encoder.present = False
        await write(4, _channel_address("ctrl"), _field("ctrl", "start", 1))
        await cycle()
        seen["after_no_encoder"] = (ctx.get(logic.ch0_valid_led), ctx.get(logic.ch0_fault_led))

    sim.add_testbench(bench)
    sim.run()
    assert seen["after_frame"] == (1, 0)
    assert seen["after_no_encoder"] == (1, 1)      # valid still held from the first frame


# -- The host tool on the board's logic -------------------------------------------------------

class LockstepTransport:
    """``bissmaster``'s transport into an Amaranth simulation of a board's logic: the tool runs in
    a thread of its own and each of its calls (``write``, ``read``, ``sleep``) is done by the
    simulation's testbench, clock by clock, while the tool waits; between calls simulated time
    stands still. ``now`` is simulated time, so the link's deadlines and the tool's sample rate
    are the simulation's, as on a board they are the computer's."""

    def __init__(self, sys_clk_hz):
        import queue
        self.sys_clk_hz = sys_clk_hz
        self.clocks = 0
        self.calls, self.replies = queue.Queue(), queue.Queue()

    def _call(self, *call):
        self.calls.put(call)
        return self.replies.get()

    def now(self):
        return self.clocks / self.sys_clk_hz

    def write(self, data):
        self._call("write", bytes(data))

    def read(self, n, timeout):
        return self._call("read", n, timeout)

    def sleep(self, seconds):
        self._call("sleep", seconds)


def test_host_tool_configures_and_reads_the_board():
    """The host tool itself (bissmaster.host.cli.main) on the iCEBreaker's logic (its core: the
    ``bp3`` preset with the board's overrides, 24 MHz; the UART at 4 clocks per bit, 6 Mbaud,
    to keep the run short) over its UART pins, against the limits bench's encoder (a 4-bit
    BiSS C word with nE/nW and CRC-6 from the independent encoder model): `config --preset
    biss-c-4 --ma-hz 3e6` (MA half period 4 at 24 MHz), `read` prints the encoder's position
    with OK and lights the valid LED, `counters` are all 0; unplugged, `read` exits 6 with
    NO_ACK and `counters` counts it. Every exit code as docs/bench.md gives it."""
    import io
    import threading

    from bissmaster.host import cli
    from testkit.limits_bench import POSITION

    board, div, logic, sim = icebreaker_logic()
    encoder = Encoder(hp=4, bits=FRAME)
    transport = LockstepTransport(board.sys_clk_hz)
    common = ["--baud", str(board.sys_clk_hz // div), "--clock-hz", str(board.sys_clk_hz),
              "--latency", "2e-6"]
    runs = []

    def unplug():
        encoder.present = False
    steps = [["config", "--preset", "biss-c-4", "--ma-hz", "3e6"],
             ["read", "--count", "2", "--rate", "20000"],
             ["counters"], unplug,
             ["read", "--count", "2", "--rate", "20000"],
             ["counters"]]

    def host():
        try:
            for step in steps:
                if callable(step):
                    step()          # (the simulation waits for the tool's next call)
                    continue
                out, err = io.StringIO(), io.StringIO()
                code = cli.main(step + common, transport=transport, stdout=out, stderr=err)
                runs.append((step[0], code, out.getvalue(), err.getvalue()))
        finally:
            transport.calls.put(("done",))

    leds = []

    async def bench(ctx):
        line = Line(div)
        received = bytearray()

        async def tick():
            ctx.set(logic.ch0_slo, encoder.step(ctx.get(logic.ch0_ma)))
            line.sample(ctx.get(logic.uart_tx))
            if line.bytes:
                received.extend(line.bytes)
                line.bytes.clear()
            await ctx.tick()
            transport.clocks += 1

        for _ in range(4):
            await tick()
        thread = threading.Thread(target=host, daemon=True)
        thread.start()
        while True:
            call = transport.calls.get(timeout=600)
            if call[0] == "done":
                break
            if call[0] == "write":
                for level in uart_levels(call[1], div):
                    ctx.set(logic.uart_rx, level)
                    await tick()
                reply = None
            elif call[0] == "sleep":
                for _ in range(max(round(call[1] * board.sys_clk_hz), 0)):
                    await tick()
                reply = None
            else:
                n, timeout = call[1], call[2]
                deadline = transport.clocks + round(timeout * board.sys_clk_hz)
                while len(received) < n and transport.clocks < deadline:
                    await tick()
                reply, received[:] = bytes(received[:n]), received[n:]
            leds.append(ctx.get(logic.ch0_valid_led))
            transport.replies.put(reply)
        thread.join(timeout=60)

    sim.add_testbench(bench)
    sim.run()

    (config, c0, _, e0), (read, c1, out1, e1), (_, c2, out2, e2), \
        (_, c3, out3, e3), (_, c4, out4, e4) = runs
    assert c0 == 0, e0
    assert c1 == 0, e1
    rows = [line.split() for line in out1.splitlines()[1:]]
    assert [(r[3], int(r[4]), r[5], r[6], r[7]) for r in rows] == \
        [("OK", POSITION, "1", "1", "ok")] * 2, out1
    # the round trip in clocks, and in ns at the board's clock, one decimal (41.7 ns a clock)
    assert all(r[9] == f"{int(r[8]) * 1e9 / board.sys_clk_hz:.1f}" for r in rows), out1
    assert [r[2] for r in rows] == ["1", "2"], "one cycle per sample"
    assert 1 in leds, "the valid LED lit"
    counts = {l.split()[0]: int(l.split()[1]) for l in out2.splitlines()[1:]}
    assert c2 == 0 and counts and not any(counts.values()), out2
    assert c3 == 6 and "NO_ACK 2" in e3 and "does not answer" in e3, (c3, e3)
    counts = {l.split()[0]: int(l.split()[1]) for l in out4.splitlines()[1:]}
    assert c4 == 0 and counts["no_ack"] == 2 and sum(counts.values()) == 2, out4
