"""SSI double transmission: the second copy compared with the first, bit by bit."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import WORD_INDEX_WIDTH


class SsiCopyCompare(wiring.Component):
    """Compares every bit of an SSI word's second copy with the first as it arrives.

    An encoder in double transmission (iC-MU's "ring" repeat) sends its word, one bit that
    must be 0, and the word again (docs/ports.md, "SSI mode"). The first copy's bits go into a
    shift register as sent (the newest in bit 0); the second copy shifts in behind them, so the
    first copy's bit for the same position is always ``index`` places down: the word's length
    less one. ``mismatch`` is set by a separator of 1 or any bit that differs, and held until
    the decoder's reset.

    Parameters
    ----------
    width : int
        The longest word: the shift register's length.

    Attributes
    ----------
    first : In(1)
        A bit of the first copy is sampled (``bit``).
    separator : In(1)
        The separator bit is sampled.
    second : In(1)
        A bit of the second copy is sampled.
    bit : In(1)
    index : In(WORD_INDEX_WIDTH)
        The word's last bit index (its length less one).
    mismatch : Out(1)
        The copies differ, or the separator was 1 (registered).
    """

    def __init__(self, width):
        self._width = width
        super().__init__({
            "first": In(1),
            "separator": In(1),
            "second": In(1),
            "bit": In(1),
            "index": In(WORD_INDEX_WIDTH),
            "mismatch": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        ring = Signal(self._width)
        expected = ring.bit_select(self.index, 1)       # the first copy's bit at this index
        with m.If(self.first | self.second):
            m.d.sync += ring.eq(Cat(self.bit, ring))
        with m.If(self.separator):
            m.d.sync += self.mismatch.eq(self.bit)       # must be 0
        with m.If(self.second):
            m.d.sync += self.mismatch.eq(self.mismatch | (self.bit != expected))
        return m
