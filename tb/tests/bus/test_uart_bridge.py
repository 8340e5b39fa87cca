"""The UART bridge on Amaranth's simulator: the 8N1 UART (rx/tx, rtl/bissmaster/bus/uart.py)
and the packet engine in front of the real register bank (rtl/bissmaster/bus/uart_bridge.py).

Expected values are written here from docs/uart_bridge.md: the framing, the statuses, the
CRC-8/AUTOSAR (this file's own bitwise CRC, checked against the catalogue's check value), the
timeouts in bit times. The line is driven and read by this file's own bit-level UART (levels
per system clock, any bit length, fractional ones too); register values come from the SystemRDL
source's field kinds, as in test_register_bank.py. Register-bus accesses are watched on the
bank's side (``w_en``, ``r_en``), so "no access" is checked, not assumed.
"""

import gc
import random
import warnings
from collections import deque

import pytest
from amaranth.hdl import ClockDomain, Module
from amaranth.lib import wiring
from amaranth.sim import Simulator

from bissmaster.bus import regmap
from bissmaster.bus.bus_top import BusTop
from bissmaster.bus.register_bank import RegisterBank
from bissmaster.bus.uart import UartRx, UartTx, divider
from bissmaster.bus import uart_bridge as bridge_mod
from bissmaster.bus.uart_bridge import UartBridge
from bissmaster.generate import main
from bissmaster.params import MasterParams
from testkit import REPO
from testkit.block_sim import refused

MAP = regmap.load()
SYS_HZ = 100_000_000

# -- The protocol, from docs/uart_bridge.md ----------------------------------------------------
SYNC_REQUEST, SYNC_RESPONSE = 0xA5, 0x5A
PING, READ, WRITE, READ_BURST = 0x0, 0x1, 0x2, 0x3
OK, BAD_CRC, BAD_COMMAND, BAD_ADDRESS = 0x00, 0x01, 0x02, 0x03
LEAD_BITS = 20          # quiet line before a request's SYNC


def crc8(data):
    """CRC-8/AUTOSAR: poly 0x2F, init 0xFF, no reflection, xorout 0xFF."""
    reg = 0xFF
    for byte in bytes(data):
        reg ^= byte
        for _ in range(8):
            reg = ((reg << 1) ^ 0x2F) & 0xFF if reg & 0x80 else (reg << 1) & 0xFF
    return reg ^ 0xFF


def test_own_crc_is_the_catalogue_crc8_autosar():
    assert crc8(b"123456789") == 0xDF


def request(op, address=None, value=None, count=None, tag=1):
    body = bytes([SYNC_REQUEST, tag << 4 | op])
    if address is not None:
        body += address.to_bytes(2, "little")
    if value is not None:
        body += value.to_bytes(4, "little")
    if count is not None:
        body += bytes([count])
    return body + bytes([crc8(body)])


def answer(cmd, status, words=()):
    body = bytes([SYNC_RESPONSE, cmd, status]) + b"".join(w.to_bytes(4, "little") for w in words)
    return body + bytes([crc8(body)])


def frame_bits(byte, stop=1):
    return [0] + [(byte >> i) & 1 for i in range(8)] + [stop]


def levels(bits, bit_clocks, phase=0.0):
    """The line level in each system clock for ``bits`` of ``bit_clocks`` clocks each (any
    real number), the first bit starting ``phase`` clocks before the first clock's edge."""
    total = len(bits) * bit_clocks
    return [bits[min(int((k + phase) / bit_clocks), len(bits) - 1)]
            for k in range(int(total - phase + 0.999))]


def channel_addr(path, ch=0):
    return MAP.channel_base + ch * MAP.channel_stride + next(
        r for r in MAP.channel if r.path == path).offset


def config_mask(path):
    reg = next(r for r in MAP.channel if r.path == path)
    return sum(((1 << f.width) - 1) << f.lsb for f in reg.fields
               if f.kind == regmap.Kind.CONFIG)


def doc_table(first_header):
    """The rows of the docs/uart_bridge.md table whose first header cell is ``first_header``."""
    lines = (REPO / "docs" / "uart_bridge.md").read_text().splitlines()
    split = lambda line: [c.strip().strip("`") for c in line.strip().strip("|").split("|")]
    for i, line in enumerate(lines):
        if line.startswith("|") and split(line)[0] == first_header:
            head = split(line)
            rows = []
            for row in lines[i + 2:]:
                if not row.startswith("|"):
                    break
                rows.append(dict(zip(head, split(row))))
            return rows
    raise AssertionError(f"docs/uart_bridge.md has no table headed {first_header!r}")


def test_this_files_protocol_and_the_rtls_are_the_documented_ones():
    """The RTL's constants (bus/uart_bridge.py) and this file's, against docs/uart_bridge.md
    (the host's copy: tb/tests/host/test_link.py)."""
    ops = {r["opcode"]: (int(r["code"], 16), int(r["request bytes"])) for r in doc_table("opcode")}
    assert ops == {"PING": (PING, 3), "READ": (READ, 5), "WRITE": (WRITE, 9),
                   "READ_BURST": (READ_BURST, 6)}
    assert {op.name: (op.value, n) for op, n in bridge_mod.REQUEST_LENGTH.items()} == ops
    assert {o.name for o in bridge_mod.Opcode} == set(ops)
    statuses = {r["status"]: int(r["code"], 16) for r in doc_table("status")}
    assert statuses == {"OK": OK, "BAD_CRC": BAD_CRC, "BAD_COMMAND": BAD_COMMAND,
                        "BAD_ADDRESS": BAD_ADDRESS}
    assert {s.name: s.value for s in bridge_mod.BridgeStatus} == statuses
    consts = {r["constant"]: r["value"] for r in doc_table("constant")}
    assert int(consts["SYNC_REQUEST"], 16) == SYNC_REQUEST == bridge_mod.SYNC_REQUEST
    assert int(consts["SYNC_RESPONSE"], 16) == SYNC_RESPONSE == bridge_mod.SYNC_RESPONSE
    crc = bridge_mod.CRC8
    assert (crc.crc_width, crc.polynomial, crc.initial_crc, crc.xor_output) == (
        8, int(consts["CRC polynomial"], 16), int(consts["CRC initial value"], 16),
        int(consts["CRC final XOR"], 16))
    assert not crc.reflect_input and not crc.reflect_output and consts["CRC reflected"] == "no"
    assert crc().compute(b"123456789") == int(consts["CRC check"], 16) == crc8(b"123456789")
    assert int(consts["lead"].split()[0]) == LEAD_BITS == bridge_mod.LEAD_BITS
    assert int(consts["inter-byte timeout"].split()[0]) == bridge_mod.DEFAULT_TIMEOUT_BITS


# -- The divider --------------------------------------------------------------------------------

@pytest.mark.parametrize("clk, baud, div", [
    (100_000_000, 115_200, 868), (100_000_000, 3_000_000, 33), (48_000_000, 3_000_000, 16),
    (50_000_000, 3_000_000, 17), (16_000_000, 4_000_000, 4), (12_000_000, 9600, 1250),
])
def test_divider(clk, baud, div):
    assert divider(clk, baud) == div


@pytest.mark.parametrize("clk, baud, message", [
    (10_000_000, 3_000_000, "less than 4"),                 # 3.33 clocks per bit
    (100_000_000, 30_000_000, "less than 4"),
    (20_000_000, 3_000_000, r"4\.8 % off"),                 # 7 clocks: 2.857 Mbaud
    (100_000_000, 0, "baud must be a positive integer"),
    (100_000_000, 115_200.0, "baud must be a positive integer"),
])
def test_divider_refused(clk, baud, message):
    with pytest.raises(ValueError, match=message):
        divider(clk, baud)



def test_bad_bridge_parameters_are_refused(capsys):
    refused(lambda: UartBridge(13, sys_clk_hz=SYS_HZ, baud=115_200, timeout_bits=0),
            "timeout_bits must be an integer from 1")
    refused(lambda: BusTop("uart", 1, MasterParams(), baud=40_000_000), "less than 4")
    refused(lambda: BusTop("axil", 1, baud=115_200), "has no option 'baud'")
    refused(lambda: BusTop("uart", 2, [MasterParams(), MasterParams(sys_clk_hz=50_000_000)]),
            "share one clock")
    with warnings.catch_warnings():     # the refused BusTop inside the command is never used
        warnings.filterwarnings("ignore", message=".*created but never used")
        with pytest.raises(SystemExit):
            main(["--top", "uart", "--baud", "1000000", "--sys-clk-hz", "3000000",
                  "-o", "/dev/null"])
        gc.collect()
    assert "less than 4" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--top", "axil", "--baud", "115200", "-o", "/dev/null"])
    assert "--baud applies to --top uart, not --top axil" in capsys.readouterr().err


# -- The UART alone ------------------------------------------------------------------------------

def _simulate(dut, bench):
    top = Module()
    top.domains.sync = ClockDomain()
    top.submodules.dut = dut
    sim = Simulator(top)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()


@pytest.mark.parametrize("div", [4, 7])
def test_tx_sends_8n1_at_the_divider_back_to_back(div):
    """Each byte: a start bit, 8 data bits LSB first, a stop bit, ``div`` clocks each, from the
    clock after it is taken; the next byte, offered at once, follows without a gap."""
    data = [0x55, 0x00, 0xFF, 0xA5, 0x3C]
    trace, taken = [], []

    async def bench(ctx):
        dut = tx
        queue = deque(data)
        for clock in range(10 * div * len(data) + 3 * div):
            ctx.set(dut.valid, bool(queue))
            ctx.set(dut.data, queue[0] if queue else 0)
            trace.append(ctx.get(dut.tx))
            if queue and ctx.get(dut.ready):
                taken.append(clock)
                queue.popleft()
            await ctx.tick()

    tx = UartTx(div)
    _simulate(tx, bench)
    assert taken == [10 * div * i for i in range(len(data))]
    expected = [1] + [lvl for b in data for bit in frame_bits(b) for lvl in [bit] * div]
    assert trace[:len(expected)] == expected
    assert set(trace[len(expected):]) == {1}


def _receive(div, line):
    """Drive UartRx with ``line`` (a level per clock); returns [(kind, data)] per byte end."""
    got = []

    async def bench(ctx):
        for level in line + [1] * (3 * div):
            ctx.set(rx.rx, level)
            if ctx.get(rx.valid):
                got.append(("byte", ctx.get(rx.data)))
            if ctx.get(rx.frame_error):
                got.append(("frame_error", ctx.get(rx.data)))
            await ctx.tick()

    rx = UartRx(div)
    _simulate(rx, bench)
    return got


@pytest.mark.parametrize("div", [4, 7, 16])
@pytest.mark.parametrize("rate", [1.0, 0.98, 1.02])
def test_rx_takes_bytes_at_the_baud_and_2_percent_off(div, rate):
    """Bytes back to back from a sender whose bit is ``div / rate`` clocks (2 % slow or fast),
    at a random phase to the clock."""
    rng = random.Random(div * 100 + int(rate * 100))
    data = [0x00, 0xFF, 0x55, 0xAA, 0x01, 0x80, 0xA5] + [rng.getrandbits(8) for _ in range(9)]
    bits = [1, 1] + [b for byte in data for b in frame_bits(byte)] + [1, 1]
    got = _receive(div, levels(bits, div / rate, phase=rng.random()))
    assert got == [("byte", b) for b in data]


def test_rx_framing_error_and_a_held_low_line():
    """A 0 stop bit: one frame_error (no byte); a line held low for 30 bit times afterwards
    gives no more; once it is high again, the next byte is taken."""
    div = 8
    bits = [1, 1] + frame_bits(0x5A, stop=0) + [0] * 30 + [1] * 3 + frame_bits(0x3C) + [1]
    assert _receive(div, levels(bits, div)) == [("frame_error", 0x5A), ("byte", 0x3C)]


def test_rx_a_glitch_is_not_a_start_bit():
    div = 8
    line = [1] * 10 + [0] * 2 + [1] * 30 + levels([1] + frame_bits(0x81) + [1], div)
    assert _receive(div, line) == [("byte", 0x81)]


# -- The bridge in front of the register bank ---------------------------------------------------

class Bench:
    """The host's end of the line, one system clock at a time: what to send (levels queued),
    the bytes the bridge sent (with the clock their start bit began), the bus accesses."""

    def __init__(self, ctx, bridge, div):
        self.ctx, self.bridge, self.div = ctx, bridge, div
        self.clock = 0
        self.line = deque()
        self.received = []              # (clock of the start bit, byte)
        self.accesses = []              # ("w", byte address, data, strobes) / ("r", address)
        self.sent_end = 0               # the clock after the last level queued
        self._rx_start = None
        self._samples = []

    # What goes onto the bridge's rx.
    def send(self, data, *, gap_bits=0, stop=None):
        """Queue ``data`` (bytes) at the baud, ``gap_bits`` of idle line between bytes; ``stop``:
        {byte index: stop bit level} to break some."""
        for i, byte in enumerate(data):
            stop_bit = (stop or {}).get(i, 1)
            self.line.extend(levels(frame_bits(byte, stop_bit), self.div))
            if not stop_bit:        # a stop bit 0 (not a break): the line is high after it
                self.line.extend([1] * 2 * self.div)
            if gap_bits and i != len(data) - 1:
                self.line.extend([1] * gap_bits * self.div)

    def idle(self, bits):
        self.line.extend([1] * int(bits * self.div))

    async def step(self):
        ctx, regs = self.ctx, self.bridge.regs
        level = self.line.popleft() if self.line else 1
        ctx.set(self.bridge.uart.rx, level)
        self._decode(ctx.get(self.bridge.uart.tx))
        if ctx.get(regs.w_en):
            self.accesses.append(("w", ctx.get(regs.w_addr) * 4, ctx.get(regs.w_data),
                                  ctx.get(regs.w_strb)))
        if ctx.get(regs.r_en):
            self.accesses.append(("r", ctx.get(regs.r_addr) * 4))
        await ctx.tick()
        self.clock += 1

    def _decode(self, tx):
        if self._rx_start is None:
            if tx == 0:
                self._rx_start, self._samples = self.clock, []
            return
        offset = self.clock - self._rx_start
        if offset % self.div == self.div // 2 and offset > self.div:
            self._samples.append(tx)
            if len(self._samples) == 9:
                assert self._samples[8] == 1, "a stop bit of the bridge's tx is 0"
                self.received.append((self._rx_start,
                                      sum(b << i for i, b in enumerate(self._samples[:8]))))
                self._rx_start = None

    async def run(self, clocks):
        for _ in range(clocks):
            await self.step()

    async def flush(self):
        """Run until everything queued is on the line."""
        while self.line:
            await self.step()

    async def transact(self, data, answer_bytes, *, limit_bits=100, **send):
        """Send ``data``, then run until ``answer_bytes`` more bytes came back (or ``limit_bits``
        and their ten bit times each after the request); returns them."""
        before = len(self.received)
        self.send(data, **send)
        await self.flush()
        for _ in range((limit_bits + 10 * answer_bytes) * self.div):
            if len(self.received) - before >= answer_bytes and self._rx_start is None:
                break
            await self.step()
        return bytes(b for _, b in self.received[before:])


def run_bridge(test, *, div=4, timeout_bits=40):
    """``test(bench)`` against a UartBridge (``div`` clocks per bit) in front of one channel's
    register bank."""
    top = Module()
    top.domains.sync = ClockDomain()
    top.submodules.bank = bank = RegisterBank(MAP, 1)
    top.submodules.bridge = bridge = UartBridge(MAP.addr_width, sys_clk_hz=SYS_HZ,
                                                baud=SYS_HZ // div, timeout_bits=timeout_bits)
    assert bridge.divider == div
    wiring.connect(top, bridge.regs, bank.bus)
    sim = Simulator(top)
    sim.add_clock(1e-8)

    async def bench(ctx):
        b = Bench(ctx, bridge, div)
        b.idle(LEAD_BITS + 5)
        await test(b)
    sim.add_testbench(bench)
    sim.run()


ID = next(r for r in MAP.globals if r.path == "id")
ID_VALUE = sum(f.reset << f.lsb for f in ID.fields)


@pytest.mark.parametrize("div", [4, 9])
def test_write_read_round_trip(div):
    """A WRITE of a channel's configuration register is answered OK and reads back (its
    configuration bits); a READ of the constant ``id`` gives the map's value."""
    cfg = channel_addr("cfg_words")

    async def test(b):
        assert await b.transact(request(WRITE, cfg, 0xDEADBEEF, tag=3), 4) \
            == answer(0x32, OK)
        assert await b.transact(request(READ, cfg, tag=4), 8) \
            == answer(0x41, OK, [0xDEADBEEF & config_mask("cfg_words")])
        assert await b.transact(request(READ, ID.offset, tag=5), 8) \
            == answer(0x51, OK, [ID_VALUE])
        assert b.accesses == [("w", cfg, 0xDEADBEEF, 0xF), ("r", cfg), ("r", ID.offset)]
    run_bridge(test, div=div)


def test_every_command():
    """PING: OK, no access. READ: one read. WRITE: one write of all four lanes. READ_BURST: the
    words in address order, four bytes each, in one answer."""
    result = channel_addr("result.status")
    cfg = [channel_addr(p) for p in ("cfg_ma", "cfg_period", "cfg_break")]

    async def test(b):
        assert await b.transact(request(PING, tag=0), 4) == answer(0x00, OK)
        assert b.accesses == []
        values = [0x12345678, 0x00ABCDEF, 0x0000FFFF]
        for tag, (addr, value) in enumerate(zip(cfg, values), 1):
            assert await b.transact(request(WRITE, addr, value, tag=tag), 4) \
                == answer(tag << 4 | WRITE, OK)
        expected = [v & config_mask(p) for v, p in zip(values, ("cfg_ma", "cfg_period",
                                                                 "cfg_break"))]
        assert await b.transact(request(READ_BURST, cfg[0], count=3, tag=7), 16) \
            == answer(0x73, OK, expected)
        assert await b.transact(request(READ, cfg[2], tag=8), 8) == answer(0x81, OK, expected[2:])
        got = await b.transact(request(READ_BURST, result, count=7, tag=9), 32)
        assert got == answer(0x93, OK, [0] * 7)
        assert b.accesses == (
            [("w", a, v, 0xF) for a, v in zip(cfg, values)]
            + [("r", a) for a in cfg] + [("r", cfg[2])]
            + [("r", result + 4 * i) for i in range(7)])
    run_bridge(test)


def test_a_burst_answer_is_one_byte_stream():
    """The words of a burst follow each other on the line without a gap: one byte per ten bit
    times from the SYNC to the CRC."""
    async def test(b):
        before = len(b.received)
        await b.transact(request(READ_BURST, channel_addr("cfg_ma"), count=5), 24)
        starts = [c for c, _ in b.received[before:]]
        assert [t - starts[0] for t in starts] == [10 * b.div * i for i in range(24)]
    run_bridge(test)


def test_bad_crc_is_answered_and_accesses_nothing():
    """Every bit of a WRITE or READ request flipped (but in SYNC, which then is no request):
    BAD_CRC, no access. A good request works afterwards."""
    cfg = channel_addr("cfg_checks")

    async def test(b):
        rng = random.Random(5)
        for good in (request(WRITE, cfg, 0x11223344, tag=2), request(READ, cfg, tag=2)):
            for i in range(1, len(good)):
                bad = bytearray(good)
                bad[i] ^= 1 << rng.randrange(8)
                got = await b.transact(bytes(bad), 4)
                assert got == answer(bad[1], BAD_CRC), (i, got)
                b.idle(LEAD_BITS)
        assert b.accesses == []
        assert await b.transact(request(WRITE, cfg, 1, tag=3), 4) == answer(0x32, OK)
        assert b.accesses == [("w", cfg, 1, 0xF)]
    run_bridge(test)


def test_a_framing_error_in_a_request_is_bad_crc():
    """A byte with a 0 stop bit counts as a byte and spoils the request (its CRC may be right)."""
    cfg = channel_addr("cfg_checks")

    async def test(b):
        for i in (1, 4, 8):
            got = await b.transact(request(WRITE, cfg, 0x5, tag=6), 4, stop={i: 0})
            assert got == answer(0x62, BAD_CRC), i
            b.idle(LEAD_BITS)
        assert b.accesses == []
    run_bridge(test)


def test_unknown_opcode_is_bad_command_once_the_line_is_quiet():
    """Its length unknown, the bytes after an unknown opcode are dropped until the inter-byte
    timeout; then BAD_COMMAND, with the command byte echoed. A burst of 0 words: BAD_COMMAND at
    once. No access either way."""
    timeout_bits = 40

    async def test(b):
        bad = bytes([SYNC_REQUEST, 0x57, 0x20, 0x02, 1, 2, 3, 4])
        got = await b.transact(bad + bytes([crc8(bad)]), 4, limit_bits=200)
        assert got == answer(0x57, BAD_COMMAND)
        b.idle(LEAD_BITS)
        got = await b.transact(request(READ_BURST, channel_addr("cfg_ma"), count=0, tag=2), 4)
        assert got == answer(0x23, BAD_COMMAND)
        assert b.accesses == []
    run_bridge(test, timeout_bits=timeout_bits)


def test_unknown_opcode_answer_waits_for_the_timeout_exactly():
    """The BAD_COMMAND answer's start bit begins ``timeout_bits`` (quiet line after the last
    byte's stop bit) later, to within a bit."""
    timeout_bits = 30

    async def test(b):
        b.send(bytes([SYNC_REQUEST, 0x0F, 0x00]))
        await b.flush()
        end = b.clock                                # the last stop bit has just ended
        await b.run((timeout_bits + 50) * b.div)
        starts = [c for c, _ in b.received]
        assert len(starts) == 4
        assert abs((starts[0] - end) - timeout_bits * b.div) <= b.div
    run_bridge(test, div=8, timeout_bits=timeout_bits)


@pytest.mark.parametrize("div", [4, 33])
def test_the_answer_follows_the_request_by_six_clocks(div):
    """docs/uart_bridge.md, rule 5: the answer's start bit begins about 6 system clocks after
    the middle of the request's last stop bit (synchronizer, byte end, check, first byte)."""
    async def test(b):
        b.send(request(READ, ID.offset, tag=1))
        await b.flush()
        middle = b.clock - b.div / 2                 # the last stop bit's middle
        await b.run(90 * b.div)
        assert 5 <= b.received[0][0] - middle <= 6.5
    run_bridge(test, div=div)


@pytest.mark.parametrize("address, count", [
    (0x222, None), (0x2000, None), (0xFFFC, None), (0x1FF8, 3), (0x0002, 1),
])
def test_bad_address(address, count):
    """Not a multiple of 4, or a word beyond the 13-bit byte address space of the register map
    (0x2000 up): BAD_ADDRESS, no access, for READ, WRITE and READ_BURST."""
    async def test(b):
        if count is None:
            assert await b.transact(request(READ, address, tag=1), 4) == answer(0x11, BAD_ADDRESS)
            b.idle(LEAD_BITS)
            assert await b.transact(request(WRITE, address, 7, tag=2), 4) \
                == answer(0x22, BAD_ADDRESS)
        else:
            assert await b.transact(request(READ_BURST, address, count=count, tag=1), 4) \
                == answer(0x13, BAD_ADDRESS)
        assert b.accesses == []
    run_bridge(test)


def test_the_last_words_of_the_address_space_are_reachable():
    async def test(b):
        got = await b.transact(request(READ_BURST, 0x1FF8, count=2, tag=1), 12)
        assert got == answer(0x13, OK, [0, 0])
        assert await b.transact(request(WRITE, 0x1FFC, 9, tag=2), 4) == answer(0x22, OK)
        assert b.accesses == [("r", 0x1FF8), ("r", 0x1FFC), ("w", 0x1FFC, 9, 0xF)]
    run_bridge(test)


def test_truncated_request_is_dropped_after_the_timeout_and_the_next_works():
    timeout_bits = 40
    cfg = channel_addr("cfg_period")

    async def test(b):
        got = await b.transact(request(WRITE, cfg, 0x1234, tag=1)[:6], 1,
                               limit_bits=timeout_bits + 30)
        assert got == b"" and b.accesses == []
        assert await b.transact(request(WRITE, cfg, 0x77, tag=2), 4) == answer(0x22, OK)
        assert await b.transact(request(READ, cfg, tag=3), 8) == answer(0x31, OK, [0x77])
        assert b.accesses == [("w", cfg, 0x77, 0xF), ("r", cfg)]
    run_bridge(test, timeout_bits=timeout_bits)


def test_gaps_inside_a_request_up_to_the_timeout():
    """Quiet line between the bytes of a request: ``timeout_bits - 2`` is waited for; with
    ``timeout_bits + 2`` the request is dropped at the first gap (no answer, no access), and
    its rest, preceded by no quiet line, starts nothing."""
    timeout_bits = 40
    cfg = channel_addr("cfg_period")

    async def test(b):
        got = await b.transact(request(WRITE, cfg, 0x42, tag=1), 4, gap_bits=timeout_bits - 2)
        assert got == answer(0x12, OK)
        b.idle(LEAD_BITS)
        got = await b.transact(request(WRITE, cfg, 0x43, tag=2), 1, gap_bits=timeout_bits + 2,
                               limit_bits=timeout_bits + 30)
        assert got == b""
        assert b.accesses == [("w", cfg, 0x42, 0xF)]
    run_bridge(test, timeout_bits=timeout_bits)


def test_back_to_back_requests():
    """Each request starts the moment the answer to the one before has ended (the fastest a
    host can go); every one is answered."""
    cfg = channel_addr("cfg_ack")

    async def test(b):
        for tag in range(12):
            op = (WRITE, READ, PING)[tag % 3]
            req = request(op, cfg if op != PING else None, tag if op == WRITE else None, tag=tag)
            want = answer(tag << 4 | op, OK, [tag - 1] if op == READ else [])
            assert await b.transact(req, len(want), limit_bits=150) == want, tag
        assert len(b.accesses) == 8
    run_bridge(test)


def test_a_sync_inside_a_byte_stream_starts_no_request():
    """A request sent while the answer to the one before is on the line is ignored (no access,
    no answer), also when its bytes hold a whole valid request (here a WRITE's data holds a
    PING, whose SYNC arrives after the PING before it has been answered, the engine idle): a
    request's SYNC counts only after quiet line. The next one after quiet works."""
    cfg = channel_addr("cfg_ack")
    inner = int.from_bytes(request(PING, tag=9) + b"\0", "little")

    async def test(b):
        b.send(request(PING, tag=1) + request(WRITE, cfg, inner, tag=2))
        await b.run(400 * b.div)
        got = bytes(x for _, x in b.received)
        assert got == answer(0x10, OK)
        assert b.accesses == []
        assert await b.transact(request(WRITE, cfg, 5, tag=3), 4) == answer(0x32, OK)
    run_bridge(test)


def test_a_repeated_write_is_answered_but_not_written_again():
    """A WRITE equal to the last good request (tag, address, data), itself an OK WRITE, is a
    retry: answered OK, not written. A BAD_CRC request in between does not end that memory; a
    READ, a PING, or another tag does."""
    cfg = channel_addr("cfg_timeout")
    irq = channel_addr("irq_status")

    async def test(b):
        w = request(WRITE, cfg, 0x100, tag=4)

        async def do(req, status=OK, n=4):
            got = await b.transact(req, n)
            b.idle(LEAD_BITS)
            assert got[2] == status, got
            return got

        await do(w)
        await do(w)                                             # the retry: not written
        bad = bytearray(w)
        bad[5] ^= 0x10
        await do(bytes(bad), BAD_CRC)
        await do(w)                                             # still the same retry
        assert b.accesses == [("w", cfg, 0x100, 0xF)]
        await do(request(READ, cfg, tag=5), n=8)
        await do(w)                                             # after a read: a new write
        await do(request(PING, tag=6))
        await do(w)
        await do(request(WRITE, cfg, 0x100, tag=7))             # another tag: a new write
        await do(request(WRITE, irq, 1, tag=8))                 # write-1-to-clear, retried:
        await do(request(WRITE, irq, 1, tag=8))                 # acts once
        assert b.accesses == [("w", cfg, 0x100, 0xF), ("r", cfg), ("w", cfg, 0x100, 0xF),
                              ("w", cfg, 0x100, 0xF), ("w", cfg, 0x100, 0xF),
                              ("w", irq, 1, 0xF)]
    run_bridge(test)


def test_noise_before_a_request_is_ignored():
    """Bytes that are not a SYNC after quiet line (noise, a framing error) start nothing."""
    async def test(b):
        b.send(bytes([0x00, 0xFF, 0x13]))
        b.send(bytes([0x42]), stop={0: 0})
        b.idle(LEAD_BITS + 2)
        assert await b.transact(request(READ, ID.offset, tag=1), 8) == answer(0x11, OK, [ID_VALUE])
    run_bridge(test)
