"""The CDM bits a register access sends: its header, its write bytes and their CRC-4."""

from amaranth.hdl import *
from amaranth.lib import enum, wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from .crc4 import CRC4
from ..layouts import access_request_layout


class CdmSource(enum.Enum, shape=3):
    """Where the CDM bit of the next request cycle comes from."""
    ZERO = 0
    ONE = 1
    HEADER = 2      # the header's next bit (S, CTS, ID, ADR; R, W)
    DATA = 3        # the write byte's next bit
    CRC = 4         # bit ``crc_bit`` of the CRC-4 of the bits sent


#: What the sequencer tells the sender, frame by frame (its own side: all outputs).
SEND_CONTROL = wiring.Signature({
    "load_header": Out(1),
    "shift_header": Out(1),
    "load_byte": Out(1),
    "shift_byte": Out(1),
    "crc_start": Out(1),
    "crc_valid": Out(1),
    "source": Out(CdmSource),
    "crc_bit": Out(2),
})


class CdmSender(wiring.Component):
    """Holds the bits a register access sends and puts one on ``cdm``, as ``control`` says.

    ``control.load_header`` takes the header from ``request``: S=1, CTS=1, ID[2:0], ADR[6:0],
    four places for the CRC-4, R, W (18 bits, sent MSB first); ``control.shift_header`` moves
    to its next bit. ``control.load_byte`` takes ``byte`` (the write buffer's byte) as the byte
    to send and keeps it as ``sent`` (for the echo check); ``control.shift_byte`` moves to its
    next bit, MSB first. The CRC-4 (control_crc.CRC4, bit-serial) restarts with
    ``control.crc_start`` and, with ``control.crc_valid``, takes the header's current bit in a
    clock with ``shift_header``, else the byte's. ``cdm`` is the bit of ``control.source``:
    0, 1, the header's current bit, the byte's current bit, or CRC bit ``control.crc_bit``
    (0: the first sent, the MSB) of the bits taken so far.

    Attributes
    ----------
    control : In(SEND_CONTROL)
    request : In(access_request_layout)
        Read with ``control.load_header``.
    byte : In(8)
        Read with ``control.load_byte``.
    cdm : Out(1)
    sent : Out(8)
        The byte last loaded.
    """

    def __init__(self):
        super().__init__({
            "control": In(SEND_CONTROL),
            "request": In(access_request_layout()),
            "byte": In(8),
            "cdm": Out(1),
            "sent": Out(8),
        })

    def elaborate(self, platform):
        m = Module()
        control = self.control
        request = self.request
        # The header's bits, LSB first: W, R, the CRC-4's places, ADR, ID, CTS, S.
        first_header = Cat(request.write, ~request.write, C(0, protocol.CRC4_WIDTH),
                           request.address, request.slave_id, C(1, 1), C(1, 1))
        header = Signal(len(first_header))          # the header's CDM bits, MSB first
        to_send = Signal(8)                         # the write byte, shifted out MSB first

        # The header: loaded at the start, shifted out frame by frame.
        with m.If(control.load_header):
            m.d.sync += header.eq(first_header)
        with m.If(control.shift_header):
            m.d.sync += header.eq(header << 1)

        # The write byte: loaded at a register's S, shifted out frame by frame, kept for its echo.
        with m.If(control.load_byte):
            m.d.sync += [to_send.eq(self.byte), self.sent.eq(self.byte)]
        with m.If(control.shift_byte):
            m.d.sync += to_send.eq(to_send << 1)

        # The CRC-4 of the bits sent (the header's CTS, ID, ADR; a write's DATA).
        m.submodules.tx_crc = tx_crc = CRC4(data_width=1).create()
        m.d.comb += [tx_crc.start.eq(control.crc_start), tx_crc.valid.eq(control.crc_valid),
                     tx_crc.data.eq(Mux(control.shift_header, header[-1], to_send[-1]))]

        # The bit of the next request cycle.
        with m.Switch(control.source):
            with m.Case(CdmSource.ONE):
                m.d.comb += self.cdm.eq(1)
            with m.Case(CdmSource.HEADER):
                m.d.comb += self.cdm.eq(header[-1])
            with m.Case(CdmSource.DATA):
                m.d.comb += self.cdm.eq(to_send[-1])
            with m.Case(CdmSource.CRC):
                m.d.comb += self.cdm.eq(tx_crc.crc.bit_select(~control.crc_bit, 1))
        return m
