"""Formal harnesses: Amaranth elaboratables that wrap the real blocks of the core.

Each harness drives the block's inputs from free inputs of its own (:meth:`Harness.any_seq`: a
fresh free value every clock; :meth:`Harness.any_const`: one free value for the whole trace),
narrows them with ``Assume``, observes the
outputs with counters and shift registers of its own, and states the property with ``Assert``
(and ``Cover`` for non-vacuity). The clock domain has no reset: every register starts from its
``init`` value in the base case, and from any value in an induction step.

Expected values are never taken from the RTL: phase lengths are counted by the harness, the
frame is parsed by the harness from its own reading of the configuration, and the CRCs are
computed by a bit-serial LFSR written here from docs/protocol.md (section 6), not with
``amaranth.lib.crc`` that the RTL uses.

``mutation`` names a deliberate weakening (an assumption dropped, a wrong reference) for which
the solver must find a counterexample: it shows that the assertions can fail, i.e. that a PASS
is not vacuous. ``lemmas`` adds assertions about internal registers that make the properties
k-inductive; they are proven like the others, never assumed. Every internal of the core that
the harnesses name (for lemmas, and the master's receiver signals) is in :data:`INTERNALS`.

Only Amaranth's public API is used: free values are undriven inputs of the harness (Amaranth 0.5
exports ``AnyConst``/``AnySeq`` only from its private ``amaranth.hdl._ast``, and from
``amaranth.asserts``, the 0.4 module whose other names 0.5 deprecates), and internals are found
through public fragment attributes (``flow.Internals``).
"""

from dataclasses import dataclass

from amaranth.hdl import (Array, Assert, Assume, C, Cat, ClockDomain, Cover, Elaboratable,
                          Module, Mux, Signal, Value, signed)
from amaranth.lib import wiring

import protocol_facts as facts
from bissmaster.core.confirmation import Confirmation
from bissmaster.core.frame_decoder import FrameDecoder
from bissmaster.core.frame_verdict import FrameVerdict
from bissmaster.core.ma_clock import MaClock
from bissmaster.master import BissMaster
from bissmaster.core.field_ends import FIELD_ENDS
from bissmaster.params import CRC_SETTINGS, Crc
from bissmaster.control.register_access import RegisterAccess
from bissmaster.core.slo_sampler import SloSampler
from master_contract import (CA_STATUS, CHECK_OFF, CONFIRM_FRAMES_DEFAULT, CONFIRM_NEUTRAL,
                             FRAME_STATUSES, MA_HALF_PERIOD_MIN, STATUS)

from .flow import Internals

# =============================================================================================
# Where the harnesses reach inside the core: every fragment path and name, in one table
# =============================================================================================

#: ``role: (kind, path, name)``. Kinds: ``"signal"``, a signal that the fragment at ``path``
#: assigns (a register or a wire of that block); ``"port"``, a port of the component that
#: fragment was elaborated from; ``"fsm"``, an FSM of that fragment (the states are named where
#: they are used); ``"block"``, a sub-block of the master, below which that block's own entries
#: apply. Paths are ``/``-separated submodule names from the block under test (``""``: the block
#: itself); ``{w}`` is a word number, ``{crc}`` ``crc6`` or ``crc16``. The master is being split
#: into components: when a path or a name changes in the RTL, change it here. An entry that no
#: longer matches stops the build with a ``LookupError`` naming it (never a silent pass).
INTERNALS = {
    # MaClock
    "ma_clock.fsm": ("fsm", "", "ma_fsm"),                      # states LOW, HIGH
    "ma_clock.phase_left": ("signal", "", "phase_left"),        # clocks left in the MA phase
    "ma_clock.busy": ("port", "", "busy"),
    "ma_clock.half_period": ("port", "", "half_period"),
    "ma_clock.run": ("port", "", "run"),
    "ma_clock.hold": ("port", "", "hold"),                      # CDM builds: hold MA low
    # SloSampler
    "sampler.fsm": ("fsm", "", "sampler_fsm"),                  # states MEASURE, SAMPLE
    "sampler.slot_left": ("signal", "", "slot_left"),           # clocks to the next event
    "sampler.slot_zero": ("signal", "", "slot_zero"),
    "sampler.phase": ("signal", "", "phase"),                   # next event: vote 1, centre, 3
    "sampler.first_slot": ("signal", "", "first_slot"),         # slot 0 (the Ack) not decided
    "sampler.vote": ("signal", "", "vote"),                     # the vote spacing
    "sampler.single": ("signal", "", "single"),                 # one sample per slot (hp 2)
    "sampler.first_load": ("signal", "", "first_load"),         # timer: edge to the first vote
    "sampler.vote_load": ("signal", "", "vote_load"),           # ... vote to vote
    "sampler.vote_one": ("signal", "", "vote_one"),             # the vote spacing is 1
    "sampler.gap": ("signal", "", "gap"),                       # a fall now is ambiguous
    "sampler.mid_slot": ("signal", "", "mid_slot"),             # slot timer, edge halfway
    "sampler.odd": ("signal", "", "odd"),                       # clocks since the fall, odd
    "sampler.sample": ("port", "", "sample"),
    "sampler.bit": ("port", "", "bit"),
    # FrameDecoder
    "decoder.fsm": ("fsm", "", "decoder_fsm"),                  # states ACK, CDS, WORD, ...
    "decoder.sample": ("port", "", "sample"),                   # the decision it consumes ...
    "decoder.bit": ("port", "", "bit"),                         # ... (the sampler's, a clock late)
    "decoder.idx": ("signal", "", "idx"),                       # bit index in the word
    "decoder.word": ("signal", "", "word"),                     # word index (builds of 2+ words)
    "decoder.crc_reg": ("signal", "crc", "reg"),                # the CrcEngine's shift register
    "decoder.crc_mismatch": ("signal", "crc", "mismatch"),      # a received CRC bit differed
    "decoder.crc_settings": ("signal", "crc", "settings"),      # the current word's CRC
    "decoder.crc_next": ("signal", "", "crc_next_word"),        # the word the engine loads next
    "decoder.ends_current": ("signal", "field_ends", "current_ends"),      # its field ends ...
    "decoder.ends_following": ("signal", "field_ends", "following_ends"),  # ... the next word's
    "decoder.ends_pick": ("signal", "field_ends", "following_word"),  # ... the word loaded next
    "decoder.crc_ok": ("port", "", "crc_ok"),                   # the verdict per word
    "decoder.in_crc": ("signal", "", "in_crc"),                 # the bit is a received CRC bit
    # BissMaster
    "master.ma_clock": ("block", "ma_clock", None),
    "master.sampler": ("block", "sampler", None),
    "master.decoder": ("block", "decoder", None),
    "master.cycle_fsm": ("fsm", "controller", "cycle_fsm"),     # WAIT_READY, CLOCK, TAIL, END
    "master.latched": ("port", "controller", "first_clock"),    # WAIT_READY's first clock
    "master.cfg_ok": ("signal", "config", "ok"),                # registered configuration check
    "master.receiver_clear": ("signal", "controller", "receiver_clear"),  # sampler/decoder reset
    "master.request": ("port", "scheduler", "request"),         # the controller's request input
    "master.cdm_cycle": ("port", "controller", "cdm_cycle"),    # the cycle's CDM bit
    # RegisterAccess
    "access.fsm": ("fsm", "sequencer", "access_fsm"),           # IDLE, LEAD, HEADER, ...
    "access.step": ("signal", "sequencer", "step"),             # frame in header / register
    "access.index": ("port", "sequencer", "index"),             # the register in progress
    "access.waited": ("signal", "sequencer", "waited"),         # frames waited for a start bit
    "access.idle_run": ("signal", "idle", "idle_run"),          # consecutive CDM = 0 frames
    "access.idle_seen": ("signal", "idle", "idle_seen"),        # ... that delivered a good frame
    "access.ending": ("signal", "sequencer", "ending"),         # the status a cancel ends with
    "access.header": ("signal", "sender", "header"),            # the header's CDM bits, MSB 1st
    "access.request": ("signal", "sequencer", "req"),           # the request latched at start
    # Confirmation (in _JudgedFrame)
    "confirm.left": ("signal", "confirmation", "left"),         # frames still to confirm
}


class Inside:
    """The :data:`INTERNALS` of an elaborated block (``flow.Internals`` does the search).
    ``at``: the path of the block inside the design (``block()`` gives a sub-block's view)."""

    def __init__(self, design, at=""):
        self.internals = design if isinstance(design, Internals) else Internals(design)
        self.fragment = self.internals.fragment
        self.at = at

    def _entry(self, role, kinds, fmt):
        kind, path, name = INTERNALS[role]
        if kind not in kinds:
            raise LookupError(f"INTERNALS[{role!r}] is a {kind}, not a {' or '.join(kinds)}")
        path = "/".join(p for p in (self.at, path.format(**fmt)) if p)
        return kind, path, name.format(**fmt) if name else name

    def block(self, role):
        """The view of a sub-block (a ``"block"`` entry)."""
        path = self._entry(role, ("block",), {})[1]
        _named(role, self.internals.fragment_at, path)
        return Inside(self.internals, path)

    def __call__(self, role, **fmt):
        """The signal or port of entry ``role``."""
        kind, path, name = self._entry(role, ("signal", "port"), fmt)
        find = self.internals.port if kind == "port" else self.internals.signal
        return _named(role, find, path, name)

    def in_state(self, role, state):
        """1 while the FSM of entry ``role`` is in ``state``."""
        _, path, name = self._entry(role, ("fsm",), {})
        return _named(role, self.internals.in_state, path, name, state)


def _named(role, find, *args):
    """``find(*args)``, a LookupError naming the :data:`INTERNALS` entry to fix."""
    try:
        return find(*args)
    except LookupError as exc:
        raise LookupError(f"INTERNALS[{role!r}]: {exc}") from None


class Harness(Elaboratable):
    """Base: the harness owns the ``sync`` domain (no reset). Its ports are its clock and its
    free inputs (made during elaboration: ``flow.build`` elaborates before it reads ``ports``).
    The keyword arguments (a subclass's settings) become attributes."""

    def __init__(self, **settings):
        self.cd = ClockDomain("sync", reset_less=True)
        self.free_inputs = []
        for name, value in settings.items():
            setattr(self, name, value)

    @property
    def ports(self):
        return [self.cd.clk, *self.free_inputs]

    def _module(self):
        """A Module whose ``sync`` domain is the harness's."""
        m = Module()
        m.domains.sync = self.cd
        self.free_inputs = []
        return m

    def any_seq(self, shape, name):
        """A free value in every clock: an input of the harness that nothing drives
        (yosys-smtbmc gives every top-level input a free value in every step)."""
        value = Signal(shape, name=name)
        self.free_inputs.append(value)
        return value

    def any_const(self, m, shape, name):
        """One free value for the whole trace: a free input taken in the first clock and
        held in a register from then on (anywhere in an induction step as well)."""
        fresh = self.any_seq(shape, f"{name}_in")
        held = Signal(shape, name=f"{name}_held")
        loaded = Signal(name=f"{name}_loaded")
        value = Signal(shape, name=name)
        m.d.comb += value.eq(Mux(loaded, held, fresh))
        m.d.sync += [held.eq(value), loaded.eq(1)]
        return value

    def drive_free(self, m, dut, exclude=()):
        """Every input port of ``dut`` from a free input of the same name, except the names
        in ``exclude``."""
        for name, member in dut.signature.members.items():
            if member.flow == wiring.In and name not in exclude:
                port = getattr(dut, name)
                m.d.comb += port.eq(self.any_seq(len(port), name))


class _PhaseMonitor:
    """Counts clocks between transitions of a line and checks every phase against a reference.

    ``since`` is the number of clocks since the line last changed (saturating, starts high: the
    line has been idle since long before the trace). At every transition the phase that just
    ended is checked: at least ``hp_phase`` clocks; a low phase exactly ``hp_phase`` (1:1 duty);
    a high phase exactly ``hp_phase`` too unless ``idle_seen`` (the clock stopped in between).
    ``hp_phase`` is the reference latched at the transition that began the phase.
    """

    def __init__(self, m, line, hp_now, stopped, width=18):
        self.prev = prev = Signal(init=1, name="mon_prev")
        self.since = since = Signal(width, init=(1 << width) - 1, name="mon_since")
        self.hp_phase = hp_phase = Signal(16, name="mon_hp_phase")
        self.idle_seen = idle_seen = Signal(init=1, name="mon_idle_seen")
        self.edge = edge = Signal(name="mon_edge")
        self.fall = fall = Signal(name="mon_fall")
        self.rise = rise = Signal(name="mon_rise")
        m.d.comb += [edge.eq(line != prev), fall.eq(prev & ~line), rise.eq(~prev & line)]
        m.d.sync += prev.eq(line)
        # ``since`` counts the clocks of the current phase, the current clock included.
        with m.If(edge):
            m.d.sync += [since.eq(1), hp_phase.eq(hp_now), idle_seen.eq(stopped)]
        with m.Else():
            with m.If(since != (1 << width) - 1):
                m.d.sync += since.eq(since + 1)
            with m.If(stopped):
                m.d.sync += idle_seen.eq(1)
        # The phase that ends at this transition lasted ``since`` clocks.
        self.short = short = Signal(name="mon_short")
        self.low_wrong = low_wrong = Signal(name="mon_low_wrong")
        self.high_wrong = high_wrong = Signal(name="mon_high_wrong")
        m.d.comb += [
            short.eq(edge & (since < hp_phase)),
            low_wrong.eq(rise & (since != hp_phase)),
            high_wrong.eq(fall & ~idle_seen & (since != hp_phase)),
        ]


# =============================================================================================
# (a) MA: idles high, no phase shorter than the half period
# =============================================================================================

def _check_ma(m, ma, hp, clock_busy, inside, lemmas, run=None, hold=None):
    """The MA properties of one MaClock instance, with ``hp`` the half period it must honour.

    ``clock_busy`` is the MaClock's own busy, ``inside`` its :class:`Inside`. Lemmas relate the harness's phase counter to the
    block's FSM and phase timer; they are asserted (so proven), never assumed.

    With the CDM hold (``run`` and ``hold``, MaClock's inputs, given): a fall that follows a
    high phase whose last clock had ``run`` low is a hold; such a low phase may be longer than
    the half period (never shorter), and it only happens when ``hold`` was high there: with
    ``hold`` low (CDM = 0) MA idles high exactly as without the hold.
    """
    mon = _PhaseMonitor(m, ma, hp, stopped=~clock_busy)
    cdm = hold is not None
    low_wrong = mon.low_wrong
    if cdm:
        run_prev = Signal(name="mon_run_prev")
        hold_prev = Signal(name="mon_hold_prev")
        in_hold = Signal(name="mon_in_hold")        # the current low phase is a CDM hold
        m.d.sync += [run_prev.eq(run), hold_prev.eq(hold)]
        with m.If(mon.fall):
            m.d.sync += in_hold.eq(~run_prev)
        low_wrong = mon.low_wrong & ~in_hold
        m.d.comb += Assert(~(mon.fall & ~run_prev) | hold_prev,
                           "MA falls after a stop only for CDM = 1 (hold high)")
    m.d.comb += [
        Assert(clock_busy | ma, "MA high while the clock is idle"),
        Assert(~mon.short, "no MA phase shorter than the half period"),
        Assert(~low_wrong, "every low phase exactly one half period (CDM holds: at least)"),
        Assert(~mon.high_wrong, "every high phase inside a burst exactly one half period"),
    ]
    if lemmas:
        phase_left = inside("ma_clock.phase_left")
        low = inside.in_state("ma_clock.fsm", "LOW")
        high = inside.in_state("ma_clock.fsm", "HIGH")
        edge = mon.edge
        if cdm:
            held = inside.in_state("ma_clock.fsm", "HOLD")
            release = inside.in_state("ma_clock.fsm", "RELEASE")
            idle = inside.in_state("ma_clock.fsm", "IDLE")
            m.d.comb += [
                Assert(idle | low | high | held | release, "lemma: MaClock in a state"),
                Assert(ma == ~(low | held), "lemma: MA low exactly in LOW and HOLD"),
                Assert(clock_busy == (low | high | held | release), "lemma: busy states"),
                Assert(ma | edge | (in_hold == held), "lemma: a hold phase is HOLD"),
                # HOLD counts its half period down to 0 and stays there.
                Assert(~held | edge | (mon.since + 1 + phase_left == mon.hp_phase)
                       | (phase_left == 0) & (mon.since + 1 >= mon.hp_phase),
                       "lemma: hold phase counter"),
                Assert(~clock_busy | held | edge | (mon.since + 1 + phase_left == mon.hp_phase),
                       "lemma: phase counter"),
            ]
        else:
            m.d.comb += [
                Assert(ma == ~low, "lemma: MA low exactly in LOW"),
                Assert(clock_busy == (low | high), "lemma: busy in LOW and HIGH"),
                # In a phase: clocks spent (``since`` + this one) + clocks left = half period.
                Assert(~clock_busy | edge | (mon.since + 1 + phase_left == mon.hp_phase),
                       "lemma: phase counter"),
            ]
        m.d.comb += [
            # An MA edge loads the phase timer with the half period.
            Assert(~edge | (clock_busy & (phase_left + 1 == hp)), "lemma: edge loads timer"),
            Assert(~clock_busy | edge | (mon.hp_phase == hp), "lemma: phase's half period"),
            Assert(~low | edge | ~mon.idle_seen, "lemma: low phases never see idle"),
            # Idle: the high phase so far already lasts a full half period.
            Assert(clock_busy | (mon.since >= mon.hp_phase), "lemma: idle after a full phase"),
        ]
    return mon


class MaClockHarness(Harness):
    """MaClock alone: ``run`` free every clock; ``half_period`` free, at least 2, and held
    while the clock is busy (the master latches it for the whole cycle).

    Properties: MA is high whenever the block is not busy; every high and low phase lasts at
    least the half period; low phases, and high phases inside a burst, last exactly the half
    period. Lemmas (for induction, proven as well): the phase counter of the harness and the
    block's ``phase_left`` add up to the half period; MA is low exactly in state LOW.

    ``hp_max`` bounds the half period (None: any 16-bit value). Mutation ``"hp_unstable"``
    lets the half period change in the middle of a burst: the solver must find a short phase.
    """

    def __init__(self, hp_max=None, lemmas=True, mutation=None, cdm=False):
        super().__init__(hp_max=hp_max, lemmas=lemmas, mutation=mutation, cdm=cdm)

    def elaborate(self, platform):
        m = self._module()
        dut = MaClock(cdm=self.cdm)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        hold = None
        if self.cdm:
            hold = self.any_seq(1, "hold")
            m.d.comb += dut.hold.eq(hold)
        run = self.any_seq(1, "run")
        hp = self.any_seq(16, "half_period")
        hp_prev = Signal(16)
        m.d.sync += hp_prev.eq(hp)
        m.d.comb += [dut.run.eq(run), dut.half_period.eq(hp)]
        m.d.comb += Assume(hp >= MA_HALF_PERIOD_MIN)
        if self.hp_max is not None:
            m.d.comb += Assume(hp <= self.hp_max)
        if self.mutation != "hp_unstable":
            m.d.comb += Assume(~dut.busy | (hp == hp_prev))

        mon = _check_ma(m, dut.ma, hp, dut.busy, inside, self.lemmas, run=run, hold=hold)
        if self.cdm:
            # Non-vacuity of the hold: a low phase longer than the half period.
            m.d.comb += Cover(mon.rise & (mon.since > mon.hp_phase) & (hp >= 3))

        # Non-vacuity: three full periods at a half period of at least 3, stop, and a restart.
        periods = Signal(4)
        with m.If(mon.rise & (hp < 3)):
            m.d.sync += periods.eq(0)
        with m.Elif(mon.rise & (periods != 15)):
            m.d.sync += periods.eq(periods + 1)
        m.d.comb += Cover((periods >= 3) & mon.fall & mon.idle_seen)
        return m


class MasterMaHarness(Harness):
    """The whole BissMaster's MA output. Every input is free at every clock (SLO, start,
    abort_cycle, every cfg_*), except ``periodic``, held low: ``start`` already produces every
    possible request pattern.

    The harness latches the live ``cfg_ma_half_period`` itself when the master accepts a request
    (idle, ``start``, no abort, no configuration error: all visible on the ports), and checks
    every MA phase against it; MA must be high whenever the master is idle.

    Lemmas (``lemmas=True``, for induction): the MaClock lemmas, the master's MaClock is idle
    while the master is idle, and the half period MaClock sees is the one the harness latched.
    Mutation ``"live_hp"``: check against the live setting instead of the latched one (the
    setting may change during a cycle, so the solver must find a "short" phase).
    """

    def __init__(self, params, lemmas=False, hp_max=None, mutation=None):
        super().__init__(params=params, lemmas=lemmas, hp_max=hp_max, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        dut = BissMaster(self.params)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        self.drive_free(m, dut, exclude=("periodic",))
        m.d.comb += dut.periodic.eq(0)
        if self.hp_max is not None:
            m.d.comb += Assume(dut.cfg_ma_half_period <= self.hp_max)

        # IDLE takes every request; an invalid configuration is refused in WAIT_READY. With the
        # register-access engine, the scheduler also requests cycles for it (periodic ticks
        # that the ports do not show): the request is then taken from the scheduler's output.
        request = inside("master.request") if self.params.register_access else dut.start
        accept = ~dut.busy & request & ~dut.abort_cycle
        hp_cycle = Signal(16)
        with m.If(accept):
            m.d.sync += hp_cycle.eq(dut.cfg_ma_half_period)
        hp_ref = dut.cfg_ma_half_period if self.mutation == "live_hp" else hp_cycle

        ma_clock = inside.block("master.ma_clock")
        clock_busy = ma_clock("ma_clock.busy")
        m.d.comb += Assert(dut.busy | dut.ma, "MA high while the master is idle")
        cdm = self.params.register_access
        mon = _check_ma(m, dut.ma, hp_ref, clock_busy, ma_clock, self.lemmas,
                        run=ma_clock("ma_clock.run") if cdm else None,
                        hold=ma_clock("ma_clock.hold") if cdm else None)
        if self.lemmas:
            hp_dut = ma_clock("ma_clock.half_period")
            in_cycle = 0
            # (CONFIRM: with the CDM hold it goes on to END.)
            for state in ("WAIT_READY", "CLOCK", "TAIL", "END", "CONFIRM"):
                in_cycle = in_cycle | inside.in_state("master.cycle_fsm", state)
            clocking = 0
            for state in ("CLOCK", "TAIL", "END", "CONFIRM"):
                clocking = clocking | inside.in_state("master.cycle_fsm", state)
            waiting = inside.in_state("master.cycle_fsm", "WAIT_READY")
            first = inside("master.latched")            # WAIT_READY's first clock
            cfg_ok = inside("master.cfg_ok")            # registered configuration check
            hp_ok = hp_cycle >= MA_HALF_PERIOD_MIN
            idle_state = inside.in_state("master.cycle_fsm", "IDLE")
            m.d.comb += [
                # The controller keeps ``idle`` as a register written with every transition.
                Assert(dut.busy == ~idle_state, "lemma: busy is the IDLE state's decode"),
                Assert(dut.busy | ~clock_busy, "lemma: MaClock idle while the master is idle"),
                # (The master may copy the settings in every idle clock: only a cycle's matter.)
                Assert(~(clock_busy | in_cycle) | (hp_dut == hp_cycle),
                       "lemma: MaClock's half period is the latched one"),
                # Only a valid configuration (half period >= 2) is ever clocked: WAIT_READY
                # refuses an invalid one in its first clock, from the registered check.
                Assert(~(clock_busy | clocking | waiting & (~first | cfg_ok)) | hp_ok,
                       "lemma: a cycle's half period is at least 2"),
            ]
            if cdm:
                # MaClock holds (and releases) only in a cycle whose CDM bit is 1; the bit is
                # copied only while idle, and the master is never idle while MaClock is busy.
                holding = (ma_clock.in_state("ma_clock.fsm", "HOLD")
                           | ma_clock.in_state("ma_clock.fsm", "RELEASE"))
                m.d.comb += Assert(~holding | inside("master.cdm_cycle"),
                                   "lemma: a hold only with the cycle's CDM = 1")

        # Non-vacuity: two request cycles with MA clocking, and back to idle.
        cycles = Signal(2)
        with m.If(accept & (cycles != 3)):
            m.d.sync += cycles.eq(cycles + 1)
        rises = Signal(2)
        with m.If(mon.rise & (rises != 3)):
            m.d.sync += rises.eq(rises + 1)
        m.d.comb += Cover((cycles >= 2) & (rises >= 3) & ~dut.busy)
        return m


# =============================================================================================
# (b) Every request cycle ends, and the master returns to idle, within a bound
# =============================================================================================

def _word_bits(dut, w):
    """Bits of word ``w`` on the line after CDS, from the live configuration ports (the
    harness's own reading of protocol section 5: data, nE/nW, LC, CRC)."""
    crc = getattr(dut, f"cfg_w{w}_crc")
    crc_bits = Mux(crc == Crc.CRC6, 6, Mux(crc == Crc.CRC16, 16, 0))
    return (getattr(dut, f"cfg_w{w}_data_bits")
            + Mux(getattr(dut, f"cfg_w{w}_nenw"), 2, 0)
            + Mux(getattr(dut, f"cfg_w{w}_lc"), 6, 0) + crc_bits)


@dataclass(frozen=True)
class LivenessLimits:
    """Small ranges for the runtime settings, so that a whole worst-case cycle fits in a BMC
    run: half period, Ack, timeout and break limits up to the given maxima; word formats from
    the given choices (data bits up to ``data_bits_max``, nE/nW and LC allowed or not, the
    CRC codes in ``crcs``)."""
    hp_max: int = 2
    ack_max: int = 6
    timeout_max: int = 2
    break_max: int = 2
    data_bits_max: int = 1
    nenw: bool = False
    lc: bool = False
    crcs: tuple = (Crc.NONE,)
    quiet_max: int = 2
    ssi_delay_max: int = 2

    @staticmethod
    def has_ssi(dut):
        """The build accepts ``cfg_ssi`` (docs/ports.md, "SSI mode")."""
        return hasattr(dut, "cfg_ssi")

    def assume(self, m, dut, words, *, time_min=0, crcs=True):
        """Assume the master's live settings within these limits. ``time_min`` 1 excludes
        the value 0 (the built-in default) for the Ack, timeout and break settings;
        ``crcs`` False leaves the CRC codes free."""
        m.d.comb += [
            Assume((dut.cfg_ma_half_period >= 2) & (dut.cfg_ma_half_period <= self.hp_max)),
            Assume((dut.cfg_ack_limit >= time_min) & (dut.cfg_ack_limit <= self.ack_max)),
            Assume((dut.cfg_timeout_limit >= time_min)
                   & (dut.cfg_timeout_limit <= self.timeout_max)),
            Assume((dut.cfg_break_time >= time_min) & (dut.cfg_break_time <= self.break_max)),
        ]
        if hasattr(dut, "cfg_quiet_time"):
            # The quiet time (docs/ports.md): 1 .. quiet_max clocks, never the 1 us default.
            m.d.comb += Assume((dut.cfg_quiet_time >= 1) & (dut.cfg_quiet_time <= self.quiet_max))
        if self.has_ssi(dut):
            # SSI frames (docs/ports.md, "SSI mode"): the set round trip within a small range,
            # as the other times (``cfg_ssi`` and the word's options stay free).
            m.d.comb += Assume(dut.cfg_ssi_delay <= self.ssi_delay_max)
        for w in range(words):
            cfg = {name: getattr(dut, f"cfg_w{w}_{name}") for name in ("data_bits", "nenw", "lc", "crc")}
            m.d.comb += Assume(cfg["data_bits"] <= self.data_bits_max)
            if not self.nenw:
                m.d.comb += Assume(~cfg["nenw"])
            if not self.lc:
                m.d.comb += Assume(~cfg["lc"])
            if crcs:
                crc_ok = 0
                for c in self.crcs:
                    crc_ok = crc_ok | (cfg["crc"] == c)
                m.d.comb += Assume(crc_ok)

    def max_frame_bits(self, words):
        crc = max({Crc.NONE: 0, Crc.CRC6: 6, Crc.CRC16: 16}[c] for c in self.crcs)
        return words * (self.data_bits_max + 2 * self.nenw + crc) + 6 * self.lc

    def max_ssi_stop_slot(self):
        """The SSI stop bit's index (docs/ports.md, "SSI mode"): N = data + the error bit or
        nE/nW (not both: invalid) + the CRC; N, or 2 N + 1 with the double transmission."""
        crc = max({Crc.NONE: 0, Crc.CRC6: 6, Crc.CRC16: 16}[c] for c in self.crcs)
        n = self.data_bits_max + max(1, 2 * self.nenw) + crc
        return 2 * n + 1

    def max_bound(self, words, slack):
        h = self.hp_max
        v = h // 2 if h >= 3 else 0
        biss = (1 + (self.timeout_max + self.quiet_max + 1) + (3 * h + 1) + (self.ack_max + 1)
                + (self.ack_max + 2 * h) + (self.max_frame_bits(words) + 1) * 2 * h + 3 + slack
                + 3 * h + (self.timeout_max + 1) + 2)       # the end check
        ssi = (1 + (self.timeout_max + self.quiet_max + 1) + (h + 1)
               + self.max_ssi_stop_slot() * 2 * h + (self.ssi_delay_max + h + v + 1) + 3 + slack
               + (self.timeout_max + 1) + 2)                # the end check
        return max(biss, ssi)

    def depth(self, words, slack):
        """BMC depth that holds power-up, the break, and the longest cycle, with a margin."""
        return self.break_max + 2 + self.max_bound(words, slack) + 3


class MasterLivenessHarness(Harness):
    """Bounded liveness of the whole BissMaster, as safety properties.

    Inputs: SLO, start, periodic, abort_cycle, clear_counters free at every clock (glitches,
    a missing or stuck encoder, any frame content); the cycle settings free at every clock
    within ``limits`` (the master latches them per cycle); ``cfg_break_time`` (read live) one
    free constant.

    The harness latches the settings itself at each accepted request and computes a bound
    from them (``bound_done``). Properties:

    1. every accepted request is answered by ``done`` within ``bound_done`` clocks, whatever
       SLO does, aborts included;
    2. ``busy`` falls within ``bound_idle`` clocks of the last of: power-up, an accepted
       request, an ``abort_cycle`` pulse.

    ``slack`` is added to both bounds (clocks of pipeline latency not modelled by the
    formula). Mutation ``"tight"`` drops the ``2 * half period`` per frame bit from the bound:
    the solver must then find a frame that takes longer.
    """

    def __init__(self, params, limits, slack=8, mutation=None):
        super().__init__(params=params, limits=limits, slack=slack, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        p, lim = self.params, self.limits
        dut = BissMaster(p)
        m.submodules.dut = dut

        self.drive_free(m, dut, exclude=("cfg_break_time",))
        m.d.comb += dut.cfg_break_time.eq(
            self.any_const(m, len(dut.cfg_break_time), "cfg_break_time"))
        lim.assume(m, dut, p.words, time_min=1)

        # The harness's copy of the cycle's settings. A request was accepted in the previous
        # clock if the master was idle there, saw no abort, and is busy now (an idle master
        # only leaves idle for an abort or an accepted request); the settings it latched are
        # the live ones of that clock.
        frame_bits = _word_bits(dut, 0)
        if p.words == 2:
            frame_bits = frame_bits + Mux(dut.cfg_w1_enable, _word_bits(dut, 1), 0)
        tw = p.timer_width
        has_ssi = lim.has_ssi(dut)
        ssi_live = C(0, 11)
        if has_ssi:
            ssi_delay_live = Signal(8)      # <= ssi_delay_max (assumed)
            m.d.comb += ssi_delay_live.eq(dut.cfg_ssi_delay)
            ssi_live = Cat(dut.cfg_ssi, dut.cfg_ssi_double, dut.cfg_ssi_error, ssi_delay_live)
        live = Cat(dut.cfg_ma_half_period, dut.cfg_ack_limit, dut.cfg_timeout_limit,
                   frame_bits[:8], dut.cfg_end_check, dut.cfg_quiet_time[:4], ssi_live)
        snapshot = Signal(len(live))
        could_accept = Signal()
        m.d.sync += [snapshot.eq(live), could_accept.eq(~dut.busy & ~dut.abort_cycle)]
        accepted = Signal()
        m.d.comb += accepted.eq(could_accept & dut.busy)
        hp, ack, timeout, bits = (snapshot[:16], snapshot[16:16 + tw], snapshot[16 + tw:16 + 2 * tw],
                                  snapshot[16 + 2 * tw:16 + 2 * tw + 8])
        end_check = snapshot[16 + 2 * tw + 8]
        quiet = snapshot[16 + 2 * tw + 9:16 + 2 * tw + 13]
        ssi, ssi_double, ssi_error, ssi_delay = (snapshot[-11], snapshot[-10], snapshot[-9],
                                                 snapshot[-8:])
        # SSI (docs/ports.md, "SSI mode"): the word's N bits (data, the error bit, nE/nW, CRC;
        # no LC), the stop bit's index N, or 2 N + 1 with the double transmission (the word,
        # one 0, the word again).
        ssi_bits = bits + ssi_error
        ssi_stop = Mux(ssi_double, 2 * ssi_bits + 1, ssi_bits)

        # The bound, clock by clock: 1 to leave IDLE; WAIT_READY up to the timeout limit + the
        # quiet time + 1 (SLO high pulses shorter than the quiet time do not end the low time:
        # the timeout limit is reached, or SLO stays high for the quiet time);
        # MA to its second rise (3 half periods + 1: the sampler is armed); the Ack edge and the
        # slot-0 sample up to the Ack limit + 1; the Start sample up to the Ack limit + one MA
        # period after that (the NO_START limit on the sampler's decisions); CDS and the frame
        # bits, one MA period (2 half periods) each; ``done`` 3 clocks after the last sample
        # (the register to the decoder, decoder and output registers). With the end check,
        # ``done`` waits for the stop bit's sample and MA's
        # stop (at most 3 half periods), then SLO high up to the timeout limit + 1, then the
        # verdict (2 clocks). The half period takes few values: one formula with constant
        # factors per value (a product of two variables would slow the solver down a lot).
        # An SSI cycle (docs/ports.md, "SSI mode"): the same wait for the quiet line; MA to its
        # first rise (h + 1: the sampler is armed there); bit k is put on SLO at rise k + 1, so
        # the stop bit's rise comes ``ssi_stop`` MA periods later; its decision the set round
        # trip + h + v + 1 after that rise ("exactly as a BiSS bit after a measured round
        # trip": the NO_ACK row's ``line_delay + hp + v + 1``); ``done`` 3 clocks after it
        # ("Latency"). With the end check: MA has stopped by then (its last rise is the stop
        # bit's), so SLO high within the timeout limit + 1, then the verdict (2 clocks).
        def formula(h):
            per_bit = 0 if self.mutation == "tight" else 2 * h
            v = h // 2 if h >= 3 else 0     # the vote spacing (docs/ports.md, "Noise immunity")
            biss = (1 + (timeout + quiet + 1) + (3 * h + 1) + (ack + 1) + (ack + 2 * h)
                    + (bits + 1) * per_bit + 3 + self.slack
                    + Mux(end_check, 3 * h + (timeout + 1) + 2, 0))
            if not has_ssi:
                return biss
            ssi_bound = (1 + (timeout + quiet + 1) + (h + 1) + ssi_stop * per_bit
                         + (ssi_delay + h + v + 1) + 3 + self.slack
                         + Mux(end_check, (timeout + 1) + 2, 0))
            return Mux(ssi, ssi_bound, biss)
        bound = formula(lim.hp_max)
        for h in range(lim.hp_max - 1, 1, -1):
            bound = Mux(hp == h, formula(h), bound)
        bound_done = Signal(16)
        with m.If(accepted):
            m.d.sync += bound_done.eq(bound)
        # BREAK: the break time; in an SSI cycle the timeout limit as well (docs/ports.md,
        # "SSI mode": "BREAK (after an abort or a fault) lasts cfg_timeout_limit as well as
        # cfg_break_time").
        cycle_ssi, cycle_timeout = Signal(), Signal(tw)
        with m.If(accepted):
            m.d.sync += [cycle_ssi.eq(ssi), cycle_timeout.eq(timeout)]
        pause = Mux(cycle_ssi & (cycle_timeout > dut.cfg_break_time), cycle_timeout,
                    dut.cfg_break_time)
        bound_idle = Signal(16)
        m.d.comb += bound_idle.eq(bound_done + 4 * lim.hp_max + pause + self.slack)

        # 1. ``done`` answers every accepted request.
        pending = Signal()
        waited = Signal(10)
        with m.If(accepted):
            m.d.sync += [pending.eq(1), waited.eq(1)]
        with m.Elif(dut.done):
            m.d.sync += [pending.eq(0), waited.eq(0)]
        with m.Elif(pending & (waited != 1023)):
            m.d.sync += waited.eq(waited + 1)
        m.d.comb += Assert(~pending | (waited <= bound_done), "done within the bound")

        # 2. ``busy`` falls.
        busy_for = Signal(10, init=1)
        with m.If(~dut.busy | dut.abort_cycle | accepted):
            m.d.sync += busy_for.eq(0)
        with m.Elif(busy_for != 1023):
            m.d.sync += busy_for.eq(busy_for + 1)
        m.d.comb += Assert(~dut.busy | (busy_for <= bound_idle), "back to idle within the bound")

        # Non-vacuity: a valid frame; a cycle that ends in a fault; back to idle after a frame.
        had_frame, busy_prev = Signal(), Signal()
        m.d.sync += busy_prev.eq(dut.busy)
        with m.If(dut.valid):
            m.d.sync += had_frame.eq(1)
        m.d.comb += [
            Cover(dut.valid),
            Cover(dut.done & (dut.status == STATUS["NO_START"])),
            Cover(had_frame & busy_prev & ~dut.busy),
        ]
        return m


def _vote_spacing(hp):
    """Clocks between the three votes of a slot, from docs/ports.md ("Noise immunity"): a
    quarter bit (hp // 2) for hp >= 3, none (one sample) for hp = 2. The harnesses' own reading."""
    return Mux(hp >= 3, hp >> 1, 0)


class SamplerHarness(Harness):
    """SloSampler alone: SLO and ``arm`` free at every clock (glitches, bounces, no encoder,
    an encoder that answers at any time), the half period any free constant >= 2.

    Properties (the receiver never stalls and never drifts once it has found the Ack edge):
    once ``locked``, it stays locked, and ``sample`` strobes exactly every MA period (2 half
    periods), whatever SLO does; slot 0 (whose decision locks it) is always decided low. (Where
    slot 0 falls after the edge is SamplerImmunityHarness's and the block tests' business: with
    one glitch at the edge it may move by up to the vote spacing v.) Lemmas: locked means the
    FSM is in SAMPLE past slot 0; the slot timer and the clocks since the last decision add up
    to the clocks from that decision to the next event (2u to the first vote, u = hp - v, then v and 2v more); ``slot_zero``
    mirrors ``slot_left``; the vote registers and the timer's reload values follow the half
    period; slot 0 counts from the edge's fall, and an ambiguous fall comes within u + v of it.

    Mutation ``"short_gap"``: assert a gap of one clock less; the solver must find a trace.
    """

    def __init__(self, delay_width, lemmas=True, mutation=None):
        super().__init__(delay_width=delay_width, lemmas=lemmas, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        dut = SloSampler(self.delay_width, synchronizer=False)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        hp = self.any_const(m, 16, "half_period")
        m.d.comb += [dut.slo.eq(self.any_seq(1, "slo")), dut.arm.eq(self.any_seq(1, "arm")),
                     dut.half_period.eq(hp),
                     Assume(hp >= MA_HALF_PERIOD_MIN)]
        period = Cat(C(0, 1), hp)                    # 2 * hp, 17 bits
        v = _vote_spacing(hp)
        if self.mutation == "short_gap":
            period = period - 1

        # Clocks since the last sample strobe (saturating; 1 in the clock after a strobe).
        since = Signal(18, init=(1 << 18) - 1)
        with m.If(dut.sample):
            m.d.sync += since.eq(1)
        with m.Elif(since != (1 << 18) - 1):
            m.d.sync += since.eq(since + 1)
        locked_prev = Signal()
        m.d.sync += locked_prev.eq(dut.locked)

        m.d.comb += [
            Assert(~locked_prev | dut.locked, "locked stays locked"),
            Assert(~(dut.sample & dut.locked) | (since == period), "one sample every MA period"),
            Assert(~dut.locked | (since <= period), "no gap longer than an MA period once locked"),
            Assert(~(dut.sample & ~dut.locked) | ~dut.bit, "slot 0 is decided low"),
        ]
        if self.lemmas:
            # The vote registers follow the (constant) half period: the spacing one clock after
            # the start, the timer's reload values two clocks after it (the period's reload is
            # wiring from first_load).
            settled = Signal(3)
            with m.If(settled != 4):
                m.d.sync += settled.eq(settled + 1)
            in_sample = inside.in_state("sampler.fsm", "SAMPLE")
            in_measure = inside.in_state("sampler.fsm", "MEASURE")
            in_idle = inside.in_state("sampler.fsm", "IDLE")
            slot_left = inside("sampler.slot_left")
            slot_zero = inside("sampler.slot_zero")
            phase = inside("sampler.phase")
            first_slot = inside("sampler.first_slot")
            gap = inside("sampler.gap")
            mid_slot, odd = inside("sampler.mid_slot"), inside("sampler.odd")
            # 2 * ceil(span / 2) - span % 2 = span, the clocks since the edge's fall.
            span = 2 * (hp - 1 - mid_slot) - odd
            u = hp - v                                 # edge (or third vote) to the first vote
            m.d.comb += [
                # The master arms the sampler long after the half period is latched.
                Assume((settled == 4) | ~dut.arm),
                Assert((settled == 4) | in_idle & ~gap, "lemma: idle until armed"),
                Assert((settled < 2) | (inside("sampler.vote") == v), "lemma: vote spacing"),
                Assert((settled < 2) | (inside("sampler.single") == (hp < 3)), "lemma: single"),
                Assert((settled < 3) | (inside("sampler.first_load") == u - 1),
                       "lemma: first_load"),
                Assert((settled < 3) | (inside("sampler.vote_load") == (v - 1)[:15]),
                       "lemma: vote_load"),
                Assert((settled < 3) | (inside("sampler.vote_one") == (v == 1)),
                       "lemma: vote_one"),
                Assert(dut.locked == (in_sample & ~first_slot), "lemma: locked past slot 0"),
                # Once locked: the clocks since the last decision and the slot timer add up to
                # the clocks from that decision to the next event (2u, then + v, then + 2v).
                Assert(~in_sample | (phase <= 2) & ((hp >= 3) | (phase == 0)),
                       "lemma: phase range"),
                Assert(~(in_sample & first_slot & (phase == 1)) | (slot_left < hp),
                       "lemma: slot 0 timer to the centre"),
                Assert(~(in_sample & first_slot & (phase == 2)) | (slot_left < v),
                       "lemma: slot 0 timer to the third vote"),
                Assert(~dut.locked | (phase != 0) | (since + slot_left == 2 * u),
                       "lemma: slot timer to the first vote"),
                Assert(~dut.locked | (phase != 1) | (since + slot_left == 2 * u + v),
                       "lemma: slot timer to the centre"),
                Assert(~dut.locked | (phase != 2) | (since + slot_left == period),
                       "lemma: slot timer to the third vote"),
                Assert(~(in_sample | gap) | (slot_zero == (slot_left == 0)), "lemma: slot_zero"),
                Assert(~in_sample | (slot_left < period), "lemma: slot timer range"),
                # Slot 0, before its first vote, counts from the edge's fall.
                Assert((settled < 3) | ~(in_sample & first_slot & (phase == 0))
                       | (span + slot_left == u) & (slot_left < u),
                       "lemma: slot 0 counts from the fall"),
                # The ambiguity window: v clocks after a rise within u clocks of the fall.
                Assert(~gap | in_measure, "lemma: gap only while measuring"),
                Assert((settled < 3) | ~gap | (slot_left < v) & (span - (v - slot_left) >= 1)
                       & (span - (v - slot_left) <= u),
                       "lemma: an ambiguous fall is within u + v of the first"),
            ]

        m.d.comb += Cover(dut.locked & dut.sample & (hp >= 3) & ~dut.bit)
        return m


class _SamplerFrameHarness(Harness):
    """Base of the harnesses that drive SloSampler alone with an encoder's frame: the sampler
    armed in clock 1, the half period a free constant from 3 to ``hp_max``, SLO high, falling
    at a free clock (the Ack edge, 2 or more clocks after arming), then ``slots`` free slot
    values (slot 0 low, the Ack) of one MA period each, and high after them."""

    def __init__(self, delay_width, hp_max=4, slots=4, mutation=None):
        super().__init__(delay_width=delay_width, hp_max=hp_max, slots=slots,
                         mutation=mutation)

    def _frame(self, m, jitter=False):
        """The sampler and its line: (dut, hp, v, values, t, line, offsets). ``jitter``: every
        change after the edge (into slot k, and the rise after the last) comes its own free
        offset (``offsets[k - 1]``) of v - hp .. hp - v clocks from its nominal clock;
        otherwise all offsets are 0. The harness drives ``dut.slo`` from ``line``."""
        dut = SloSampler(self.delay_width, synchronizer=False)
        m.submodules.dut = dut
        hp = self.any_const(m, 4, "half_period")
        v = _vote_spacing(hp)
        edge = self.any_const(m, 5, "edge")                 # clocks from arm to the Ack edge
        values = self.any_const(m, self.slots, "slots")     # slot k's level, slot 0 low
        m.d.comb += [Assume((hp >= 3) & (hp <= self.hp_max)), Assume(edge >= 2),
                     Assume(~values[0])]
        if jitter:
            offsets = [self.any_const(m, signed(5), f"offset{k}")
                       for k in range(1, self.slots + 1)]
            for o in offsets:
                m.d.comb += Assume((o >= v - hp) & (o <= hp - v))
        else:
            offsets = [0] * self.slots

        t = Signal(8)                                       # the harness's clock: arm in 1
        with m.If(t != 255):
            m.d.sync += t.eq(t + 1)
        m.d.comb += [dut.arm.eq(t == 1), dut.half_period.eq(hp)]
        since_edge = Signal(signed(10))
        m.d.comb += since_edge.eq(t - 1 - edge)
        # The slot on the line: the number of (shifted) boundaries passed since the edge.
        slot = Signal(range(self.slots + 1))
        m.d.comb += slot.eq(sum((since_edge >= 2 * hp * k + o).as_unsigned()
                                for k, o in enumerate(offsets, start=1)))
        line = Signal()
        with m.If(since_edge < 0):
            m.d.comb += line.eq(1)
        with m.Elif(slot < self.slots):
            m.d.comb += line.eq(values.bit_select(slot, 1))
        with m.Else():
            m.d.comb += line.eq(1)
        return dut, hp, v, values, t, line, offsets

    def _decided(self, m, dut):
        """How many slots the sampler has decided (up to ``slots``)."""
        decided = Signal(range(self.slots + 2))
        with m.If(dut.sample & (decided < self.slots)):
            m.d.sync += decided.eq(decided + 1)
        return decided


class SamplerImmunityHarness(_SamplerFrameHarness):
    """SloSampler alone, the noise-immunity property: an ideal encoder line with one glitch.

    The frame of :class:`_SamplerFrameHarness` (half period 3 .. ``hp_max``), without jitter;
    over it, one glitch inverts the line for a free number of clocks from 1 to the vote
    spacing v (hp // 2), starting at any clock. Property: every slot the sampler decides is
    decided as the encoder sent it (so no Start is faked and the frame never shifts), unless
    the glitch made SLO low at the arming clock (``early``: the master's DELAY_RANGE fault).
    Mutation ``"long"``: a glitch of v + 1 clocks; the solver must find a wrong decision.
    """

    def elaborate(self, platform):
        m = self._module()
        dut, hp, v, values, t, line, _ = self._frame(m)
        g_start = self.any_const(m, 8, "glitch_start")
        g_len = self.any_const(m, 4, "glitch_len")
        longest = v + 1 if self.mutation == "long" else v
        m.d.comb += Assume((g_len >= 1) & (g_len <= longest))
        glitch = (t >= g_start) & (t < g_start + g_len)
        m.d.comb += dut.slo.eq(line ^ glitch)

        # Every decision is the sent slot value, in order.
        decided = self._decided(m, dut)
        # (A glitch over the arming clock makes SLO low there: ``early``, which the master
        # reports as DELAY_RANGE, a fault; the sampler's decisions are then not used.)
        m.d.comb += Assert(~dut.sample | dut.early | (decided >= self.slots)
                           | (dut.bit == values.bit_select(decided, 1)),
                           "every decided slot as sent")
        # Not vacuous: the whole frame is decided.
        m.d.comb += Cover((decided == self.slots) & (hp == self.hp_max) & (g_len == v))
        return m


class SamplerCleanLineHarness(_SamplerFrameHarness):
    """SloSampler alone, the no-false-alarm property of its noise strobe: a clean, jittered line.

    The frame of :class:`_SamplerFrameHarness` (half period 3 .. ``hp_max``) with every change
    after the edge (into slot k, and the rise after the last slot) a free offset from its
    nominal clock, anywhere from the slot before's third vote to the next slot's first vote
    (v - hp .. hp - v clocks, a quarter period each way at an even half period: the jitter the
    protocol allows). Properties: ``noise`` never strobes (none of the documented patterns,
    the two-edges-between-centres rule included, fires on a clean line) and every decided slot
    is as sent. Mutation ``"glitch"``: the line inverted for one free clock as well; the
    solver must find a strobe (the property is not vacuous).
    """

    def elaborate(self, platform):
        m = self._module()
        dut, hp, v, values, t, line, offsets = self._frame(m, jitter=True)
        if self.mutation == "glitch":
            g_at = self.any_const(m, 8, "glitch_at")
            m.d.comb += dut.slo.eq(line ^ (t == g_at))
        else:
            m.d.comb += dut.slo.eq(line)

        decided = self._decided(m, dut)
        m.d.comb += [
            Assert(~dut.noise, "no noise strobe on a clean line"),
            Assert(~dut.sample | (decided >= self.slots)
                   | (dut.bit == values.bit_select(decided, 1)), "every decided slot as sent"),
            # Not vacuous: the whole frame decided at the largest half period with a change
            # at each extreme.
            Cover((decided == self.slots) & (hp == self.hp_max)
                  & (offsets[0] == v - hp) & (offsets[1] == hp - v)
                  & (values[1] != values[0]) & (values[2] != values[1])),
        ]
        return m


# =============================================================================================
# (c) A frame with a CRC error is never reported valid
# =============================================================================================

#: The CRCs from docs/protocol.md, section 6 (tb/protocol_facts.py): register polynomial
#: without the top term, start 0, sent inverted, MSB first.
CRC_SPEC = {Crc.CRC6: (facts.CRC6_WIDTH, facts.CRC6_POLY),
            Crc.CRC16: (facts.CRC16_WIDTH, facts.CRC16_POLY)}


def _crc_state(inside):
    """The decoder's CRC engine: its shift register and its mismatch flag (lemma inputs only:
    the properties compare with the harness's own CRC model). ``inside``: the decoder's
    :class:`Inside`."""
    return {"reg": inside("decoder.crc_reg"), "mismatch": inside("decoder.crc_mismatch")}


def _engine_settings(code):
    """What the master's configuration gives the CRC engine for a word's CRC code (width,
    register polynomial, start, inverted), written from docs/protocol.md section 6 (named
    CRCs; start 0, sent inverted); width 0 for none. Custom CRCs (code 3) are not modelled
    here: the formal harnesses keep to the named ones."""
    width = Mux(code == Crc.CRC6, facts.CRC6_WIDTH, Mux(code == Crc.CRC16, facts.CRC16_WIDTH, 0))
    poly = Mux(code == Crc.CRC6, facts.CRC6_POLY, Mux(code == Crc.CRC16, facts.CRC16_POLY, 0))
    named = (code == Crc.CRC6) | (code == Crc.CRC16)
    return {"width": width, "poly": poly, "start": facts.CRC_INIT, "inverted": named}


def _field_ends(m, w, c, payload, length):
    """A word's field ends as the decoder registers them (FIELD_ENDS, its port layout: the
    last data bit, the nW bit, the last nE/nW bit, the last LC bit, the last bit, all as bit
    indices from 0 at the word's first data bit; data at bit 0; LC at bit 0) from the word's
    configuration ``c`` (word ``w``) and the parser's payload (data + nE/nW + LC) and length."""
    value = Signal(FIELD_ENDS, name=f"h_ends{w}")
    nenw = Mux(c["nenw"], facts.NE_NW_BITS, 0)
    m.d.comb += [
        value.data_end_p1.eq(c["data_bits"] + 1),
        value.data_end_m1.eq(c["data_bits"] - 1),
        value.nenw_end_m1.eq(c["data_bits"] + nenw - 1),
        value.lc_end_m1.eq(payload - 1),
        value.word_end_m1.eq(length - 1),
        value.data_at0.eq(1),          # data_bits >= 1
        value.lc_at0.eq(0),
    ]
    return value.as_value()


def _lfsr_step(reg, bit, width, poly):
    """One bit into a Galois CRC register, MSB first: shift left, and if the bit that falls
    out differs from the data bit, add the polynomial."""
    feedback = reg[width - 1] ^ bit
    shifted = Cat(C(0, 1), reg[:width - 1])
    return shifted ^ Mux(feedback, C(poly, width), C(0, width))


def _ideal_constants(width, poly):
    """``C[j]``: the part of the receiver's register, after the data and the first ``j`` CRC
    bits *as sent* (inverted, MSB first), that does not depend on the data: the register is then
    ``(R << j) ^ C[j]`` with ``R`` its value after the data (the feedback is always
    ``1 ^ C[j][msb]``). ``C[width]`` is the residue that a correct word leaves."""
    consts, c = [0], 0
    mask = (1 << width) - 1
    for _ in range(width):
        feedback = 1 ^ (c >> (width - 1))
        c = ((c << 1) & mask) ^ (poly if feedback else 0)
        consts.append(c)
    return consts


class _FrameParser:
    """The harness's own reading of a frame, fed the same (sample, bit) stream as the decoder.

    Configuration: per word ``cfg[w]`` = dict of data_bits, nenw, lc, crc; ``count`` words.
    Phases: ACK (low slots) until a high slot (Start), then CDS, then the words, then DONE.

    For each word and each CRC kind it keeps ``shadow``: an independent CRC register fed every
    bit of the word (``_lfsr_step``, written from the spec). For the configured kind it keeps
    the register after the data part (``data_crc``: over data, nE/nW, LC), the received CRC
    bits (``rx``), and the verdict a master must reach: ``ok`` = (received CRC == inverted
    ``data_crc``), a word without CRC always ok.

    Lemmas (``lemmas=True``; asserted, so proven): during the CRC bits, the shadow register is
    ``(data_crc << j) ^ C[j] ^ diff`` where ``diff`` is the CRC register of the *error* bits
    (received xor expected) alone, and ``diff`` is 0 exactly while no bit was wrong (it keeps a
    set bit below position ``j`` once one was). They split the XOR reasoning into one step per
    bit, which the solver cannot find on its own for CRC-16 in reasonable time. With ``rtl``
    (per word, per kind: the RTL's CRC register) it also asserts shadow == RTL register.

    ``clear`` restarts the parse (a new cycle). ``ssi``: the frame is an SSI frame
    (docs/ports.md, "SSI mode"): no Ack, Start or CDS, word 0 begins in the first clock after
    ``clear`` and the first decision is its first bit; a ``cfg[0]`` entry ``ssi_error`` adds
    the SSI error bit after the data (before the CRC, which covers it). The parse ends with the
    (first copy of the) word: an SSI double transmission's separator and second copy are not
    CRC bits. ``mutation="poly"`` uses a wrong CRC-6 polynomial (x^6 + x^5 + 1) in
    ``data_crc``; ``"no_invert"`` forgets the inversion: the solver must find a word on which
    the RTL and the harness disagree.
    """

    ACK, CDS, WORD, DONE = range(4)

    def __init__(self, m, sample, bit, cfg, count, clear=C(0), lemmas=True, rtl=None,
                 mutation=None, ssi=C(0)):
        words = len(cfg)
        self.phase = phase = Signal(2, name="p_phase")
        self.pos = pos = Signal(7, name="p_pos")
        self.word = word = Signal(range(max(words, 2)), name="p_word")
        self.done_strobe = done_strobe = Signal(name="p_done_strobe")
        self.ok = [Signal(name=f"p_ok{w}") for w in range(words)]
        self.length = []
        self.payload = []

        data_spec = dict(CRC_SPEC)
        if mutation == "poly":
            data_spec[Crc.CRC6] = (6, 0x21)
        for w in range(words):
            c = cfg[w]
            crc_bits = Mux(c["crc"] == Crc.CRC6, 6, Mux(c["crc"] == Crc.CRC16, 16, 0))
            payload = Signal(7, name=f"p_payload{w}")
            m.d.comb += payload.eq(c["data_bits"] + Mux(c["nenw"], 2, 0) + Mux(c["lc"], 6, 0)
                                   + (c["ssi_error"] if "ssi_error" in c else 0))
            self.payload.append(payload)
            length = Signal(7, name=f"p_len{w}")
            m.d.comb += length.eq(payload + crc_bits)
            self.length.append(length)
            this = Signal(name=f"p_this{w}")
            m.d.comb += this.eq((phase == self.WORD) & (word == w) & sample)

            data_crc = Signal(16, name=f"p_data_crc{w}")
            rx = Signal(16, name=f"p_rx{w}")
            j = Signal(5, name=f"p_j{w}")                       # CRC bits received so far
            diff = Signal(16, name=f"p_diff{w}")
            wrong = Signal(name=f"p_wrong{w}")                  # a CRC bit differed
            shadow = {k: Signal(wd, name=f"p_shadow{w}_{k.name}") for k, (wd, _) in CRC_SPEC.items()}
            in_payload = pos < payload
            with m.If(clear):
                m.d.sync += [data_crc.eq(0), rx.eq(0), j.eq(0), diff.eq(0), wrong.eq(0)]
                m.d.sync += [sh.eq(0) for sh in shadow.values()]
            with m.Elif(this):
                for k, (wd, poly) in CRC_SPEC.items():
                    # The RTL restarts its registers at the word's first bit: so does this.
                    src = Mux(pos == 0, 0, shadow[k])
                    m.d.sync += shadow[k].eq(_lfsr_step(src, bit, wd, poly))
                with m.If(in_payload):
                    with m.Switch(c["crc"]):
                        for k, (wd, poly) in data_spec.items():
                            with m.Case(k):
                                m.d.sync += data_crc.eq(_lfsr_step(data_crc[:wd], bit, wd, poly))
                with m.Else():
                    m.d.sync += [rx.eq(Cat(bit, rx[:15])), j.eq(j + 1)]
                    with m.Switch(c["crc"]):
                        for k, (wd, poly) in CRC_SPEC.items():
                            with m.Case(k):
                                sent = ~(data_crc[:wd] << j)[wd - 1]     # CRC bit j as sent
                                error = bit ^ sent
                                m.d.sync += [diff.eq(_lfsr_step(diff[:wd], error, wd, poly)),
                                             wrong.eq(wrong | error)]
            inv = 0 if mutation == "no_invert" else 0xFFFF
            with m.Switch(c["crc"]):
                with m.Case(Crc.NONE):
                    m.d.comb += self.ok[w].eq(1)
                for k, (wd, _) in CRC_SPEC.items():
                    with m.Case(k):
                        mask = (1 << wd) - 1
                        m.d.comb += self.ok[w].eq((rx & mask) == ((data_crc ^ inv) & mask))

            if lemmas:
                with m.Switch(c["crc"]):
                    for k, (wd, poly) in CRC_SPEC.items():
                        consts = _ideal_constants(wd, poly)
                        with m.Case(k):
                            for jj in range(wd + 1):
                                mask = (1 << wd) - 1
                                expect = ((data_crc[:wd] << jj)[:wd] ^ consts[jj] ^ diff[:wd])
                                # The received CRC bits so far against the ones sent.
                                sent_top = (~data_crc[:wd])[wd - jj:wd] if jj else C(0, 0)
                                with m.If(j == jj):
                                    m.d.comb += [
                                        Assert(shadow[k] == expect, "lemma: shadow = ideal ^ diff"),
                                        Assert(wrong == (rx[:jj] != sent_top) if jj else ~wrong,
                                               "lemma: wrong = some CRC bit differed"),
                                        Assert(Mux(wrong, (diff[:wd] & ((1 << jj) - 1)) != 0,
                                                   diff == 0),
                                               "lemma: diff is 0 until a bit is wrong, then has "
                                               "a set bit below j"),
                                        Assert((diff[wd:] == 0) & (data_crc[wd:] == 0),
                                               "lemma: unused register bits"),
                                    ]
                            with m.If(j > wd):
                                m.d.comb += Assert(0, "lemma: j in range")
                    with m.Case(Crc.NONE):
                        m.d.comb += [Assert(j == 0, "lemma: no CRC bits"),
                                     Assert(~wrong, "lemma: no CRC bit, none wrong")]
                at_word = (phase == self.WORD) & (word == w)
                not_started = ((phase == self.ACK) | (phase == self.CDS)
                               | ((phase == self.WORD) & ((word < w) | (word == w) & (pos == 0))))
                finished = (phase == self.DONE) | ((phase == self.WORD) & (word > w))
                crc_width = Mux(c["crc"] == Crc.CRC6, 6, Mux(c["crc"] == Crc.CRC16, 16, 0))
                m.d.comb += [
                    Assert(~at_word | Mux(in_payload, j == 0, pos == payload + j),
                           "lemma: j counts the CRC bits"),
                    Assert(~not_started | ((data_crc == 0) & (rx == 0) & (j == 0) & (diff == 0)
                                           & ~wrong), "lemma: word not started"),
                    Assert(~finished | (count <= w) | (j == crc_width), "lemma: word finished"),
                    Assert(~at_word | (pos < length), "lemma: pos in the word"),
                    Assert((phase != self.WORD) | (word < count), "lemma: word in the frame"),
                ]
                if rtl is not None:
                    # The engine serves every word in turn: while this word runs, its register
                    # is the data part's CRC shifted by the CRC bits received, and its flag says
                    # whether one of them differed; once the word is done, its verdict holds.
                    reg, mismatch = rtl["reg"], rtl["mismatch"]
                    with m.Switch(c["crc"]):
                        for k, (wd, poly) in CRC_SPEC.items():
                            with m.Case(k):
                                for jj in range(wd + 1):
                                    with m.If(at_word & (j == jj)):
                                        m.d.comb += Assert(
                                            reg[:wd] == (data_crc[:wd] << jj)[:wd],
                                            f"lemma: word {w} engine register")
                        with m.Case(Crc.NONE):
                            pass
                    m.d.comb += [
                        Assert(~at_word | (mismatch == wrong), f"lemma: word {w} engine mismatch"),
                        Assert(~(finished & (count > w)) | (rtl["ok"][w] == self.ok[w]),
                               f"lemma: word {w} engine verdict"),
                    ]

        length = self.length[0] if words == 1 else Array(self.length)[word]
        m.d.sync += done_strobe.eq(0)
        with m.If(clear):
            m.d.sync += [phase.eq(self.ACK), pos.eq(0), word.eq(0)]
        with m.Elif((phase == self.ACK) & ssi):
            # SSI: word 0 begins in the first clock after the clear (no Ack, Start or CDS).
            m.d.sync += [phase.eq(self.WORD), pos.eq(0), word.eq(0)]
        with m.Elif(sample):
            with m.Switch(phase):
                with m.Case(self.ACK):
                    with m.If(bit):
                        m.d.sync += phase.eq(self.CDS)
                with m.Case(self.CDS):
                    m.d.sync += [phase.eq(self.WORD), pos.eq(0), word.eq(0)]
                with m.Case(self.WORD):
                    m.d.sync += pos.eq(pos + 1)
                    with m.If(pos == length - 1):
                        m.d.sync += pos.eq(0)
                        with m.If(word == count - 1):
                            m.d.sync += [phase.eq(self.DONE), done_strobe.eq(1)]
                        with m.Else():
                            m.d.sync += word.eq(word + 1)


def _assume_word_config(m, cfg, params, w):
    """A configuration the master accepts for word ``w`` (see BissMaster._config_valid)."""
    crc_ok = cfg["crc"] == Crc.NONE
    for kind in params.word_crcs[w]:
        crc_ok |= cfg["crc"] == kind
    m.d.comb += Assume((cfg["data_bits"] >= 1) & (cfg["data_bits"] <= params.max_data_bits[w])
                       & crc_ok)


class DecoderCrcHarness(Harness):
    """FrameDecoder alone: ``sample`` and ``bit`` free at every clock (any frame, any spacing of
    the samples); the word configuration and word count free constants within what the master
    accepts (one LC per frame).

    Properties, checked against :class:`_FrameParser`: ``done`` strobes exactly when the
    harness's parse of the configured frame ends; from then on each word's ``crc_ok`` equals
    the independent check (received CRC == inverted CRC of the data part). So a word with a
    wrong CRC is never reported ok, and a right one never reported wrong.
    """

    def __init__(self, params, lemmas=True, mutation=None):
        super().__init__(params=params, lemmas=lemmas, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        p = self.params
        dut = FrameDecoder(p)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        sample, bit = self.any_seq(1, "sample"), self.any_seq(1, "bit")
        m.d.comb += [dut.sample.eq(sample), dut.bit.eq(bit)]
        cfg = []
        for w in range(p.words):
            c = {name: self.any_const(m, len(getattr(dut.words[w], name)), f"w{w}_{name}")
                 for name in ("data_bits", "nenw", "lc", "crc")}
            m.d.comb += [getattr(dut.words[w], name).eq(v) for name, v in c.items()]
            # Named CRCs only (the custom settings are left 0): the width as the master's
            # configuration resolves it; the engine resolves the rest itself (a one-word
            # decoder gets the whole CRC resolved).
            settings = _engine_settings(c["crc"])
            m.d.comb += dut.crc_widths[w].eq(settings["width"])
            if p.words == 1:
                m.d.comb += [getattr(dut.word0_crc, name).eq(v) for name, v in settings.items()]
            _assume_word_config(m, c, p, w)
            cfg.append(c)
        count = self.any_const(m, len(dut.word_count), "word_count")
        m.d.comb += [dut.word_count.eq(count), Assume((count >= 1) & (count <= p.words))]
        # One LC per frame (one sign-of-life tracker), among the words the frame has.
        for a in range(p.words):
            for b in range(a + 1, p.words):
                m.d.comb += Assume(~((count > b) & cfg[a]["lc"] & cfg[b]["lc"]))

        rtl = None
        if self.lemmas:
            rtl = dict(_crc_state(inside), ok=dut.crc_ok)
        parse = _FrameParser(m, sample, bit, cfg, count, lemmas=self.lemmas, rtl=rtl,
                             mutation=self.mutation)
        in_done = parse.phase == _FrameParser.DONE
        m.d.comb += Assert(dut.done == parse.done_strobe, "done exactly when the frame ends")
        if self.lemmas:
            state = {n: inside.in_state("decoder.fsm", n)
                     for n in ("ACK", "CDS", "WORD", "STOP", "END")}
            idx = inside("decoder.idx")
            m.d.comb += [
                Assert(state["ACK"] == (parse.phase == _FrameParser.ACK), "lemma: ACK"),
                Assert(state["CDS"] == (parse.phase == _FrameParser.CDS), "lemma: CDS"),
                Assert(state["WORD"] == (parse.phase == _FrameParser.WORD), "lemma: WORD"),
                Assert(~state["WORD"] | (idx == parse.pos), "lemma: bit index"),
            ]
            payload = (parse.payload[0] if p.words == 1
                       else Array(parse.payload)[parse.word])
            m.d.comb += Assert(~state["WORD"] | (inside("decoder.in_crc") == (parse.pos >= payload)),
                               "lemma: the engine checks exactly the CRC bits")
            if p.words >= 2:
                word = inside("decoder.word")
                m.d.comb += Assert(~state["WORD"] | (word == parse.word), "lemma: word index")
            if p.words >= 2:
                # The engine holds the current word's CRC, taken at the word's load (a
                # one-word engine reads the configuration instead).
                held = CRC_SETTINGS(inside("decoder.crc_settings"))     # its port layout
                want = _engine_settings(Array(c["crc"] for c in cfg)[parse.word])
                m.d.comb += Assert(~state["WORD"] | ((held.width == want["width"])
                                                     & (held.poly == want["poly"])
                                                     & (held.inverted == want["inverted"])),
                                   "lemma: the engine holds the word's CRC")
            # The field ends of the current word and of the next (builds of 2+ words), as
            # bit indices within the word (docs/ports.md's word layout; 7 bits).
            held = inside("decoder.ends_current")
            lemma = "lemma: the current word's field ends"
            ends = [_field_ends(m, w, c, parse.payload[w], parse.length[w])
                    for w, c in enumerate(cfg)]
            m.d.comb += Assert(~state["WORD"] | (held == (ends[0] if p.words == 1
                                                          else Array(ends)[parse.word])), lemma)
            if p.words >= 2:
                held = inside("decoder.ends_following")
                for w in range(p.words - 1):
                    m.d.comb += Assert(~(state["WORD"] & (parse.word == w))
                                       | (held == ends[w + 1]),
                                       "lemma: the following word's field ends")
                # The word the CRC engine loads next: word 0 until the frame's words begin,
                # then the one after the current one.
                load_next = inside("decoder.crc_next")
                m.d.comb += [
                    Assert(~(state["ACK"] | state["CDS"]) | (load_next == 0),
                           "lemma: the engine loads word 0 first"),
                    Assert(~state["WORD"] | (load_next == (parse.word + 1)[:len(load_next)]),
                           "lemma: the engine loads the word after the current one next"),
                ]
                # The word the field ends load next: word 1 until the frame's words begin
                # (the decoder is reset before every frame), then two after the current one.
                pick = inside("decoder.ends_pick")
                before = state["ACK"] | state["CDS"]
                m.d.comb += [
                    Assert(~before | (pick == 1), "lemma: word 1's ends load first"),
                    Assert(~state["WORD"] | (pick == (parse.word + 2)[:len(pick)]),
                           "lemma: the word two after the current one loads next"),
                ]
            if p.ssi:
                # BiSS frames (``ssi`` left at 0): the SSI double transmission's states are
                # never entered.
                m.d.comb += Assert(~inside.in_state("decoder.fsm", "SEPARATOR")
                                   & ~inside.in_state("decoder.fsm", "COPY"),
                                   "lemma: no SSI copy in a BiSS frame")
        for w in range(p.words):
            used = count > w
            m.d.comb += Assert(~(in_done & used) | (dut.crc_ok[w] == parse.ok[w]),
                               f"word {w}: crc_ok == independent CRC check")

        # Non-vacuity: frames with good and bad CRCs of both kinds.
        kinds = {c: Cat(*((cfg[w]["crc"] == c) & (count > w) for w in range(p.words))).any()
                 for c in (Crc.CRC6, Crc.CRC16)}
        all_ok = Cat(*(parse.ok[w] | (count <= w) for w in range(p.words))).all()
        m.d.comb += [
            Cover(dut.done & all_ok & kinds[Crc.CRC6] & kinds[Crc.CRC16]),
            Cover(dut.done & ~all_ok & kinds[Crc.CRC16]),
        ]
        if p.words > 2:
            # A chain: a frame of every word whose last word alone failed its CRC.
            last = p.words - 1
            m.d.comb += Cover(dut.done & (count == p.words) & ~parse.ok[last]
                              & Cat(*parse.ok[:last]).all())
        return m


class MasterCrcHarness(Harness):
    """The whole BissMaster: every input free at every clock (SLO, start, periodic, abort,
    every cfg_* within ``limits``, as for liveness, which keeps frames short).

    The harness detects an accepted request from the ports (as in the liveness harness),
    latches the word configuration itself, and parses the bits the decoder consumes (the
    sampler's ``sample``/``bit`` strobes, read inside the core) with :class:`_FrameParser`.
    Properties: ``valid`` implies the independent CRC check passed for every word of the
    frame; a reported frame whose independent check fails has a CRC error status, and one
    whose check passes has none.
    """

    def __init__(self, params, limits, lemmas=True, mutation=None):
        super().__init__(params=params, limits=limits, lemmas=lemmas, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        p, lim = self.params, self.limits
        dut = BissMaster(p)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        self.drive_free(m, dut)
        lim.assume(m, dut, p.words, crcs=False)
        names = ("data_bits", "nenw", "lc", "crc")
        if p.custom_crc:
            # The named CRCs only: the harness's own CRC model has no custom one (those are
            # proven by block tests against published check values and by cocotb).
            m.d.comb += Assume(Cat(*(getattr(dut, f"cfg_w{w}_crc") != Crc.CUSTOM
                                     for w in range(p.words))).all())

        # Accepted request: idle and no abort in the previous clock, busy now. SSI frames
        # (docs/ports.md, "SSI mode"): ``cfg_ssi`` and the error bit (read only with it).
        has_ssi = lim.has_ssi(dut)
        live = Cat(*(getattr(dut, f"cfg_w{w}_{n}") for w in range(p.words) for n in names),
                   dut.cfg_w1_enable if p.words == 2 else C(0, 1),
                   dut.cfg_ssi if has_ssi else C(0, 1),
                   dut.cfg_ssi & dut.cfg_ssi_error if has_ssi else C(0, 1))
        snapshot = Signal(len(live))
        latched = Signal(len(live))
        could_accept = Signal()
        m.d.sync += [snapshot.eq(live), could_accept.eq(~dut.busy & ~dut.abort_cycle)]
        accepted = could_accept & dut.busy
        with m.If(accepted):
            m.d.sync += latched.eq(snapshot)
        cfg, offset = [], 0
        for w in range(p.words):
            c = {}
            for n in names:
                width = len(getattr(dut, f"cfg_w{w}_{n}"))
                c[n] = latched[offset:offset + width]
                offset += width
            cfg.append(c)
        count = 1 + latched[offset]
        cfg[0]["ssi_error"] = latched[offset + 2]
        ssi = latched[offset + 1]

        # The bits the decoder consumes, and the core's own "new cycle" reset of the receiver
        # (the parse restarts with it; the configuration is the harness's copy).
        # (The decoder's own inputs: the master registers the sampler's decisions on their way.)
        decoder = inside.block("master.decoder")
        sample, bit = decoder("decoder.sample"), decoder("decoder.bit")
        clear = inside("master.receiver_clear")
        rtl = dict(_crc_state(decoder), ok=decoder("decoder.crc_ok"))
        parse = _FrameParser(m, sample, bit, cfg, count, clear=clear, lemmas=self.lemmas,
                             rtl=rtl if self.lemmas else None, mutation=self.mutation, ssi=ssi)

        all_ok = Cat(*(parse.ok[w] | (count <= w) for w in range(p.words))).all()
        crc_status = Cat(*(dut.status == STATUS[name] for name in
                           ("CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH"))).any()
        frame_status = Cat(*(dut.status == STATUS[name] for name in FRAME_STATUSES)).any()
        in_done = parse.phase == _FrameParser.DONE
        m.d.comb += [
            Assert(~dut.valid | (in_done & all_ok), "valid only with every CRC right"),
            Assert(~(dut.done & frame_status) | in_done, "a frame is reported only when parsed"),
            Assert(~(dut.done & frame_status) | (crc_status == ~all_ok),
                   "CRC error status exactly when the independent check fails"),
        ]
        for w in range(p.words):
            m.d.comb += Assert(~(dut.done & frame_status & (count > w))
                               | (getattr(dut, f"word{w}_crc_ok") == parse.ok[w]),
                               f"word{w}_crc_ok == independent check")

        m.d.comb += [
            Cover(dut.valid & Cat(*(cfg[w]["crc"] != Crc.NONE for w in range(p.words))).any()),
            Cover(dut.done & crc_status),
        ]
        return m



# =============================================================================================
# (e) Every accepted register access ends within its frame bound (issue 13)
# =============================================================================================

#: The control channel's frame counts, the harness's own reading of docs/control.md
#: (docs/protocol.md, section 10), never the RTL's: CDM = 0 frames before S, as many in a row cancel a
#: control frame; the header's frames (S .. W); one register's frames (S .. P).
CONTROL_IDLE_FRAMES = 14
CONTROL_HEADER_FRAMES = 18
CONTROL_REGISTER_FRAMES = 14
#: ``ca_status`` codes (docs/control.md, "Statuses"); the most bytes of one access.
ACCESS_OK = CA_STATUS["OK"]
ACCESS_ABORTED = CA_STATUS["ABORTED"]
ACCESS_BAD_REQUEST = CA_STATUS["BAD_REQUEST"]
ACCESS_COUNT_MAX = 64


def access_frame_bound(count, start_wait_frames, write):
    """docs/control.md, "Bound: every access ends": the frames up to the last one that
    can carry CDM = 1, then the 14 CDM = 0 frames of a cancel (an access that ends OK ends
    earlier: its final frame comes 2 or 14 frames after that last 1). 14 idle frames, plus one
    in flight at ``ca_start`` (an S still under way from an access aborted before), the
    header (18), the registers before the last one (14 each, a read's 14 + its start-bit wait),
    then the last register up to its last possible CDM = 1: a write's last CRC bit (13
    frames), a read's last wait frame (2 + wait). ``count`` and ``write`` may be Values."""
    idle, header, register = CONTROL_IDLE_FRAMES, CONTROL_HEADER_FRAMES, CONTROL_REGISTER_FRAMES
    lead = idle + 1 + header
    write_bound = lead + (count - 1) * register + (register - 1) + idle
    read_bound = lead + (count - 1) * (register + start_wait_frames) + 2 + start_wait_frames \
        + idle
    if isinstance(write, bool):
        return write_bound if write else read_bound
    return Mux(write, write_bound, read_bound)


class RegisterAccessEndsHarness(Harness):
    """RegisterAccess alone: every accepted register access ends within its frame bound.

    Inputs free at every clock: the request fields (slave ID, address, count 0..127, read or
    write), ``start``, ``abort``, the write-buffer port, the read-buffer address, and, for every
    ended frame, ``frame_ok`` and ``frame_cds``.

    The frames come from a model of the cycle controller, as the engine's docstring states its
    contract ("the controller copies [cdm] while idle, so a cycle carries the bit it was
    accepted with"; ``frame_cdm`` is "the CDM bit that cycle carried"): a free ``cycle_accept``
    starts a request cycle when none is in flight and takes the engine's ``cdm`` of that clock;
    ``frame_end`` is free while a cycle is in flight and ends it, with ``frame_cdm`` = the bit
    taken. One cycle at a time, and a new one is accepted at the earliest in the clock after
    the previous one ended (the controller reports a frame from a busy state and copies ``cdm``
    only in IDLE, from the clock after): so a frame can end every second clock. With
    ``frame_cdm`` free instead (mutation ``"free_cdm"``) the bound does not hold, and the solver
    shows it: LEAD and CANCEL wait for 14 consecutive frames that carried CDM = 0, the header's
    first frame for one that carried S, and frames that report a CDM bit the engine did not
    send can keep any of them waiting forever.

    The harness counts the ended frames after each accepted ``start`` (``start`` while not
    busy) and computes the bound itself (:func:`access_frame_bound` of the count and direction
    it latched). Properties: ``done`` strobes before more than the bound frames have ended;
    ``busy`` is low when ``done`` strobes and falls only with ``done``; no ``done`` without an
    accepted start; a cycle carrying CDM = 1 is still in flight at ``done`` only when the
    status is ABORTED (or BAD_REQUEST, right after such an abort: that cycle is still on its
    way).

    Lemmas (``lemmas=True``, for induction; proven, never assumed), on the engine's FSM, step,
    index, wait and idle counters (:data:`INTERNALS` ``access.*``): frames counted + the most
    frames the engine's state can still take <= the bound, with the most frames per state
    written from the docs (the idle frames before S, the header's and the registers' remaining
    steps, the read's start-bit wait, the frames a cancel still needs: a cycle in flight if it
    carries CDM = 1, then the zeros still missing); the counters within their ranges; the
    latched request is the harness's; the header's first bit (S) is 1 until S is sent; which
    frames carry CDM = 0 (a read's register after S, P, the final frame, a cancel) and so how
    many zeros have ended in the last register and the final frame.

    ``count_max`` assumes at most that many bytes, ``write`` only reads (False) or writes
    (True), ``wbuf=False`` leaves the write buffer unwritten (all zero: Yosys drops it): smaller
    searches for the covers and the mutations; the proof has all of them free. ``slack`` is
    added to the bound (negative: a tighter bound than documented). ``cover``: ``"read1"`` (a
    one-byte read ends OK) or ``"bound"`` (an access ends after exactly its bound of frames:
    the bound is reached, one less is not a bound). Mutations: ``"free_cdm"`` (above).
    """

    def __init__(self, start_wait=2, lemmas=True, count_max=None, write=None, wbuf=True,
                 slack=0, mutation=None, cover="read1"):
        super().__init__(start_wait=start_wait, lemmas=lemmas, count_max=count_max,
                         write=write, wbuf=wbuf, slack=slack, mutation=mutation, cover=cover)

    def elaborate(self, platform):
        m = self._module()
        w_frames = self.start_wait
        dut = RegisterAccess(w_frames)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment

        self.drive_free(m, dut, exclude=("request", "wbuf", "frame_end", "frame_cdm"))
        for port in ("request", "wbuf"):        # structures: one free input per field
            view = getattr(dut, port)
            for name, _ in view.shape():
                field = getattr(view, name)
                if port == "wbuf" and not self.wbuf:
                    continue                    # never written: Yosys drops the memory
                m.d.comb += field.eq(self.any_seq(len(field), f"{port}_{name}"))
        if self.count_max is not None:
            m.d.comb += Assume(dut.request.count <= self.count_max)
        if self.write is not None:
            m.d.comb += Assume(dut.request.write == int(self.write))

        # The controller model: one request cycle in flight at a time, carrying the engine's
        # cdm of the clock it was accepted in.
        frame_end = self.any_seq(1, "frame_end")
        accept = self.any_seq(1, "cycle_accept")
        in_flight = Signal()
        cycle_cdm = Signal()
        m.d.comb += dut.frame_end.eq(frame_end)
        if self.mutation == "free_cdm":
            m.d.comb += dut.frame_cdm.eq(self.any_seq(1, "frame_cdm"))
        else:
            m.d.comb += [Assume(~frame_end | in_flight), dut.frame_cdm.eq(cycle_cdm)]
            with m.If(frame_end):
                m.d.sync += in_flight.eq(0)
            with m.Elif(accept):
                m.d.sync += [in_flight.eq(1), cycle_cdm.eq(dut.cdm)]

        # The harness's own count of the frames of each accepted access, and its bound.
        started = dut.start & ~dut.busy
        pending = Signal()                      # an access accepted, its done not yet seen
        # Wide enough for the bound of any count the request port can carry (0 .. 127).
        width = (max(access_frame_bound(2**len(dut.request.count) - 1, w_frames, w)
                     for w in (False, True)) + max(self.slack, 0)).bit_length() + 1
        frames = Signal(width)                  # frames ended since the start (saturating)
        request = Signal(dut.request.shape(), name="started_request")  # taken at that start
        count, write = request.count, request.write
        with m.If(started):
            m.d.sync += [pending.eq(1), frames.eq(0), request.eq(dut.request)]
        with m.Else():
            with m.If(dut.done):
                m.d.sync += pending.eq(0)
            with m.If(frame_end & (frames != 2**len(frames) - 1)):
                m.d.sync += frames.eq(frames + 1)
        bound = Signal(width)
        m.d.comb += bound.eq(access_frame_bound(count, w_frames, write) + self.slack)

        busy_prev = Signal()
        m.d.sync += busy_prev.eq(dut.busy)
        f, c = in_flight, cycle_cdm
        status = Value.cast(dut.result.status)
        m.d.comb += [
            Assert(~pending | (frames <= bound), "done before more than the bound frames"),
            Assert(~dut.done | ~dut.busy, "busy is low with done"),
            Assert(~(busy_prev & ~dut.busy) | dut.done, "busy falls only with done"),
            Assert(~dut.done | pending, "no done without an accepted start"),
        ]
        if self.mutation != "free_cdm":
            m.d.comb += Assert(~(dut.done & f & c) | (status == ACCESS_ABORTED)
                               | (status == ACCESS_BAD_REQUEST),
                               "a CDM = 1 cycle in flight at done only after an abort")

        if self.lemmas:
            state = {s: inside.in_state("access.fsm", s)
                     for s in ("IDLE", "LEAD", "HEADER", "REGISTER", "WAIT", "FINAL", "CANCEL")}
            step = inside("access.step")
            index = inside("access.index")
            waited = inside("access.waited")
            r = inside("access.idle_run")
            seen = inside("access.idle_seen")
            ending = Value.cast(inside("access.ending"))
            header = inside("access.header")
            req = inside("access.request")
            idle = CONTROL_IDLE_FRAMES
            read = ~write
            per_register = Mux(write, CONTROL_REGISTER_FRAMES,
                               CONTROL_REGISTER_FRAMES + w_frames)
            # After the last register's P: a write's last CDM = 1 was its 13th frame, so the
            # final frame and 12 zeros (13); a read's its last wait frame: 12 + 2.
            tail = Mux(write, 1 + (idle - 2), 2)
            # The most frames a cancel still takes: the cycle in flight if it carries a 1
            # (it breaks the run of zeros), then the zeros still missing; none once the run is
            # complete (the cycle in flight may still end in the clock that finishes).
            cancel_left = Mux(f & c, 1 + idle, Mux(r == idle, f, idle - r))
            # LEAD: S waits for 14 zeros that delivered a good frame (``idle_seen``; a failed
            # frame ends the access); possibly one cycle accepted with CDM = 0 as LEAD leaves
            # ends at the header's first frame (LEAD leaves at once when the count is complete
            # and no frame ends). A cycle carrying 1 in flight at the start: the S of an access
            # that was aborted while it was under way, and ended at once.
            lead_left = Mux(f & c, 1 + idle, Mux(seen == idle, 1, idle - seen))
            registers = count * per_register
            after_index = (count - index - 1) * per_register + tail
            # FINAL: its frame carries 0; then the zeros still missing (none when complete).
            final_left = Mux(r == idle, 1, idle - r)
            left = Signal(width)
            with m.If(state["LEAD"]):
                m.d.comb += left.eq(lead_left + CONTROL_HEADER_FRAMES + registers + tail)
            with m.Elif(state["HEADER"]):
                m.d.comb += left.eq(CONTROL_HEADER_FRAMES - step
                                    + Mux((step == 0) & f & ~c, 1, 0)
                                    + registers + tail)
            with m.Elif(state["REGISTER"]):
                m.d.comb += left.eq(CONTROL_REGISTER_FRAMES - step
                                    + Mux(read & (step <= 1), w_frames, 0) + after_index)
            with m.Elif(state["WAIT"]):
                m.d.comb += left.eq(w_frames - waited + CONTROL_REGISTER_FRAMES - 2
                                    + after_index)
            with m.Elif(state["FINAL"]):
                m.d.comb += left.eq(final_left)
            with m.Elif(state["CANCEL"]):
                m.d.comb += left.eq(cancel_left)
            busy_states = 0
            for s in ("LEAD", "HEADER", "REGISTER", "WAIT", "FINAL", "CANCEL"):
                busy_states = busy_states | state[s]
            in_register = state["REGISTER"]
            m.d.comb += [
                Assert(dut.busy == ~state["IDLE"], "lemma: busy is not IDLE"),
                Assert(~dut.busy | busy_states, "lemma: the engine is in a state"),
                Assert(~dut.busy | pending, "lemma: busy only after an accepted start"),
                Assert(dut.busy | ~pending | dut.done, "lemma: pending ends with done"),
                Assert(~dut.busy | (req == request.as_value()), "lemma: the request latched"),
                Assert(~dut.busy | (count >= 1) & (count <= ACCESS_COUNT_MAX),
                       "lemma: count 1 .. 64"),
                Assert(r <= idle, "lemma: idle run at most 14"),
                Assert(seen <= idle, "lemma: idle count before S at most 14"),
                Assert(~(state["LEAD"] | state["HEADER"]) | (index == 0), "lemma: index 0"),
                Assert(~(in_register | state["WAIT"]) | (index < count),
                       "lemma: index below the count"),
                Assert(~state["HEADER"] | (step < CONTROL_HEADER_FRAMES), "lemma: header step"),
                Assert(~in_register | (step < CONTROL_REGISTER_FRAMES),
                       "lemma: register step"),
                Assert(~state["WAIT"] | (waited < w_frames), "lemma: wait count"),
                Assert(~(state["LEAD"] | state["HEADER"] & (step == 0))
                       | header[CONTROL_HEADER_FRAMES - 1], "lemma: S first in the header"),
                # Which cycles carry CDM = 0, and the zeros that have ended since the last 1.
                Assert(~(in_register & ((step == CONTROL_REGISTER_FRAMES - 1)
                                        | read & (step >= 1))) | ~(f & c),
                       "lemma: P and a read's frames after S carry 0"),
                Assert(~(in_register & read & (step >= 2)) | (r + 2 >= step),
                       "lemma: a read's zeros since its start bit"),
                Assert(~state["FINAL"] | ~(f & c), "lemma: the final frame carries 0"),
                Assert(~state["FINAL"] | (r >= Mux(write, 1, idle - 2)),
                       "lemma: the zeros ended before the final frame"),
                Assert(~(state["CANCEL"] & f & c) | (ending == ACCESS_ABORTED),
                       "lemma: a CDM = 1 in flight in a cancel only after an abort"),
                Assert(~(dut.busy & pending) | (frames + left <= bound),
                       "lemma: frames so far + frames left <= the bound"),
            ]

        if self.cover == "bound":
            # The bound is reached: an access ends after exactly its bound of frames.
            m.d.comb += Cover(dut.done & pending & (frames == bound))
        else:
            # Non-vacuity: a read of one byte ends OK.
            m.d.comb += Cover(dut.done & (status == ACCESS_OK) & pending & ~write
                              & (count == 1))
        return m


# =============================================================================================
# (f) Confirmation after a fault: no valid frame within cfg_confirm_frames frames of a fault
# =============================================================================================
class _JudgedFrame(Elaboratable):
    """FrameVerdict and Confirmation wired as :class:`~bissmaster.master.BissMaster` wires them
    (the verdict's status and report into the confirmation, its ``pending`` back as
    ``unconfirmed``). ``mutation="unwired"`` leaves ``unconfirmed`` at 0."""

    def __init__(self, params, mutation=None):
        self.verdict = FrameVerdict(params)
        self.confirmation = Confirmation()
        self.mutation = mutation

    def elaborate(self, platform):
        m = Module()
        m.submodules.verdict = v = self.verdict
        m.submodules.confirmation = c = self.confirmation
        m.d.comb += [c.report.eq(v.report), c.status.eq(v.status)]
        if self.mutation != "unwired":
            m.d.comb += v.unconfirmed.eq(c.pending)
        return m


class ConfirmationHarness(Harness):
    """The verdict and the confirmation: every verdict input free in every clock (a frame
    report and a fault never in one clock, as the controller makes them; a fault's status one
    of NO_ACK .. NO_STOP), ``cfg_confirm_frames`` one free value for the trace.

    The harness keeps its own account from the reported statuses (docs/ports.md, "Confirmation
    after a fault"): whether a fault (any status outside CONFIRM_NEUTRAL) was reported, and how
    many frames that passed every check (status OK or UNCONFIRMED) were reported since the last
    one. With N = the setting (0: 1) and the setting not 15, properties: (1) a frame is valid
    only if no fault was reported yet or N such frames came since the last fault; (2) a frame
    that passes every check with that behind it (or with the setting 15) is valid: exactly N
    are withheld. Lemma (k-induction): the block's count of frames still to confirm is what
    the account says. Mutation ``"unwired"``: the confirmation not wired into the verdict; (1)
    must fail.
    """

    def __init__(self, params, lemmas=True, mutation=None):
        super().__init__(params=params, lemmas=lemmas, mutation=mutation)

    def elaborate(self, platform):
        m = self._module()
        dut = _JudgedFrame(self.params, self.mutation)
        inside = Inside(dut)
        m.submodules.dut = inside.fragment
        v = dut.verdict

        for name in ("report_frame", "fault", "crc_ok", "lc_repeat_seen", "lc_skip_seen",
                     "lc_zero_seen", "spw_match", "noisy", "delay_jump"):
            port = getattr(v, name)
            m.d.comb += port.eq(self.any_seq(len(port), name))
        cfg = Value.cast(v.cfg)
        m.d.comb += cfg.eq(self.any_seq(len(cfg), "cfg"))
        fault_status = Value.cast(v.fault_status)
        m.d.comb += fault_status.eq(self.any_seq(len(fault_status), "fault_status"))
        m.d.comb += [
            Assume(~(v.report_frame & v.fault)),
            Assume(~v.fault | ((fault_status >= STATUS["NO_ACK"])
                               & (fault_status <= STATUS["NO_STOP"]))),
        ]
        setting = self.any_const(m, len(dut.confirmation.setting), "confirm_frames")
        m.d.comb += dut.confirmation.setting.eq(setting)

        # The account, from the reported status alone.
        status = Value.cast(v.status)
        top = 2**len(setting) - 1
        fault = v.report & ~Cat(status == STATUS[n] for n in CONFIRM_NEUTRAL).any()
        passed_now = v.report_frame & ((status == STATUS["OK"]) | (status == STATUS["UNCONFIRMED"]))
        fault_seen = Signal()
        passed = Signal(len(setting))           # frames that passed since the last fault
        with m.If(fault):
            m.d.sync += [fault_seen.eq(1), passed.eq(0)]
        with m.Elif(passed_now & (passed != top)):
            m.d.sync += passed.eq(passed + 1)
        frames = Mux(setting == 0, CONFIRM_FRAMES_DEFAULT, setting)
        on = setting != CHECK_OFF
        owed = fault_seen & on & (passed < frames)

        m.d.comb += [
            Assert(~v.valid | ~owed, "valid only with N clean frames since the last fault"),
            Assert(~passed_now | owed | v.valid, "a clean frame with N behind it is valid"),
            Assert(~v.valid | v.report_frame, "valid only with a frame"),
        ]
        if self.lemmas:
            left = inside("confirm.left")
            m.d.comb += [
                Assert(~owed | (left == frames - passed), "lemma: frames still owed"),
                Assert(owed | ~on | (left == 0), "lemma: nothing owed"),
            ]
        # Non-vacuity: a frame withheld, then a valid one, after a fault, with N = 2.
        m.d.comb += [
            Cover(v.valid & fault_seen & (setting == 2)),
            Cover(passed_now & ~v.valid & (setting == 2) & (passed == 1)),
        ]
        return m
