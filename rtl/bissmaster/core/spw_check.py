"""BiSS Safety CPW/SPW plausibility check."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class SpwCheck(wiring.Component):
    """Compares the SPW with the CPW's leading bits, modulo the SPW range, within a tolerance.

    The SPW is the CPW with its extra low bits dropped, so the decoder keeps the CPW's first
    ``bits`` bits (``cpw_top``) while it arrives: no shifter is needed. Positions wrap (rotary
    encoders), so the distance is taken both ways modulo ``2**bits``.

    Two pipeline stages: ``match`` follows the inputs two clocks later. The master only reads
    it after the SPW's CRC, at least 6 bits (24 clocks) after the SPW data are final.
    """

    def __init__(self, width):
        self._width = width
        super().__init__({
            "cpw_top": In(width),
            "spw": In(width),
            "bits": In(range(width + 1)),
            "tolerance": In(8),
            "match": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        width = self._width

        mask = Cat(*(self.bits > i for i in range(width)))     # 2**bits - 1
        ahead = Signal(width)
        behind = Signal(width)
        tolerance = Signal(8)
        m.d.sync += [
            ahead.eq((self.cpw_top - self.spw)[:width] & mask),
            behind.eq((self.spw - self.cpw_top)[:width] & mask),
            tolerance.eq(self.tolerance),
            self.match.eq((ahead <= tolerance) | (behind <= tolerance)),
        ]
        return m
