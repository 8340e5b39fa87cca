"""The host bridge over a UART: request and response packets onto the register bank's bus.

A host (a PC behind the board's USB-serial UART, ``bissmaster.host.link``) reads and writes
the registers of the same map as the AXI4-Lite and Wishbone tops, one packet per register
access. docs/uart_bridge.md is the protocol's definition (the framing table, the statuses, the
timeouts, the CRC); the constants below are its RTL copy, and the host has its own, both
checked against that page (tb/tests/host/test_link.py).

Like the bus adapters (:mod:`bissmaster.bus.bus_adapters`), the bridge only turns one protocol
into :class:`~bissmaster.bus.register_bank.RegisterBus` transactions: no register knowledge,
no address decoding beyond the bus's width.
"""

from amaranth.hdl import *
from amaranth.lib import crc, enum, wiring
from amaranth.lib.wiring import In, Out

from .register_bank import STROBES, RegisterBus
from .uart import UartRx, UartTx, divider as uart_divider

#: The first byte of a request, and of a response (different, so that a host never takes its
#: own request's echo for an answer).
SYNC_REQUEST = 0xA5
SYNC_RESPONSE = 0x5A

#: The 16-bit byte address of a request.
ADDRESS_BITS = 16


class Opcode(enum.Enum, shape=4):
    """The low four bits of a request's command byte (the high four are the host's tag)."""
    PING = 0x0          # no access; clears the duplicate memory (a host's first request)
    READ = 0x1          # one word
    WRITE = 0x2         # one word, all four byte lanes
    READ_BURST = 0x3    # COUNT words (1..255) from consecutive addresses


#: Bytes of each request, SYNC and CRC included.
REQUEST_LENGTH = {Opcode.PING: 3, Opcode.READ: 5, Opcode.WRITE: 9, Opcode.READ_BURST: 6}


class BridgeStatus(enum.Enum, shape=8):
    """The third byte of a response."""
    OK = 0x00               # done (a read's data follows)
    BAD_CRC = 0x01          # CRC mismatch or a framing error in the request: no access
    BAD_COMMAND = 0x02      # unknown opcode, or a burst of 0 words: no access
    BAD_ADDRESS = 0x03      # not a multiple of 4, or beyond the bus's address space: no access


#: CRC-8/AUTOSAR (the CRC catalogue's name): polynomial 0x2F, initial value 0xFF, no
#: reflection, final XOR 0xFF; check value (CRC of ASCII "123456789") 0xDF. Over every byte of a
#: packet before the CRC byte, SYNC included.
CRC8 = crc.Algorithm(crc_width=8, polynomial=0x2F, initial_crc=0xFF, reflect_input=False,
                     reflect_output=False, xor_output=0xFF)

#: The inter-byte timeout's default, in bit times (docs/uart_bridge.md, Timeouts).
DEFAULT_TIMEOUT_BITS = 1000
#: Its range.
MAX_TIMEOUT_BITS = 1_000_000
#: Bit times of quiet line before a request's SYNC: a SYNC value in the middle of a stream of
#: bytes (a request sent while an answer is on the line, the rest of a request whose SYNC was
#: lost) never starts a request. A host sends its next request after the answer to the last
#: one, which alone takes 40 bit times.
LEAD_BITS = 20


class UartSignature(wiring.Signature):
    """The UART's two lines, as the far end (the host's side) sees them, named as the bridge's
    pins: the far end drives ``rx`` and listens to ``tx``. Both idle high."""

    def __init__(self):
        super().__init__({"rx": Out(1, init=1), "tx": In(1, init=1)})


def check_timeout_bits(timeout_bits):
    """Raise ValueError unless ``timeout_bits`` is a valid inter-byte timeout."""
    if (not isinstance(timeout_bits, int) or isinstance(timeout_bits, bool)
            or not 1 <= timeout_bits <= MAX_TIMEOUT_BITS):
        raise ValueError(f"timeout_bits must be an integer from 1 to {MAX_TIMEOUT_BITS}, "
                         f"not {timeout_bits!r}")


class BridgeEngine(wiring.Component):
    """The packet engine: received bytes -> register-bus accesses -> bytes to send.

    Requests (docs/uart_bridge.md, Framing): SYNC_REQUEST, the command (tag << 4 | opcode), the
    16-bit byte address (low byte first) for every opcode but PING, then COUNT (READ_BURST) or
    four data bytes (WRITE, low byte first), then the CRC-8 of every byte before it.

    Quiet line is counted in bit times of ``divider`` clocks while the receiver is not busy
    (``rx_busy`` low: from the middle of a byte's stop bit, the clock it ends, to the next
    start bit it sees), whatever the engine did with the bytes.

    Receiving: while idle, every byte is ignored but a SYNC_REQUEST whose start bit came after
    at least :data:`LEAD_BITS` of quiet line (a byte with a framing error is ignored too).
    From that SYNC_REQUEST on, the command's opcode gives the request's length; every byte
    received with a framing error (``rx_error``) counts as a byte and makes the request
    BAD_CRC. When the line has been quiet for ``timeout_bits`` after a byte, the partial
    request is dropped without an answer and the engine is idle again. An unknown opcode: the
    bytes that follow are dropped until that timeout, then the answer is BAD_COMMAND (the
    request's length is unknown, so its end is the line going quiet).

    Checking, the clock after the CRC byte: a CRC mismatch or a framing error gives BAD_CRC;
    READ_BURST with COUNT 0 gives BAD_COMMAND; an address that is not a multiple of four, or a
    word (any word of a burst) beyond the bus's ``addr_width`` bits of byte address, gives
    BAD_ADDRESS; anything else is OK. Only OK accesses the bus.

    Duplicates: the last request with a good CRC is kept (command, address, data). A WRITE
    that is OK and equal to it in every byte, when that one was an OK WRITE too, is a host's
    retry of a write whose answer it lost: it is answered OK and not written again, so a retried
    write of a pulse or a write-1-to-clear register acts once. Any other request with a good
    CRC ends the memory (the host's tag changes from one request to the next, docs).

    Accessing: an OK WRITE is ``w_en`` in the checking clock (address ``addr[2:]``, every byte
    strobe); its answer waits for the bank's ``w_busy`` to be low in a clock after the
    checking clock (two clocks more than another answer at the least; longer for a channel's
    configuration while its core is in a cycle): the write has then acted. A READ or
    READ_BURST reads each word just before its bytes are sent: ``r_en``,
    ``r_load`` in the next clock, the data taken from ``r_data`` in the clock after; the words
    of a burst in address order.

    Answering: every request that was checked, or ended as BAD_COMMAND, gets exactly one
    response: SYNC_RESPONSE, the request's command byte, the status, for an OK read four bytes
    per word (low byte first), then the CRC-8 of every byte before it. Bytes go to ``tx_*``
    one after the other as ``tx_ready`` takes them. Bytes received from the checking clock up to
    the clock the response's CRC byte is taken are ignored; the engine is idle from the next.

    Parameters
    ----------
    addr_width : int
        Bits of the bus's byte address (``RegisterBus(addr_width - 2)``), 3 .. 16.
    divider : int
        System clocks per bit.
    timeout_bits : int
        The inter-byte timeout in bit times of quiet line.

    Attributes
    ----------
    rx_data, rx_valid, rx_error, rx_busy : In
        From :class:`~bissmaster.bus.uart.UartRx` (``data``, ``valid``, ``frame_error``,
        ``busy``).
    tx_data, tx_valid : Out
    tx_ready : In
        To and from :class:`~bissmaster.bus.uart.UartTx`.
    regs : Out(RegisterBus(addr_width - 2))
    """

    def __init__(self, addr_width, divider, timeout_bits=DEFAULT_TIMEOUT_BITS):
        if not isinstance(addr_width, int) or not 3 <= addr_width <= ADDRESS_BITS:
            raise ValueError(f"addr_width must be an integer from 3 to {ADDRESS_BITS} (the "
                             f"request's address), not {addr_width!r}")
        if not isinstance(divider, int) or divider < 1:
            raise ValueError(f"divider must be a positive integer, not {divider!r}")
        check_timeout_bits(timeout_bits)
        self.addr_width, self.divider, self.timeout_bits = addr_width, divider, timeout_bits
        #: Clocks of quiet line for the timeout and before a SYNC.
        self.timeout_clocks = timeout_bits * divider
        self.lead_clocks = LEAD_BITS * divider
        super().__init__({
            "rx_data": In(8), "rx_valid": In(1), "rx_error": In(1), "rx_busy": In(1),
            "tx_data": Out(8), "tx_valid": Out(1), "tx_ready": In(1),
            "regs": Out(RegisterBus(addr_width - 2)),
        })

    def elaborate(self, platform):
        m = Module()
        regs = self.regs
        word_bits = self.addr_width - 2
        m.submodules.rx_crc = rx_crc = CRC8(data_width=8).create()
        m.submodules.tx_crc = tx_crc = CRC8(data_width=8).create()

        # The request as received.
        cmd = Signal(8)
        opcode = Signal(Opcode)
        m.d.comb += opcode.eq(cmd[:4])
        addr = Signal(ADDRESS_BITS)
        count = Signal(8)
        data = Signal(32)
        index = Signal(range(10))           # the byte received next (0: SYNC)
        length = Signal(range(10))          # the request's bytes, from its opcode
        damaged = Signal()                  # a byte with a framing error

        # The last request with a good CRC, and whether it was an OK write.
        last_write = Signal()
        last_cmd, last_addr, last_data = Signal(8), Signal(ADDRESS_BITS), Signal(32)

        # The answer.
        status = Signal(BridgeStatus)
        word_addr = Signal(word_bits)
        words_left = Signal(9)
        word = Signal(32)
        sent = Signal(2)                    # bytes of the header or of a word sent

        # Clocks of quiet line (saturating; from reset: long enough), and whether the byte
        # being received began after the lead (taken at its start bit).
        rx_byte = self.rx_valid | self.rx_error
        most = max(self.timeout_clocks, self.lead_clocks)
        since = Signal(range(most + 1), init=most)
        with m.If(self.rx_busy | rx_byte):
            m.d.sync += since.eq(0)
        with m.Elif(since != most):
            m.d.sync += since.eq(since + 1)
        quiet = ~self.rx_busy & ~rx_byte & (since >= self.timeout_clocks)
        was_busy, lead = Signal(), Signal()
        m.d.sync += was_busy.eq(self.rx_busy)
        with m.If(self.rx_busy & ~was_busy):
            m.d.sync += lead.eq(since >= self.lead_clocks)

        def send(byte, first=False):
            """Offer ``byte``; the returned condition is its being taken (fed to the CRC)."""
            m.d.comb += [self.tx_data.eq(byte), self.tx_valid.eq(1),
                         tx_crc.data.eq(byte), tx_crc.valid.eq(self.tx_ready),
                         tx_crc.start.eq(first & self.tx_ready)]
            return self.tx_ready

        # The check of a complete request (the clock after its CRC byte).
        crc_ok = rx_crc.match_detected & ~damaged
        burst = opcode == Opcode.READ_BURST
        words = Mux(burst, count, 1)
        last_word = Signal(ADDRESS_BITS - 1)
        m.d.comb += last_word.eq(addr[2:] + words - 1)
        bad_address = (addr[:2] != 0) | (last_word >> word_bits != 0)
        verdict = Signal(BridgeStatus)
        with m.If(~crc_ok):
            m.d.comb += verdict.eq(BridgeStatus.BAD_CRC)
        with m.Elif(burst & (count == 0)):
            m.d.comb += verdict.eq(BridgeStatus.BAD_COMMAND)
        with m.Elif((opcode != Opcode.PING) & bad_address):
            m.d.comb += verdict.eq(BridgeStatus.BAD_ADDRESS)
        with m.Else():
            m.d.comb += verdict.eq(BridgeStatus.OK)
        ok_write = (verdict == BridgeStatus.OK) & (opcode == Opcode.WRITE)
        duplicate = last_write & (cmd == last_cmd) & (addr == last_addr) & (data == last_data)

        m.d.comb += [regs.w_addr.eq(addr[2:]), regs.w_data.eq(data),
                     regs.w_strb.eq((1 << STROBES) - 1), regs.r_addr.eq(word_addr)]

        with m.FSM(name="bridge_fsm"):
            with m.State("IDLE"):
                m.d.comb += [rx_crc.start.eq(1), rx_crc.data.eq(self.rx_data)]
                with m.If(self.rx_valid & (self.rx_data == SYNC_REQUEST) & lead):
                    m.d.comb += rx_crc.valid.eq(1)
                    m.d.sync += [index.eq(1), damaged.eq(0)]
                    m.next = "RECEIVE"

            with m.State("RECEIVE"):
                m.d.comb += [rx_crc.data.eq(self.rx_data), rx_crc.valid.eq(rx_byte)]
                with m.If(rx_byte):
                    m.d.sync += [index.eq(index + 1), damaged.eq(damaged | self.rx_error)]
                    with m.Switch(index):
                        with m.Case(1):
                            m.d.sync += cmd.eq(self.rx_data)
                            with m.Switch(self.rx_data[:4]):
                                for op, n in REQUEST_LENGTH.items():
                                    with m.Case(op.value):
                                        m.d.sync += length.eq(n)
                                with m.Default():
                                    m.next = "DISCARD"
                        with m.Case(2):
                            m.d.sync += addr[:8].eq(self.rx_data)
                        with m.Case(3):
                            m.d.sync += addr[8:].eq(self.rx_data)
                    with m.If((index >= 4) & (index < 8)):
                        m.d.sync += data.eq(Cat(data[8:], self.rx_data))
                    with m.If(index == 4):
                        m.d.sync += count.eq(self.rx_data)
                    with m.If((index >= 2) & (index == length - 1)):
                        m.next = "CHECK"
                with m.Elif(quiet):
                    m.next = "IDLE"                 # a partial request: dropped

            with m.State("DISCARD"):
                with m.If(quiet):
                    m.d.sync += status.eq(BridgeStatus.BAD_COMMAND)
                    m.next = "HEADER"

            with m.State("CHECK"):
                m.d.sync += [status.eq(verdict), word_addr.eq(addr[2:]), words_left.eq(words),
                             sent.eq(0)]
                with m.If(crc_ok):
                    m.d.sync += [last_write.eq(ok_write), last_cmd.eq(cmd),
                                 last_addr.eq(addr), last_data.eq(data)]
                m.d.comb += regs.w_en.eq(ok_write & ~duplicate)
                with m.If(ok_write & ~duplicate):
                    m.next = "ACT"
                with m.Else():
                    m.next = "HEADER"

            with m.State("ACT"):
                # A write's answer waits until it has acted (w_busy; the bank holds a channel's
                # configuration while its core is in a cycle).
                with m.If(~regs.w_busy):
                    m.next = "HEADER"

            with m.State("HEADER"):
                byte = Array([Const(SYNC_RESPONSE, 8), cmd, status.as_value()])[sent]
                with m.If(send(byte, first=sent == 0)):
                    m.d.sync += sent.eq(sent + 1)
                    with m.If(sent == 2):
                        m.d.sync += sent.eq(0)
                        read = (opcode == Opcode.READ) | (opcode == Opcode.READ_BURST)
                        with m.If((status == BridgeStatus.OK) & read):
                            m.next = "FETCH"
                        with m.Else():
                            m.next = "CRC"

            with m.State("FETCH"):
                m.d.comb += regs.r_en.eq(1)
                m.next = "LOAD"

            with m.State("LOAD"):
                m.d.comb += regs.r_load.eq(1)
                m.next = "TAKE"

            with m.State("TAKE"):
                m.d.sync += [word.eq(regs.r_data), word_addr.eq(word_addr + 1),
                             words_left.eq(words_left - 1)]
                m.next = "WORD"

            with m.State("WORD"):
                with m.If(send(word[:8])):
                    m.d.sync += [word.eq(word >> 8), sent.eq(sent + 1)]
                    with m.If(sent == 3):
                        with m.If(words_left != 0):
                            m.next = "FETCH"
                        with m.Else():
                            m.next = "CRC"

            with m.State("CRC"):
                with m.If(send(tx_crc.crc)):
                    m.next = "IDLE"
        return m


class UartBridge(wiring.Component):
    """The UART bridge: :class:`~bissmaster.bus.uart.UartRx` and
    :class:`~bissmaster.bus.uart.UartTx` at ``baud`` around a :class:`BridgeEngine`, as a bus
    adapter onto the register bank's :class:`~bissmaster.bus.register_bank.RegisterBus`.

    Parameters
    ----------
    addr_width : int
        Bits of the bus's byte address, as for the other adapters (at most 16).
    sys_clk_hz : int
    baud : int
        The divider is ``round(sys_clk_hz / baud)``; refused (ValueError) below 4 clocks per bit
        or more than 2 % off ``baud`` (:func:`bissmaster.bus.uart.divider`).
    timeout_bits : int
        The inter-byte timeout: a partial request is dropped when the line stays quiet for this
        many bit times after a byte (1 .. 1 000 000; default :data:`DEFAULT_TIMEOUT_BITS`).

    Attributes
    ----------
    uart : In(UartSignature())
        ``rx`` (asynchronous, synchronized inside) and ``tx`` (a flip-flop).
    regs : Out(RegisterBus(addr_width - 2))
    """

    def __init__(self, addr_width, *, sys_clk_hz, baud, timeout_bits=DEFAULT_TIMEOUT_BITS):
        self.divider = uart_divider(sys_clk_hz, baud)
        check_timeout_bits(timeout_bits)
        self.addr_width, self.baud, self.timeout_bits = addr_width, baud, timeout_bits
        super().__init__({
            "uart": In(UartSignature()),
            "regs": Out(RegisterBus(addr_width - 2)),
        })

    def elaborate(self, platform):
        m = Module()
        # Not ``rx``/``tx``: the flattened ports of ``uart`` take those names, and Amaranth
        # would rename the instances (rx$36), names the constraint files cannot rely on.
        m.submodules.receiver = rx = UartRx(self.divider)
        m.submodules.transmitter = tx = UartTx(self.divider)
        m.submodules.engine = engine = BridgeEngine(self.addr_width, self.divider,
                                                    self.timeout_bits)
        wiring.connect(m, wiring.flipped(self.regs), engine.regs)
        m.d.comb += [
            rx.rx.eq(self.uart.rx), self.uart.tx.eq(tx.tx),
            engine.rx_data.eq(rx.data), engine.rx_valid.eq(rx.valid),
            engine.rx_error.eq(rx.frame_error), engine.rx_busy.eq(rx.busy),
            tx.data.eq(engine.tx_data), tx.valid.eq(engine.tx_valid),
            engine.tx_ready.eq(tx.ready),
        ]
        return m
