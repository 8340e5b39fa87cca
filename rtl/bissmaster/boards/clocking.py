"""Board clocks: the PLL settings that turn a board's oscillator into the design's clock, and
the PLL primitives as Amaranth ``Instance``s.

:func:`ecp5_pll` and :func:`ice40_pll` choose the divider settings the way Lattice's and
Project Trellis's / IceStorm's calculators (``ecppll``, ``icepll``, shipped as
``yowasp-ecppll`` / ``yowasp-icepll``) do, within the ranges of the datasheets; the tests
compare them with those tools. Only exact frequencies are accepted: the design's times (MA,
UART baud rate, the core's default times) are counted in clocks of the frequency it was built
for.
"""

from dataclasses import dataclass

from amaranth.hdl import *

MHZ = 1_000_000


@dataclass(frozen=True)
class Ecp5Pll:
    """EHXPLLL settings, feedback from CLKOP: f_out = f_in / CLKI_DIV * CLKFB_DIV,
    f_vco = f_out * CLKOP_DIV."""
    f_in: int
    clki_div: int
    clkfb_div: int
    clkop_div: int

    @property
    def f_pfd(self):
        return self.f_in / self.clki_div

    @property
    def f_out(self):
        return self.f_in * self.clkfb_div / self.clki_div

    @property
    def f_vco(self):
        return self.f_out * self.clkop_div

    @property
    def clkop_cphase(self):
        return (self.clkop_div - 1) // 2

    def instance(self, clk_in, clk_out, locked):
        """The EHXPLLL with CLKI = ``clk_in``, CLKOP = ``clk_out`` (fed back), LOCK = ``locked``."""
        return Instance(
            "EHXPLLL",
            p_PLLRST_ENA="DISABLED", p_INTFB_WAKE="DISABLED", p_STDBY_ENABLE="DISABLED",
            p_DPHASE_SOURCE="DISABLED", p_OUTDIVIDER_MUXA="DIVA",
            p_CLKI_DIV=self.clki_div, p_CLKFB_DIV=self.clkfb_div,
            p_CLKOP_ENABLE="ENABLED", p_CLKOP_DIV=self.clkop_div,
            p_CLKOP_CPHASE=self.clkop_cphase, p_CLKOP_FPHASE=0, p_FEEDBK_PATH="CLKOP",
            a_FREQUENCY_PIN_CLKI=_mhz(self.f_in), a_FREQUENCY_PIN_CLKOP=_mhz(self.f_out),
            a_ICP_CURRENT="12", a_LPF_RESISTOR="8", a_MFG_ENABLE_FILTEROPAMP="1",
            a_MFG_GMCREF_SEL="2",
            i_CLKI=clk_in, i_CLKFB=clk_out, o_CLKOP=clk_out, o_LOCK=locked,
            i_RST=0, i_STDBY=0, i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=1, i_PHASESTEP=1,
            i_PHASELOADREG=1, i_PLLWAKESYNC=0, i_ENCLKOP=0)


@dataclass(frozen=True)
class Ice40Pll:
    """SB_PLL40_PAD settings, simple feedback:
    f_out = f_in * (DIVF + 1) / ((DIVR + 1) * 2**DIVQ)."""
    f_in: int
    divr: int
    divf: int
    divq: int

    @property
    def f_pfd(self):
        return self.f_in / (self.divr + 1)

    @property
    def f_vco(self):
        return self.f_pfd * (self.divf + 1)

    @property
    def f_out(self):
        return self.f_vco / 2**self.divq

    @property
    def filter_range(self):
        """icepll's loop filter setting for the PFD frequency."""
        for limit, value in ((17, 1), (26, 2), (44, 3), (66, 4), (101, 5)):
            if self.f_pfd < limit * MHZ:
                return value
        return 6

    def instance(self, pad, clk_out, locked):
        """The SB_PLL40_PAD on the clock pin ``pad`` (the raw port: the PLL's pad is the pin
        itself: a SingleEndedPort from ``request(..., dir="-")``), its global output ``clk_out``, LOCK = ``locked``."""
        return Instance(
            "SB_PLL40_PAD",
            p_FEEDBACK_PATH="SIMPLE", p_DIVR=self.divr, p_DIVF=self.divf, p_DIVQ=self.divq,
            p_FILTER_RANGE=self.filter_range,
            i_PACKAGEPIN=pad.io, i_RESETB=1, i_BYPASS=0,
            o_PLLOUTGLOBAL=clk_out, o_LOCK=locked)


def _mhz(hz):
    return f"{hz / MHZ:g}"


def ecp5_pll(f_in, f_out):
    """The EHXPLLL settings for exactly ``f_out`` Hz from ``f_in`` Hz (ECP5 family datasheet:
    input 8..400 MHz, PFD 3.125..400 MHz, VCO 400..800 MHz, CLKOP 3.125..400 MHz), the VCO
    nearest 600 MHz (as ecppll); ValueError when none gives it exactly."""
    if not 8 * MHZ <= f_in <= 400 * MHZ or not 3.125 * MHZ <= f_out <= 400 * MHZ:
        raise ValueError(f"ECP5 PLL: {f_in} Hz in, {f_out} Hz out is outside the PLL's range")
    best = None
    for clki_div in range(1, 129):
        if f_in / clki_div < 3.125 * MHZ:
            break
        for clkfb_div in range(1, 81):
            if f_in * clkfb_div != f_out * clki_div:
                continue
            for clkop_div in range(1, 129):
                pll = Ecp5Pll(f_in, clki_div, clkfb_div, clkop_div)
                if 400 * MHZ <= pll.f_vco <= 800 * MHZ:
                    key = (abs(pll.f_vco - 600 * MHZ), clki_div, clkop_div)
                    if best is None or key < best[0]:
                        best = (key, pll)
    if best is None:
        raise ValueError(f"ECP5 PLL: no setting gives exactly {f_out} Hz from {f_in} Hz")
    return best[1]


def ice40_pll(f_in, f_out):
    """The SB_PLL40 settings (simple feedback) for exactly ``f_out`` Hz from ``f_in`` Hz (iCE40
    sysCLOCK PLL: input 10..133 MHz, PFD 10..133 MHz, VCO 533..1066 MHz, output 16..275 MHz);
    ValueError when none gives it exactly."""
    if not 10 * MHZ <= f_in <= 133 * MHZ or not 16 * MHZ <= f_out <= 275 * MHZ:
        raise ValueError(f"iCE40 PLL: {f_in} Hz in, {f_out} Hz out is outside the PLL's range")
    for divr in range(16):
        for divq in range(1, 7):
            for divf in range(128):
                pll = Ice40Pll(f_in, divr, divf, divq)
                if (10 * MHZ <= pll.f_pfd <= 133 * MHZ and 533 * MHZ <= pll.f_vco <= 1066 * MHZ
                        and f_in * (divf + 1) == f_out * (divr + 1) * 2**divq):
                    return pll
    raise ValueError(f"iCE40 PLL: no setting gives exactly {f_out} Hz from {f_in} Hz")
