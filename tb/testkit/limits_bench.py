"""A clock-by-clock bench for ``BissMaster`` on Amaranth's simulator, for the limit tests.

Only the top's ports are used (``cfg_*``, ``start``, ``periodic``, ``abort_cycle``, ``rst``,
``ma``, ``slo`` and the results), so the tests hold across any internal restructuring.

Conventions (as in test_rtl_blocks.py): "cycle ``t``" is the stretch after the ``t``-th clock
edge; cycle 0 is the first clock after reset. A registered output read in cycle ``t`` is what the
edge ending cycle ``t - 1`` stored; an input set in cycle ``t`` is sampled by the edge ending it.

The encoder here is a tiny explicit stimulus written from docs/protocol.md
(``docs/protocol.md`` section 2): SLO low from the 2nd MA rise (Ack) for
``ack_slots`` rises, then Start, CDS and the word bits (built by the independent encoder model),
then the stop bit, low, and SLO low through the encoder's timeout until ``release`` clocks after
MA stopped. Nothing in it comes from ``rtl/``.
"""

from collections import deque
from dataclasses import dataclass, field, replace

from amaranth.hdl import ClockDomain, Elaboratable, Module, Mux, Signal
from amaranth.lib.wiring import Out
from amaranth.sim import Simulator

# The package's exports, not its module layout: the top may move between modules.
from bissmaster import BissMaster, Crc, MasterParams
from encoder_model.frames import CRC6, FrameFormat, WordFormat, WordValue, build_frame
from master_contract import CRC_CODE

#: System clock of the bench: 1 MHz, so that the protocol's 40 us is 40 clocks and a default
#: (``cfg_* = 0``) can be probed at its boundary in a short simulation.
SYS_CLK_HZ = 1_000_000
#: A small one-word build: the limits do not depend on the word widths, and it simulates fast.
MAX_LINE_DELAY = 63                 # also the default of cfg_delay_limit = 0
PARAMS = MasterParams(sys_clk_hz=SYS_CLK_HZ, max_data_bits=(8,), word_crcs=((Crc.CRC6,),),
                      max_line_delay=MAX_LINE_DELAY, timer_width=16, counter_width=8,
                      timestamp_width=0)
#: The same build with the default build's line-delay port and timer width: ``max_line_delay``
#: 4095 (``line_delay`` 13 bits wide) and 24-bit timers (an Ack limit long enough for round trips
#: beyond 8191 clocks and for 65535 Ack slots).
WIDE_PARAMS = replace(PARAMS, max_line_delay=4095, timer_width=24)
#: Word 0 of every frame: 4 position bits, nE, nW and CRC-6 (12 frame bits).
WORD = WordFormat(4, nenw=True, crc=CRC6)
POSITION = 0b1011
#: Start, CDS and the word's bits, from the independent encoder model.
FRAME = build_frame(FrameFormat("limits", (WORD,)), [WordValue(POSITION)])


def clocks(seconds):
    """A protocol time in system clocks of the bench (rounded up)."""
    return -(-round(seconds * SYS_CLK_HZ * 1e6) // 10**6)


def base_config(hp=2, **overrides):
    """``cfg_*`` inputs: half period ``hp``, word 0 as :data:`WORD`, every limit at 0."""
    cfg = {
        "cfg_ma_half_period": hp,
        "cfg_request_period": 0,
        "cfg_break_time": 0,
        "cfg_ack_limit": 0,
        "cfg_timeout_limit": 0,
        "cfg_delay_limit": 0,
        "cfg_end_check": 0,
        "cfg_w0_data_bits": WORD.data_bits,
        "cfg_w0_nenw": int(WORD.nenw),
        "cfg_w0_lc": int(WORD.lc),
        "cfg_w0_crc": CRC_CODE[WORD.crc],
    }
    cfg.update(overrides)
    return cfg


@dataclass
class Encoder:
    """SLO as a function of MA, clock by clock.

    hp         : MA half period, in clocks.
    ack_slots  : Ack slots: SLO low from the 2nd rise for this many rises, Start at the next.
    bits       : what follows the Ack: Start, CDS, the word bits; then the stop bit (low) and
                 the timeout (low).
    round_trip : clocks from the clock in which MA is seen rising to the clock in which the SLO
                 pin shows the answer (0 = the same clock). Every level, the release included,
                 comes this much later.
    release    : the timeout ends (SLO high) this many clocks after MA stopped, that is after the
                 stop bit's rise + ``hp`` (the master stops MA right after the stop bit's rise).
                 May be negative, down to ``1 - hp``.
    present    : False: no encoder, SLO stays high.
    timeout    : None, or the encoder's timeout for a frame cut short: MA high for this many
                 clocks in a row ends whatever the encoder was sending (SLO high, the round trip
                 later), as when the master stops clocking mid-frame (a reset). Keep it above
                 ``hp + release`` so that it does not end a whole frame early.
    """
    hp: int
    bits: list
    ack_slots: int = 1
    round_trip: int = 0
    release: int = 4
    present: bool = True
    timeout: int | None = None
    _t: int = -1
    _high: int = 0
    _ma_prev: int = 1
    _rises: int = 0
    _stop_rise: int | None = None
    _idle: bool = True
    _line: deque = field(default_factory=deque)

    def step(self, ma):
        """The SLO pin level for this clock, given this clock's MA pin level."""
        self._t += 1
        if self._idle and self._ma_prev and not ma:            # MA falls: a new cycle
            self._idle, self._rises, self._stop_rise = False, 0, None
        if ma and not self._ma_prev:
            self._rises += 1
            if self._rises - 2 == self.ack_slots + len(self.bits):
                self._stop_rise = self._t
        self._ma_prev = ma
        self._high = self._high + 1 if ma else 0
        if self.timeout is not None and self._high >= self.timeout:
            self._idle = True
        self._line.append(self._sent())
        return self._line.popleft() if len(self._line) > self.round_trip else 1

    def _sent(self):
        if not self.present or self._idle or self._rises < 2:
            return 1
        slot = self._rises - 2              # slot k is sent at rise k + 2
        if slot < self.ack_slots:
            return 0                        # Ack
        if slot - self.ack_slots < len(self.bits):
            return self.bits[slot - self.ack_slots]
        if self._stop_rise is not None and self._t >= self._stop_rise + self.hp + self.release:
            self._idle = True
            return 1
        return 0                            # stop bit, then the timeout


#: Outputs recorded in every cycle.
TRACE = ("ma", "busy", "done", "valid", "status", "overrun", "line_delay", "word0_position")
COUNTS = ("no_ack", "no_start", "delay_range", "slo_stuck_low", "overrun", "aborted", "no_stop",
          "crc_word0")


@dataclass
class Run:
    trace: list          # per cycle: {name: value} for TRACE
    counts: dict         # count_<name> at the end

    def cycles(self, name):
        return [t for t, x in enumerate(self.trace) if x[name]]

    @property
    def dones(self):
        return [(t, self.trace[t]["status"]) for t in self.cycles("done")]

    @property
    def rises(self):
        ma = [x["ma"] for x in self.trace]
        return [t for t in range(1, len(ma)) if ma[t] and not ma[t - 1]]

    @property
    def falls(self):
        ma = [x["ma"] for x in self.trace]
        return [t for t in range(1, len(ma)) if not ma[t] and ma[t - 1]]


def simulate(cfg, encoder, n_cycles, drive=None, params=None, trace=None):
    """Run ``n_cycles`` clocks. ``drive(t, run)`` returns the control inputs for cycle ``t``
    (``start``, ``periodic``, ``abort_cycle``, ``cfg_*`` changes, or ``rst``: the ``sync``
    domain's synchronous reset, the core's ``rst`` port); ``run`` holds the trace so far. Inputs
    keep their value until changed. ``params``: the build (default :data:`PARAMS`); ``trace``:
    the outputs recorded in every cycle (default :data:`TRACE`; ``"outputs"``: every output
    port). The counters are read at the end in builds that have them."""
    params = PARAMS if params is None else params
    dut = BissMaster(params)
    top = Module()
    top.domains.sync = domain = ClockDomain("sync")
    top.submodules.dut = dut
    run = Run([], {})

    def pin(name):
        return domain.rst if name == "rst" else getattr(dut, name)

    async def bench(ctx):
        for name, value in cfg.items():
            ctx.set(getattr(dut, name), value)
        if trace == "outputs":
            names = [name for name, member in dut.signature.members.items()
                     if member.flow == Out]
        else:
            names = TRACE if trace is None else trace
        ports = {name: getattr(dut, name) for name in names}
        for t in range(n_cycles):
            ctx.set(dut.slo, encoder.step(ctx.get(dut.ma)))
            for name, value in (drive(t, run) if drive else {}).items():
                ctx.set(pin(name), value)
            run.trace.append({name: ctx.get(port) for name, port in ports.items()})
            await ctx.tick()
        if params.counters:
            run.counts.update({name: ctx.get(getattr(dut, f"count_{name}")) for name in COUNTS})

    sim = Simulator(top)
    sim.add_clock(1 / SYS_CLK_HZ)
    sim.add_testbench(bench)
    sim.run()
    return run


class LogicEncoder(Elaboratable):
    """:class:`Encoder`'s stimulus as logic, for runs too long for a Python step per clock (an
    Ack of 65000 slots is 262k clocks at hp 2): the same SLO, clock for clock, for an
    :class:`Encoder` with ``timeout`` set (the frame ends when MA has been high ``timeout``
    clocks in a row: after the stop bit, or after a frame cut short) and ``release`` out of
    play. ``ack_slots`` is a signal: the bench may change it between cycles.

    Counts for the bench: ``cycle_rises``, the MA rising edges of the current (or last) cycle;
    ``second_rise``, the clock (``now``) of its 2nd; ``last_rise``, the clock of its last.
    """

    def __init__(self, dut, bits, round_trip=0, timeout=16):
        self.dut, self.bits, self.round_trip, self.timeout = dut, list(bits), round_trip, timeout
        self.ack_slots = Signal(17)
        self.now = Signal(32)
        self.cycle_rises = Signal(20)
        self.second_rise = Signal(32)
        self.last_rise = Signal(32)

    def elaborate(self, platform):
        m = Module()
        m.submodules.dut = dut = self.dut
        ma = dut.ma
        ma_prev = Signal(init=1)
        idle = Signal(init=1)
        high = Signal(range(self.timeout + 1))
        new_cycle = idle & ma_prev & ~ma                      # MA falls: a new cycle
        rise = ma & ~ma_prev
        rises = Mux(new_cycle, 0, self.cycle_rises + rise)    # this clock's count, as step()
        high_now = Mux(ma, Mux(high == self.timeout, high, high + 1), 0)
        idle_now = (idle & ~new_cycle) | (high_now == self.timeout)
        m.d.sync += [ma_prev.eq(ma), self.cycle_rises.eq(rises), high.eq(high_now),
                     idle.eq(idle_now), self.now.eq(self.now + 1)]
        with m.If(rise):
            m.d.sync += self.last_rise.eq(self.now)
            with m.If(rises == 2):
                m.d.sync += self.second_rise.eq(self.now)
        # The level sent: slot k at rise k + 2; Ack, Start .. CRC (``bits``), then low.
        slot = Signal(21)
        sent = Signal()
        m.d.comb += slot.eq(rises - 2)
        with m.If(idle_now | (rises < 2)):
            m.d.comb += sent.eq(1)
        with m.Elif(slot < self.ack_slots):
            m.d.comb += sent.eq(0)
        with m.Else():
            with m.Switch(slot - self.ack_slots):
                for k, bit in enumerate(self.bits):
                    with m.Case(k):
                        m.d.comb += sent.eq(bit)
                with m.Default():
                    m.d.comb += sent.eq(0)                    # the stop bit, the timeout
        line = sent
        for _ in range(self.round_trip):
            delayed = Signal(init=1)
            m.d.sync += delayed.eq(line)
            line = delayed
        m.d.comb += dut.slo.eq(line)
        return m


@dataclass
class Frame:
    """One cycle of :func:`simulate_frames`; clocks are ``LogicEncoder.now`` values."""
    ack_slots: int
    second_rise: int
    done: int
    status: int
    position: int
    line_delay: int
    rises: int
    last_rise: int
    idle: int           # the first clock with ``busy`` = 0 again


def simulate_frames(cfg, ack_slots, round_trip=0, timeout=16, params=None, bits=None):
    """One request cycle for each entry of ``ack_slots`` (the Ack's length in slots), each
    requested in the first idle clock after the previous one (the first after the power-up
    break), with a :class:`LogicEncoder` sending ``bits`` (default :data:`FRAME`) and the build
    ``params`` (default :data:`PARAMS`)."""
    params = PARAMS if params is None else params
    dut = BissMaster(params)
    enc = LogicEncoder(dut, FRAME if bits is None else bits, round_trip, timeout)
    frames = []

    async def bench(ctx):
        for name, value in cfg.items():
            ctx.set(getattr(dut, name), value)
        for n in ack_slots:
            ctx.set(enc.ack_slots, n)
            if ctx.get(dut.busy):
                await ctx.tick().until(~dut.busy)
            ctx.set(dut.start, 1)
            await ctx.tick()
            ctx.set(dut.start, 0)
            done, status, position, line_delay = await ctx.tick().sample(
                enc.now, dut.status, dut.word0_position, dut.line_delay).until(dut.done)
            idle, = await ctx.tick().sample(enc.now).until(~dut.busy)
            frames.append(Frame(n, ctx.get(enc.second_rise), done, status, position, line_delay,
                                ctx.get(enc.cycle_rises), ctx.get(enc.last_rise), idle))

    sim = Simulator(enc)
    sim.add_clock(1 / SYS_CLK_HZ)
    sim.add_testbench(bench)
    sim.run()
    return frames
