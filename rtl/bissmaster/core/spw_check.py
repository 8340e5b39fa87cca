"""BiSS Safety CPW/SPW plausibility check."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .const_compare import above


def _below(bits, width):
    """``width`` bits, bit ``i`` set when ``i < bits`` (``2**bits - 1``), from a two-level decode:
    ``bits``' high part against each group of 8, its low 3 bits against each place in a group.
    Written out because ``Cat(bits > i for i in range(width))`` maps each compare to a carry
    chain of its own on ECP5 (Yosys's ``$alu`` for every ``$gt``): 70 of the check's 94 carry
    cells at 40 bits, against about 10 LUT4 for this decode (issue 27; ``const_compare``)."""
    hi, lo = bits[3:], bits[:3]
    groups = (width + 7) // 8

    hi_above = [above(hi, g) for g in range(groups)]
    hi_at = [hi == g if len(hi) else C(g == 0, 1) for g in range(groups)]
    lo_above = [above(lo, q) for q in range(8)]
    return Cat(hi_above[i // 8] | (hi_at[i // 8] & lo_above[i % 8]) for i in range(width))


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

        # With ``d`` = (cpw_top - spw) mod 2**bits: d <= tolerance or (-d) mod 2**bits <=
        # tolerance exactly when (d + tolerance) mod 2**bits <= 2 * tolerance (the window
        # -tolerance .. +tolerance shifted to 0 .. 2 * tolerance; with 2 * tolerance >=
        # 2**bits - 1 every distance matches, both ways). One adder chain and a short compare
        # instead of two differences and two compares (issue 27).
        mask = _below(self.bits, width)                        # 2**bits - 1
        shifted = Signal(width)
        double_tolerance = Signal(9)
        m.d.sync += [
            shifted.eq((self.cpw_top - self.spw + self.tolerance)[:width] & mask),
            double_tolerance.eq(Cat(C(0, 1), self.tolerance)),
        ]
        low = min(width, len(double_tolerance))
        within = shifted[:low] <= double_tolerance
        if width > low:
            within &= ~shifted[low:].any()
        m.d.sync += self.match.eq(within)
        return m
