"""The board designs: which board, which clock, which pins (:data:`BOARDS`), and
:class:`BoardTop`, the design as the board's Amaranth platform builds it.

Each :class:`Board` names an ``amaranth-boards`` platform (``pip install
'bissmaster[boards]'``), the clock the design runs on (the board's oscillator, or a PLL from
it), the core preset and channel count, the RS-422 transceiver pins of each channel on a
connector of the board, the status LEDs and the reset button. docs/bench.md has the wiring;
scripts/board.py (``make board BOARD=<name>``) builds it.
"""

import importlib
from dataclasses import dataclass, field

from amaranth.build import Attrs, DiffPairs, Pins, PinsN, Resource, Subsignal
from amaranth.hdl import *
from amaranth.lib import io
from amaranth.lib.cdc import ResetSynchronizer

from ..generate import preset_params
from .clocking import ecp5_pll, ice40_pll
from .logic import BoardLogic

#: The signals of one channel's transceiver, in the order of the pinout tables.
CHANNEL_PINS = ("ma", "slo", "de", "re")


@dataclass(frozen=True)
class Channel:
    """One channel's pins on a connector: ``pins`` maps each of :data:`CHANNEL_PINS` to the
    connector's pin name (``re`` is the transceiver's active-low ``/RE``; leave it out for a
    receiver without one). ``slo_pair``: (p, n) connector pins of a differential SLO input
    instead of ``pins["slo"]`` (an ``IBUFDS`` on Xilinx parts)."""
    conn: tuple
    pins: dict
    slo_pair: tuple = None


@dataclass(frozen=True)
class Board:
    """A board design.

    ``platform``: "module:Class" of amaranth-boards; ``family``: ecp5, ice40 or xilinx;
    ``clock``: the oscillator's resource; ``clock_hz``: its frequency; ``sys_clk_hz``: the
    design's (a PLL when they differ); ``leds``: {logic output: (resource, number[, subsignal])};
    ``reset``: the button resource (pressed = reset) or None; ``io_attrs``: the pins' I/O
    attributes (the SLO input gets ``slo_attrs`` on top); ``plan_only``: a vendor toolchain
    (``make board PLAN=1``) rather than the open flow.
    """
    name: str
    title: str
    platform: str
    family: str
    clock: str
    clock_hz: int
    sys_clk_hz: int
    channels: tuple
    leds: dict
    preset: str = "bp3"
    baud: int = 115200
    reset: tuple = None
    io_attrs: dict = field(default_factory=dict)
    slo_attrs: dict = field(default_factory=dict)
    diff_attrs: dict = field(default_factory=dict)
    resources: tuple = ()           # extra resource lists of the platform to add (names)
    plan_only: bool = False
    overrides: dict = field(default_factory=dict)   # MasterParams fields on top of the preset

    @property
    def pll(self):
        if self.sys_clk_hz == self.clock_hz:
            return None
        make = {"ecp5": ecp5_pll, "ice40": ice40_pll}.get(self.family)
        if make is None:
            raise ValueError(f"{self.name}: no PLL for family {self.family}")
        return make(self.clock_hz, self.sys_clk_hz)

    @property
    def params(self):
        return preset_params(self.preset, sys_clk_hz=self.sys_clk_hz, **self.overrides)

    def make_platform(self):
        """The amaranth-boards platform, with this design's channel resources added."""
        module, cls = self.platform.split(":")
        try:
            mod = importlib.import_module(f"amaranth_boards.{module}")
        except ImportError as e:
            raise ImportError(f"the board designs need amaranth-boards: "
                              f"pip install 'bissmaster[boards]' ({e})") from e
        platform = getattr(mod, cls)()
        for extra in self.resources:
            platform.add_resources(getattr(platform, extra))
        platform.add_resources(self.channel_resources())
        return platform

    def channel_resources(self):
        """One ``Resource("biss", n, ...)`` per channel: ``ma``, ``de`` outputs, ``slo`` input
        (single-ended, or a differential pair), ``re`` output inverted (the pin is ``/RE``)."""
        out = []
        for n, ch in enumerate(self.channels):
            subs = [Subsignal("ma", Pins(ch.pins["ma"], dir="o", conn=ch.conn))]
            if ch.slo_pair:
                subs.append(Subsignal("slo", DiffPairs(*ch.slo_pair, dir="i", conn=ch.conn),
                                      Attrs(**self.diff_attrs)))
            else:
                subs.append(Subsignal("slo", Pins(ch.pins["slo"], dir="i", conn=ch.conn),
                                      Attrs(**self.io_attrs, **self.slo_attrs)))
            subs.append(Subsignal("de", Pins(ch.pins["de"], dir="o", conn=ch.conn)))
            if "re" in ch.pins:
                subs.append(Subsignal("re", PinsN(ch.pins["re"], dir="o", conn=ch.conn)))
            out.append(Resource("biss", n, *subs,
                                *([Attrs(**self.io_attrs)] if self.io_attrs else [])))
        return out

    def logic(self):
        return BoardLogic(len(self.channels), self.params, self.baud)


class BoardTop(Elaboratable):
    """``board``'s design: clock (PLL or the oscillator), reset synchronizer, the
    :class:`~bissmaster.boards.logic.BoardLogic` on the UART and channel pins, the LEDs."""

    def __init__(self, board):
        self.board = board
        self.logic = board.logic()

    def elaborate(self, platform):
        b = self.board
        m = Module()

        def buffer(name, direction, port):
            """An I/O buffer (amaranth.lib.io.Buffer: the platform's, e.g. IBUFDS for a pair)."""
            m.submodules[name] = buf = io.Buffer(direction, port)
            return buf

        m.domains.sync = cd_sync = ClockDomain("sync")
        pll = b.pll
        locked = Signal()
        clock = platform.request(b.clock, 0, dir="-")
        if pll is None:
            m.d.comb += [cd_sync.clk.eq(buffer("clk_buf", "i", clock).i), locked.eq(1)]
        elif b.family == "ice40":
            # SB_PLL40_PAD takes the clock pin itself (no input buffer in front of it).
            m.submodules.pll = pll.instance(clock, cd_sync.clk, locked)
        else:
            m.submodules.pll = pll.instance(buffer("clk_buf", "i", clock).i, cd_sync.clk, locked)
        # No clock constraint on the PLL's output: nextpnr derives it from the input pin's
        # (the platform's Clock on the oscillator) and the PLL's dividers, and
        # scripts/board.py checks that the design's clock was timed at sys_clk_hz. (Amaranth
        # names the net by one of the fragments that use it, a name Yosys does not keep.)

        # Reset while the PLL has not locked or the button is pressed; asserted at once,
        # released on the clock (amaranth.lib.cdc.ResetSynchronizer).
        arst = Signal()
        m.d.comb += arst.eq(~locked)
        if b.reset is not None:
            button = buffer("reset_buf", "i", platform.request(*b.reset, dir="-"))
            m.d.comb += arst.eq(~locked | button.i)
        m.submodules.reset_sync = ResetSynchronizer(arst, domain="sync")

        m.submodules.logic = logic = self.logic
        uart = platform.request("uart", 0, dir="-")
        m.d.comb += [logic.uart_rx.eq(buffer("uart_rx_buf", "i", uart.rx).i),
                     buffer("uart_tx_buf", "o", uart.tx).o.eq(logic.uart_tx)]
        for n in range(len(b.channels)):
            pins = platform.request("biss", n, dir="-")
            m.d.comb += [buffer(f"ch{n}_ma_buf", "o", pins.ma).o.eq(getattr(logic, f"ch{n}_ma")),
                         getattr(logic, f"ch{n}_slo").eq(buffer(f"ch{n}_slo_buf", "i", pins.slo).i),
                         buffer(f"ch{n}_de_buf", "o", pins.de).o.eq(getattr(logic, f"ch{n}_de"))]
            if hasattr(pins, "re"):
                m.d.comb += buffer(f"ch{n}_re_buf", "o", pins.re).o.eq(getattr(logic, f"ch{n}_re"))
        requested = {}
        for signal, (name, number, *sub) in b.leds.items():
            if (name, number) not in requested:       # an RGB LED: once for its colours
                requested[name, number] = platform.request(name, number, dir="-")
            port = requested[name, number]
            if sub:
                port = getattr(port, sub[0])
            m.d.comb += buffer(f"{signal}_buf", "o", port).o.eq(getattr(logic, signal))
        return m


def _pmod_channel(conn, first):
    """A channel on one row of a 12-pin PMOD: MA, SLO, DE, /RE on pins first .. first + 3."""
    return Channel(conn, {pin: str(first + i) for i, pin in enumerate(CHANNEL_PINS)})


def _ulx3s(size):
    """The ULX3S with an LFE5U of ``size`` ("85F", "25F"): the same board otherwise, two
    channels on the GPIO header's pairs (the + and the - pins of pairs 0..3)."""
    return Board(
        f"ulx3s-{size.lower()}", f"Radiona ULX3S, LFE5U-{size} (ECP5), FT231X USB-serial",
        f"ulx3s:ULX3S_{size}_Platform", "ecp5", "clk25", 25_000_000, 80_000_000,
        channels=tuple(Channel(("gpio", 0), {pin: f"{i}{side}" for i, pin
                                             in enumerate(CHANNEL_PINS)})
                       for side in "+-"),
        leds={"heartbeat": ("led", 0), "ch0_valid_led": ("led", 1), "ch0_fault_led": ("led", 2),
              "ch1_valid_led": ("led", 3), "ch1_fault_led": ("led", 4)},
        reset=("button_fire", 1),
        io_attrs={"IO_TYPE": "LVCMOS33"}, slo_attrs={"PULLMODE": "UP"})


#: The boards, by ``make board BOARD=<name>``.
BOARDS = {b.name: b for b in [
    _ulx3s("85F"),
    _ulx3s("25F"),
    Board(
        "icebreaker", "1BitSquared iCEBreaker, iCE40UP5K-SG48, FT2232H USB-serial",
        "icebreaker:ICEBreakerPlatform", "ice40", "clk12", 12_000_000, 24_000_000,
        channels=(_pmod_channel(("pmod", 0), 1),),
        leds={"heartbeat": ("led_g", 1), "ch0_valid_led": ("led_g", 0),
              "ch0_fault_led": ("led_r", 0)},
        reset=("button", 0), resources=("break_off_pmod",),
        io_attrs={"IO_STANDARD": "SB_LVCMOS"}, slo_attrs={"PULLUP": 1},
        # The UP5K is full: 16-bit time settings (655 us at 100 MHz, 2.7 ms at 24 MHz: every
        # limit the protocol needs) and no timestamp make room for the line checks (issue 28);
        # an 8-bit half period (MA down to 47 kHz at 24 MHz, below BiSS's 80 kHz and the host
        # tool's least MA rate) leaves room on top.
        overrides={"timer_width": 16, "timestamp_width": 0, "half_period_width": 8}),
    Board(
        "arty-a7-35", "Digilent Arty A7-35T (Artix-7), FT2232H USB-serial: vendor plan only",
        "arty_a7:ArtyA7_35Platform", "xilinx", "clk100", 100_000_000, 100_000_000,
        channels=(_pmod_channel(("pmod", 0), 1),
                  # JC: a pair per row position (1/2, 3/4, 7/8, 9/10 are routed as pairs).
                  Channel(("pmod", 2), {"ma": "7", "de": "8"}, slo_pair=("1", "2"))),
        leds={"heartbeat": ("led", 0), "ch0_valid_led": ("rgb_led", 0, "g"),
              "ch0_fault_led": ("rgb_led", 0, "r"), "ch1_valid_led": ("rgb_led", 1, "g"),
              "ch1_fault_led": ("rgb_led", 1, "r")},
        reset=("rst", 0),
        io_attrs={"IOSTANDARD": "LVCMOS33"}, slo_attrs={"PULLUP": "TRUE"},
        diff_attrs={"IOSTANDARD": "LVDS_25", "DIFF_TERM": "FALSE"},
        plan_only=True),
]}
