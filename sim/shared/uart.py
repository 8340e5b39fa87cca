"""The host's end of ``biss_master_uart``'s serial line in cocotb: a UART model, and the bus
the bus scenarios use on it, which is the host software itself (``bissmaster.host.link.Link``)
over a transport bridged into the simulation.

:class:`UartLine` drives ``uart_rx`` and listens to ``uart_tx``, 8N1 at the host's baud rate
(the bridge's own rate, the divider's, may differ by up to 2 %: the line is timed by the
host's). :class:`SimTransport` is a ``bissmaster.host.link.Transport`` whose ``write`` and
``read`` run as cocotb coroutines (``cocotb.task.resume``): ``Link`` runs in a thread of its own
(``cocotb.task.bridge``) and simulated time passes while it waits, as a PC waits on a serial
port. Its hooks lose or damage bytes on the way in either direction, and break a stop bit.

Link is host software under test, imported as a user runs it (as the control-channel
scenarios run ``bissmaster.bp3``); expected values still come from the register map's source
and the encoder model (tb/tests/model/test_protocol_facts.py keeps that list).
"""

import os

import cocotb
from cocotb.task import bridge, resume
from cocotb.triggers import Event, FallingEdge, Lock, SimTimeoutError, Timer, with_timeout
from cocotb.simtime import get_sim_time

from bissmaster.host import link

#: The line's rate (sim/shared/runner.py builds the UART top at it and passes it here).
BAUD = int(os.environ.get("BISS_UART_BAUD", "3000000"))
#: The build's inter-byte timeout in bit times (--uart-timeout-bits).
TIMEOUT_BITS = int(os.environ.get("BISS_UART_TIMEOUT_BITS", "1000"))


class UartLine:
    """8N1 at ``baud``: ``send`` drives ``to_dut`` bit by bit; every byte seen on
    ``from_dut`` (sampled in the middle of each bit, from its start bit's falling edge) goes to
    ``on_byte(byte, stop_bit)``."""

    def __init__(self, to_dut, from_dut, baud, on_byte):
        self.to_dut, self.from_dut = to_dut, from_dut
        self.bit_ps = round(1e12 / baud)
        self.on_byte = on_byte
        self.framing_errors = 0
        to_dut.value = 1
        cocotb.start_soon(self._listen())

    async def send(self, items):
        """``items``: bytes, or (byte, stop bit) pairs (a 0 stop bit: a framing error; the line
        is then high for two bit times)."""
        for item in items:
            byte, stop = item if isinstance(item, tuple) else (item, 1)
            for level in [0] + [(byte >> i) & 1 for i in range(8)] + [stop]:
                self.to_dut.value = level
                await Timer(self.bit_ps, "ps")
            if not stop:
                self.to_dut.value = 1
                await Timer(2 * self.bit_ps, "ps")
        self.to_dut.value = 1

    async def _listen(self):
        half = self.bit_ps // 2
        while True:
            await FallingEdge(self.from_dut)
            await Timer(half, "ps")
            if int(self.from_dut.value):
                continue                        # not a start bit
            byte = 0
            for i in range(8):
                await Timer(self.bit_ps, "ps")
                byte |= int(self.from_dut.value) << i
            await Timer(self.bit_ps, "ps")
            stop = int(self.from_dut.value)
            self.framing_errors += not stop
            self.on_byte(byte, stop)


class SimTransport(link.Transport):
    """``Link``'s transport on a :class:`UartLine`, called from a ``bridge`` thread.

    ``requests(data)``: the bytes of one ``write`` as they go on the line (bytes, or items for
    :meth:`UartLine.send`), to lose, damage or break some. ``responses(index, byte)``: each byte
    received (``index`` counts them from 0), as the host gets it (bytes: none, one, or more).
    ``now`` is simulated time in seconds, so Link's deadlines are simulated time; ``sleep(s)``
lets simulated time pass.
    """

    def __init__(self, dut, baud=BAUD):
        self.requests = None
        self.responses = None
        self.received = 0
        self._buffer = bytearray()
        self._event = Event()
        self.line = UartLine(dut.uart_rx, dut.uart_tx, baud, self._on_byte)
        self.write = resume(self._write)
        self.read = resume(self._read)
        self.sleep = resume(self._sleep)

    def _on_byte(self, byte, stop):
        index, self.received = self.received, self.received + 1
        self._buffer += self.responses(index, byte) if self.responses else bytes([byte])
        self._event.set()

    @property
    def now(self):
        return get_sim_time("ns") * 1e-9

    async def _sleep(self, seconds):
        """Let ``seconds`` of simulated time pass (the host tool's pauses: bissmaster.host.board
        uses a transport's ``sleep`` when it has one)."""
        if seconds > 0:
            await Timer(max(round(seconds * 1e9), 1), "ns")

    async def _write(self, data):
        items = self.requests(bytes(data)) if self.requests else bytes(data)
        await self.line.send(items)

    async def _read(self, n, timeout):
        deadline_ns = get_sim_time("ns") + timeout * 1e9
        while len(self._buffer) < n:
            left = deadline_ns - get_sim_time("ns")
            if left <= 0:
                break
            self._event.clear()
            try:
                await with_timeout(self._event.wait(), max(round(left), 1), "ns")
            except SimTimeoutError:
                break
        out, self._buffer = bytes(self._buffer[:n]), self._buffer[n:]
        return out


class UartBus:
    """The bus scenarios' bus on ``biss_master_uart``: 32-bit reads and writes through
    ``Link`` (one access at a time, callers queued). A write of some byte lanes is a read,
    the lanes changed, and a write (the bridge writes whole words)."""

    def __init__(self, dut, *, latency=2e-6, retries=3):
        self.transport = SimTransport(dut)
        self.link = link.Link(self.transport, baud=BAUD, timeout_bits=TIMEOUT_BITS,
                              latency=latency, retries=retries)
        self.lock = Lock()

    async def call(self, method, *args):
        """``Link.<method>(*args)`` in a bridge thread, one at a time."""
        async with self.lock:
            return await bridge(getattr(self.link, method))(*args)

    async def read(self, addr):
        return await self.call("read32", addr)

    async def read_burst(self, addr, count):
        return await self.call("read_burst", addr, count)

    async def write(self, addr, value, lanes=0xF):
        async with self.lock:
            if lanes != 0xF:
                mask = sum(0xFF << 8 * i for i in range(4) if lanes >> i & 1)
                value = (await bridge(self.link.read32)(addr)) & ~mask | value & mask
            await bridge(self.link.write32)(addr, value & 0xFFFF_FFFF)
