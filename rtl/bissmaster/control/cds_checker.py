"""The CDS bits of a register's byte: DATA, its CRC-4, and the echo of a write."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from .crc4 import CRC4

#: What the sequencer tells the checker, frame by frame (its own side: all outputs).
CHECK_CONTROL = wiring.Signature({
    "take_data": Out(1),
    "first": Out(1),
    "take_crc": Out(1),
})


class CdsChecker(wiring.Component):
    """Collects the 8 DATA and 4 CRC-4 bits of one register from the CDS and checks them.

    ``control.take_data`` shifts ``cds`` into ``byte`` (MSB first) and into the CRC-4
    (control_crc.CRC4, bit-serial), which restarts with it when ``control.first`` is high;
    ``control.take_crc`` keeps ``cds`` as one of the first three CRC bits received. In the
    clock of the last CRC bit (on ``cds``, not taken), ``crc_ok`` says the 4 bits received
    equal the CRC-4 of the byte, and ``echo_ok`` that ``byte`` equals ``sent`` (a write's
    byte, echoed).

    Attributes
    ----------
    control : In(CHECK_CONTROL)
    cds : In(1)
        The CDS bit of the frame that ends.
    sent : In(8)
        The byte written.
    byte : Out(8)
        The DATA bits received.
    crc_ok, echo_ok : Out(1)
    """

    def __init__(self):
        super().__init__({
            "control": In(CHECK_CONTROL),
            "cds": In(1),
            "sent": In(8),
            "byte": Out(8),
            "crc_ok": Out(1),
            "echo_ok": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        got_crc = Signal(protocol.CRC4_WIDTH - 1)   # the first three CRC bits received

        # DATA, MSB first, and its CRC-4.
        m.submodules.rx_crc = rx_crc = CRC4(data_width=1).create()
        with m.If(self.control.take_data):
            m.d.sync += self.byte.eq(Cat(self.cds, self.byte))
        m.d.comb += [rx_crc.start.eq(self.control.first), rx_crc.valid.eq(self.control.take_data),
                     rx_crc.data.eq(self.cds)]

        # The CRC bits received; the last one is checked as it comes.
        with m.If(self.control.take_crc):
            m.d.sync += got_crc.eq(Cat(self.cds, got_crc))
        m.d.comb += [self.crc_ok.eq(Cat(self.cds, got_crc) == rx_crc.crc),
                     self.echo_ok.eq(self.byte == self.sent)]
        return m
