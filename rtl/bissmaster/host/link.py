"""The host's side of the UART bridge: register reads and writes over a serial line.

:class:`Link` reads and writes 32-bit registers of the bus tops' register map
(docs/registers.md) through ``biss_master_uart``'s UART bridge, over any transport with
``write(data)`` and ``read(n, timeout)`` (:class:`Transport`): :class:`SerialTransport` for a
real port (pyserial, imported only when one is opened), :class:`MemoryBridge` for tests and
for host tools without hardware (a software model of the bridge on a dictionary of registers).

The framing, the statuses and the CRC are written here from docs/uart_bridge.md, not taken from
the RTL (host code imports no hardware): tb/tests/host/test_link.py checks these constants and
the RTL's against that page's tables.

    link = Link(SerialTransport("/dev/ttyUSB1", 115200), baud=115200)
    link.write32(0x220, 24)              # channel 0 cfg_ma: MA half period
    hex(link.read32(0x220))

Every request is answered once; :class:`Link` retries what a damaged byte breaks (no answer
in time, an answer with a bad CRC or not matching the request, the bridge's BAD_CRC) a bounded
number of times, then raises :class:`LinkError`. A retried write is not written twice: the
bridge answers a repeated request (same tag, address and data) without writing again, so a
write of a pulse or of a write-1-to-clear bit acts once (docs/uart_bridge.md, Retries).
"""

import time

# -- The protocol (docs/uart_bridge.md) -------------------------------------------------------

SYNC_REQUEST = 0xA5
SYNC_RESPONSE = 0x5A

#: Opcodes: the low four bits of a request's command byte; the high four are the tag.
OPCODES = {"PING": 0x0, "READ": 0x1, "WRITE": 0x2, "READ_BURST": 0x3}
#: Bytes of each request, SYNC and CRC included.
REQUEST_LENGTH = {"PING": 3, "READ": 5, "WRITE": 9, "READ_BURST": 6}
#: The status byte of a response.
STATUSES = {"OK": 0x00, "BAD_CRC": 0x01, "BAD_COMMAND": 0x02, "BAD_ADDRESS": 0x03}
STATUS_NAMES = {code: name for name, code in STATUSES.items()}
#: Words in one READ_BURST.
MAX_BURST = 255
#: Bits on the line per byte (8N1: start, 8 data, stop).
BYTE_BITS = 10
#: The bridge's inter-byte timeout unless the build says otherwise (--uart-timeout-bits).
DEFAULT_TIMEOUT_BITS = 1000

#: CRC-8/AUTOSAR: width 8, poly 0x2F, init 0xFF, refin false, refout false, xorout 0xFF.
CRC8_POLY = 0x2F
CRC8_INIT = 0xFF
CRC8_XOR_OUT = 0xFF
#: The catalogue's check value: the CRC of the ASCII bytes "123456789".
CRC8_CHECK = 0xDF


def crc8(data):
    """CRC-8/AUTOSAR of ``data`` (bytes), bit by bit, MSB first."""
    reg = CRC8_INIT
    for byte in bytes(data):
        reg ^= byte
        for _ in range(8):
            reg = ((reg << 1) ^ CRC8_POLY) & 0xFF if reg & 0x80 else (reg << 1) & 0xFF
    return reg ^ CRC8_XOR_OUT


def encode_request(opcode, tag, address=0, value=None, count=None):
    """The bytes of one request: ``opcode`` a name of :data:`OPCODES`, ``tag`` 0..15, a 16-bit
    byte ``address`` (not for PING), the 32-bit ``value`` of a WRITE, the ``count`` of a
    READ_BURST. Nothing is checked that the bridge checks itself (alignment, range)."""
    if opcode not in OPCODES:
        raise ValueError(f"opcode must be one of {', '.join(OPCODES)}, not {opcode!r}")
    if not 0 <= tag <= 15:
        raise ValueError(f"tag must be 0..15, not {tag!r}")
    body = bytearray([SYNC_REQUEST, tag << 4 | OPCODES[opcode]])
    if opcode != "PING":
        if not 0 <= address <= 0xFFFF:
            raise ValueError(f"address must be a 16-bit byte address, not {address!r}")
        body += address.to_bytes(2, "little")
    if opcode == "WRITE":
        if not 0 <= value <= 0xFFFF_FFFF:
            raise ValueError(f"value must be a 32-bit unsigned integer, not {value!r}")
        body += value.to_bytes(4, "little")
    elif opcode == "READ_BURST":
        body.append(count)
    body.append(crc8(body))
    assert len(body) == REQUEST_LENGTH[opcode]
    return bytes(body)


def response_length(opcode, status, count=1):
    """Bytes of the response to ``opcode`` with ``status``: SYNC, command, status, for an OK
    read four bytes per word, CRC."""
    words = {"READ": 1, "READ_BURST": count}.get(opcode, 0) if status == STATUSES["OK"] else 0
    return 4 + 4 * words


# -- Errors -----------------------------------------------------------------------------------

class LinkError(Exception):
    """A register access that did not complete (after its retries, or refused)."""


class BridgeError(LinkError):
    """The bridge refused the request (a status no retry changes: BAD_ADDRESS, or BAD_COMMAND
    for a command it does not know). ``status`` is the status's name."""

    def __init__(self, message, status):
        super().__init__(message)
        self.status = status


class _Retry(Exception):
    """One attempt failed in a way a retry may mend; the message says how."""


# -- Transports -------------------------------------------------------------------------------

class Transport:
    """What :class:`Link` needs from a line: ``write(data)`` sends bytes; ``read(n, timeout)``
    returns as soon as ``n`` bytes have arrived, or after ``timeout`` seconds with those that
    did (maybe none; ``timeout`` 0: only what is waiting already)."""

    def write(self, data):
        raise NotImplementedError

    def read(self, n, timeout):
        raise NotImplementedError


class SerialTransport(Transport):
    """A serial port through pyserial (``pip install pyserial``), 8N1. ``port``: the device
    (``/dev/ttyUSB1``, ``COM4``) or an open ``serial.Serial``."""

    def __init__(self, port, baud=115200):
        if isinstance(port, str):
            try:
                import serial
            except ImportError as e:
                raise ImportError("SerialTransport needs pyserial: pip install pyserial") from e
            port = serial.Serial(port, baud, bytesize=8, parity="N", stopbits=1, timeout=0)
        self.port = port

    def write(self, data):
        self.port.write(bytes(data))
        self.port.flush()

    def read(self, n, timeout):
        self.port.timeout = timeout
        return bytes(self.port.read(n))

    def close(self):
        self.port.close()


class MemoryBridge(Transport):
    """A software model of the bridge (docs/uart_bridge.md) on a dictionary of registers, as a
    transport: for tests and for host tools run without hardware.

    Time is virtual: bytes written arrive at once, answers are ready at once, and a ``read``
    that finds too few bytes lets its ``timeout`` pass; a partial request is dropped once
    ``timeout_s`` has passed since its last byte (an unknown command is then answered
    BAD_COMMAND). ``registers`` maps byte addresses to values (unmapped: 0). ``requests``
    and ``responses`` (callables, bytes -> bytes) see the bytes of each ``write`` and of each
    answer, to lose or damage some. ``accesses`` lists every register access made, as
    ``("r" | "w", address, value)``.
    """

    def __init__(self, registers=None, *, addr_width=13, timeout_s=1e-3,
                 requests=None, responses=None):
        self.registers = dict(registers or {})
        self.addr_width, self.timeout_s = addr_width, timeout_s
        self.requests, self.responses = requests, responses
        self.accesses = []
        self.now = 0.0
        self._rx = bytearray()          # the request being received
        self._rx_time = 0.0
        self._tx = bytearray()
        self._last = None               # the last request with a good CRC, if an OK write

    def write(self, data):
        data = bytes(data)
        if self.requests:
            data = self.requests(data)
        for byte in data:
            self._receive(byte)

    def read(self, n, timeout):
        if len(self._tx) < n:
            self.now += timeout
            self._expire()
        out, self._tx = bytes(self._tx[:n]), self._tx[n:]
        return out

    def _expire(self):
        if self._rx and self.now - self._rx_time >= self.timeout_s:
            if self._rx[1:2] and self._rx[1] & 0xF not in OPCODES.values():
                self._answer(self._rx[1], STATUSES["BAD_COMMAND"])
            self._rx.clear()

    def _receive(self, byte):
        self._expire()
        self._rx_time = self.now
        if not self._rx:
            if byte == SYNC_REQUEST:
                self._rx.append(byte)
            return
        self._rx.append(byte)
        op = {code: name for name, code in OPCODES.items()}.get(self._rx[1] & 0xF)
        if op is None or len(self._rx) < REQUEST_LENGTH[op]:
            return
        request, self._rx = bytes(self._rx), bytearray()
        self._execute(op, request)

    def _execute(self, op, request):
        cmd = request[1]
        if crc8(request[:-1]) != request[-1]:
            return self._answer(cmd, STATUSES["BAD_CRC"])
        address = int.from_bytes(request[2:4], "little") if op != "PING" else 0
        words = request[4] if op == "READ_BURST" else 1
        last, self._last = self._last, None
        if op == "READ_BURST" and words == 0:
            return self._answer(cmd, STATUSES["BAD_COMMAND"])
        if op != "PING" and (address % 4 or address + 4 * words > 1 << self.addr_width):
            return self._answer(cmd, STATUSES["BAD_ADDRESS"])
        if op == "WRITE":
            self._last = request
            if request != last:
                value = int.from_bytes(request[4:8], "little")
                self.registers[address] = value
                self.accesses.append(("w", address, value))
            return self._answer(cmd, STATUSES["OK"])
        data = b""
        if op in ("READ", "READ_BURST"):
            for a in range(address, address + 4 * words, 4):
                value = self.registers.get(a, 0)
                self.accesses.append(("r", a, value))
                data += value.to_bytes(4, "little")
        self._answer(cmd, STATUSES["OK"], data)

    def _answer(self, cmd, status, data=b""):
        body = bytes([SYNC_RESPONSE, cmd, status]) + data
        body += bytes([crc8(body)])
        self._tx += self.responses(body) if self.responses else body


# -- The link ---------------------------------------------------------------------------------

class Link:
    """Register access over the UART bridge.

    Parameters
    ----------
    transport : Transport
    baud : int
        The line's rate: the timeouts are reckoned from it.
    timeout_bits : int
        The bridge's inter-byte timeout (``--uart-timeout-bits`` of the build).
    latency : float
        Seconds a round trip may take beyond its bytes on the wire (a USB-serial adapter's
        latency timer, the operating system); added to every answer's deadline.
    retries : int
        Attempts after the first, per access, before :class:`LinkError`.

    Each access is one request and its answer. A new request takes the next tag (0..15, in the
    command byte); a retry repeats the request unchanged, after the line has been quiet for the
    bridge's inter-byte timeout (so it has dropped whatever it was receiving) and stale bytes are
    thrown away. The first access of a link is preceded by a PING, which clears the bridge's
    memory of the last write (a link opened anew never has its first write taken for a
    retry). ``stats`` counts requests, attempts and each kind of failure.
    """

    def __init__(self, transport, *, baud=115200, timeout_bits=DEFAULT_TIMEOUT_BITS,
                 latency=0.05, retries=3):
        if not isinstance(retries, int) or retries < 0:
            raise ValueError(f"retries must be a non-negative integer, not {retries!r}")
        self.transport = transport
        self.bit_s = 1 / baud
        self.quiet_s = (timeout_bits + 2 * BYTE_BITS) * self.bit_s
        self.latency, self.retries = latency, retries
        self.tag = 0
        self.synced = False
        self.stats = {"requests": 0, "attempts": 0, "timeout": 0, "garbled": 0, "BAD_CRC": 0}

    # -- The accesses -------------------------------------------------------------------------
    def ping(self):
        """A request without an access: checks the line, clears the bridge's write memory."""
        self._transact("PING")
        self.synced = True

    def read32(self, address):
        """The 32-bit register at byte ``address``."""
        return self._transact("READ", address)[0]

    def read_burst(self, address, count):
        """``count`` (1..255) registers from byte ``address`` up, in one request."""
        if not isinstance(count, int) or not 1 <= count <= MAX_BURST:
            raise ValueError(f"count must be 1..{MAX_BURST}, not {count!r}")
        return self._transact("READ_BURST", address, count=count)

    def write32(self, address, value):
        """Write all four bytes of the register at byte ``address``."""
        self._transact("WRITE", address, value=value)

    # -- One request --------------------------------------------------------------------------
    def _transact(self, opcode, address=0, value=None, count=None):
        if not self.synced and opcode != "PING":
            self.ping()
        self.tag = (self.tag + 1) % 16
        request = encode_request(opcode, self.tag, address, value, count)
        self.stats["requests"] += 1
        failures = []
        for attempt in range(self.retries + 1):
            if attempt:
                self._wait_quiet()
            self._discard()
            self.stats["attempts"] += 1
            self.transport.write(request)
            try:
                return self._answer(opcode, request, count or 1)
            except _Retry as e:
                failures.append(str(e))
        what = f"{opcode} {address:#06x}" if opcode != "PING" else "PING"
        raise LinkError(f"{what}: no good answer in {self.retries + 1} attempts "
                        f"({'; '.join(failures)})")

    def _answer(self, opcode, request, words):
        """The words of the answer to ``request``; raises _Retry or BridgeError."""
        longest = response_length(opcode, STATUSES["OK"], words)
        deadline = time_left = ((len(request) + longest) * BYTE_BITS * self.bit_s * 1.05
                                + self.latency + self.quiet_s)
        start = self._clock()

        def read(n):
            left = deadline - (self._clock() - start)
            data = self.transport.read(n, max(left, 0.0)) if left > 0 else b""
            if len(data) < n:
                self.stats["timeout"] += 1
                raise _Retry(f"no answer within {time_left * 1e3:.1f} ms")
            return data

        while read(1)[0] != SYNC_RESPONSE:         # anything before the answer's SYNC: noise
            pass
        head = bytes([SYNC_RESPONSE]) + read(2)
        if head[1] != request[1]:
            self.stats["garbled"] += 1
            raise _Retry(f"an answer to command {head[1]:#04x}, not {request[1]:#04x}")
        rest = read(response_length(opcode, head[2], words) - 3)
        answer = head + rest
        if crc8(answer[:-1]) != answer[-1]:
            self.stats["garbled"] += 1
            raise _Retry("an answer with a bad CRC")
        status = STATUS_NAMES.get(head[2], f"{head[2]:#04x}")
        if status == "OK":
            data = answer[3:-1]
            return [int.from_bytes(data[i:i + 4], "little") for i in range(0, len(data), 4)]
        if status == "BAD_CRC":
            self.stats["BAD_CRC"] += 1
            raise _Retry("the bridge received a damaged request (BAD_CRC)")
        address = int.from_bytes(request[2:4], "little")
        raise BridgeError(f"{opcode} {address:#06x}: the bridge answered {status}", status)

    def _discard(self):
        """Throw away bytes waiting already (an earlier answer's remains, noise)."""
        while self.transport.read(4096, 0):
            pass

    def _wait_quiet(self):
        """Wait until the line has been quiet for the bridge's inter-byte timeout."""
        while self.transport.read(4096, self.quiet_s):
            pass

    def _clock(self):
        """Seconds, from the transport's clock when it has one (a simulation's or a model's
        virtual time), else the computer's."""
        now = getattr(self.transport, "now", None)
        if now is None:
            return time.monotonic()
        return now() if callable(now) else now
