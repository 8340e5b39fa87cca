"""BiSS C / BiSS Safety master: the top level, which only connects the blocks."""

from types import SimpleNamespace

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .core.confirmation import Confirmation
from .core.configuration import Configuration
from .core.chain_results import CHAIN_ADDR_BITS, ChainResults
from .core.counter_ram import CounterRam
from .core.counters import CounterBank
from .core.cycle_controller import CycleController
from .core.delay_check import DelayCheck
from .core.frame_decoder import FrameDecoder
from .core.frame_verdict import FrameVerdict
from .layouts import (BUFFER_LANES, BUFFER_WORD_BITS, access_request_layout, access_result_layout,
                      buffer_write_layout, config_custom_crcs, config_enables, config_ports,
                      config_words, counter_names, counter_ports, counter_slots, COUNT_ADDR_BITS, field,
                      flat_fields, result_layout)
from .core.limit_timers import LimitTimers
from .core.line_noise import LineNoise
from .core.ma_clock import MaClock
from .core.ma_stop import MaStop
from . import protocol
from .params import (CHAIN_FIRST_WORD, CHAIN_MEMORY_WORD_BITS, CRC_TABLE, DELAY_SPREAD_WIDTH,
                     LINE_CHECK_WIDTH, AccessStatus, MasterParams, Status,
                     word_config)
from .control.register_access import RegisterAccess
from .core.request_scheduler import RequestScheduler
from .core.results import ResultRegisters
from .core.sign_of_life import SignOfLife
from .core.slo_sampler import SloSampler
from .core.spw_check import SpwCheck
from .core.time_base import TimeBase


class BissMaster(wiring.Component):
    """BiSS C / BiSS Safety master for one encoder.

    See ``docs/ports.md`` for the port table and ``docs/timing.md`` for one request cycle.
    Runtime settings (``cfg_*``) are checked when a request arrives and latched for the
    cycle: changing them mid-cycle never mixes two configurations in one frame. (A
    ``config_hold`` build latches none: its ``cfg_*`` change only while ``cfg_hold`` keeps it
    idle, :class:`~bissmaster.params.MasterParams`; a ``crc_table`` build reads its custom
    CRCs' polynomials, start values and inversions from a table outside it.)

    The ports are flat (Verilog users wire them one by one); inside, the configuration, the
    result and the counters are the structures of :mod:`~bissmaster.layouts`, and the port
    names are derived from them by :func:`~bissmaster.layouts.flat_fields` alone.

    The data flow: :class:`RequestScheduler` -> :class:`CycleController` (with
    :class:`Configuration`, :class:`LimitTimers`) -> :class:`MaClock` -> line ->
    :class:`SloSampler` -> :class:`FrameDecoder` (:class:`WordCrc` per word) ->
    :class:`SignOfLife`, :class:`SpwCheck`, :class:`LineNoise`, :class:`DelayCheck` ->
    :class:`FrameVerdict` -> :class:`ResultRegisters`, :class:`CounterBank` (or, with
    ``counter_ram``, :class:`CounterRam`). With ``register_access``, :class:`RegisterAccess`
    supplies each cycle's CDM bit to the controller (which holds MA low through the encoder's
    timeout for CDM = 1) and takes each frame's CDS (``ca_*`` ports, docs/control.md).

    Parameters
    ----------
    params : MasterParams
    trigger : bool
        Add the input ``trigger`` (a request, exactly like ``start``): the seam a multi-channel
        top drives to start several channels in the same clock. The standalone core has none.
    """

    def __init__(self, params=None, *, trigger=False):
        if params is None:
            params = MasterParams()
        if not isinstance(params, MasterParams):
            raise TypeError(f"params must be a MasterParams, not {params!r}")
        self.params = p = params
        self.has_trigger = bool(trigger)
        self._config_fields = config_ports(p)
        self._result_fields = flat_fields(result_layout(p))
        if p.register_access:
            self._access_request_fields = flat_fields(access_request_layout(), "ca_")
            self._access_wbuf_fields = flat_fields(buffer_write_layout(), "ca_wbuf_")
            self._access_result_fields = flat_fields(access_result_layout(), "ca_")
        super().__init__(self.ports(p, trigger=trigger))

    @staticmethod
    def ports(params, *, trigger=False):
        """``{port name: wiring member}`` of the core built with ``params``, in port order."""
        p = params
        if p.register_access:
            access_ports = {
                **{name: In(shape) for name, _, shape in flat_fields(access_request_layout(),
                                                                     "ca_")},
                "ca_start": In(1),
                "ca_abort": In(1),
                **{name: In(shape) for name, _, shape in flat_fields(buffer_write_layout(),
                                                                     "ca_wbuf_")},
                "ca_rbuf_addr": In(BUFFER_WORD_BITS),
                "ca_rbuf_en": In(1),
                "ca_rbuf_data": Out(BUFFER_LANES * 8),
                "ca_busy": Out(1),
                "ca_done": Out(1),
                **{name: Out(shape) for name, _, shape in flat_fields(access_result_layout(),
                                                                      "ca_")},
            }
        else:
            access_ports = {}
        return {
            # Line
            "ma": Out(1, init=1),
            "slo": In(1, init=1),
            # Control
            "start": In(1),
            **({"trigger": In(1)} if trigger else {}),
            "periodic": In(1),
            "abort_cycle": In(1),
            **({"clear_counters": In(1)} if p.counters else {}),
            **({"time_now": In(p.timestamp_width)} if p.time_input else {}),
            # Runtime configuration
            **{name: In(shape) for name, _, shape in config_ports(p)},
            **({"cfg_hold": In(1)} if p.config_hold else {}),
            # The custom CRCs' table (``crc_table``): word ``crc_table_addr``'s entry, read
            # combinationally.
            **({"crc_table_addr": Out(range(p.words)), "crc_table_data": In(CRC_TABLE)}
               if p.crc_table_built else {}),
            # State
            "busy": Out(1),
            "config_error": Out(1),
            "overrun": Out(1),
            # Result of the last cycle
            "done": Out(1),
            "valid": Out(1),
            **{name: Out(shape) for name, _, shape in flat_fields(result_layout(p))},
            # Register access (control channel)
            **access_ports,
            # Error counters
            **{f"count_{name}": Out(p.counter_width) for name in counter_ports(p)},
            **({"count_addr": In(COUNT_ADDR_BITS), "count_en": In(1), "count_data": Out(32),
                "count_busy": Out(1)} if p.counter_ram else {}),
            # Words 2.. in the chain memory
            **({"chain_addr": In(CHAIN_ADDR_BITS),
                "chain_en": In(1), "chain_data": Out(CHAIN_MEMORY_WORD_BITS)}
               if p.chain_words_in_memory else {}),
        }

    @property
    def counter_names(self):
        """The error counters this build has (``count_<name>`` ports, or with ``counter_ram``
        the counter memory's slots for the data channel's)."""
        return counter_names(self.params)

    def elaborate(self, platform):
        m = Module()
        b = self._blocks(m)
        self._connect_inputs(m, b)
        self._connect_control(m, b)
        self._connect_receiver(m, b)
        self._connect_results(m, b)
        if self.params.register_access:
            self._connect_register_access(m, b)
        if self.params.counters:
            self._connect_counters(m, b)
        self._connect_outputs(m, b)
        return m

    def _blocks(self, m):
        """Every block of the master, as attributes of one namespace."""
        p = self.params
        two = p.words >= 2
        m.submodules.config = config = Configuration(p)
        m.submodules.scheduler = scheduler = RequestScheduler(p.timer_width, hold=p.config_hold)
        cdm = p.register_access
        m.submodules.controller = controller = CycleController(cdm=cdm)
        m.submodules.timers = timers = LimitTimers(p)
        m.submodules.ma_clock = ma_clock = MaClock(cdm=cdm, half_period_width=p.half_period_width)
        m.submodules.ma_stop = ma_stop = MaStop(p.words, ssi=p.ssi, word_layout=word_config(p))
        # The receiver is held in reset between cycles: every cycle starts from scratch.
        sampler = SloSampler(p.delay_width, fixed=p.ssi, half_period_width=p.half_period_width)
        decoder = FrameDecoder(p)
        m.submodules.sampler = ResetInserter(controller.receiver_clear)(sampler)
        m.submodules.decoder = ResetInserter(controller.receiver_clear)(decoder)
        m.submodules.sign_of_life = sol = SignOfLife(early=True)
        if two:
            m.submodules.spw_check = spw_check = SpwCheck(p.max_data_bits[1])
        m.submodules.line_noise = line_noise = LineNoise()
        m.submodules.delay_check = delay_check = DelayCheck(
            p.delay_width, settle_frames=protocol.DELAY_SETTLE_FRAMES,
            tolerance_width=p.delay_tolerance_width, spread_width=DELAY_SPREAD_WIDTH)
        m.submodules.verdict = verdict = FrameVerdict(p)
        m.submodules.confirmation = confirmation = Confirmation()
        m.submodules.results = results = ResultRegisters(p)
        if p.timestamped:
            m.submodules.time_base = time_base = TimeBase(p.timestamp_width, p.time_input)
        if counter_ports(p):
            m.submodules.counters = counters = CounterBank(counter_ports(p), p.counter_width)
        if p.counter_ram:
            m.submodules.counter_ram = counter_ram = CounterRam(counter_slots(p),
                                                                p.counter_width)
        if cdm:
            m.submodules.register_access = access = RegisterAccess(p.start_wait_frames)
        if p.chain_words_in_memory:
            m.submodules.chain_results = chain_results = ChainResults(
                p.words, max(p.max_data_bits[CHAIN_FIRST_WORD:]))

        cycle = config.cycle
        words = config_words(cycle, p)
        ssi = cycle.ssi if p.ssi else C(0)        # the cycle is an SSI frame
        return SimpleNamespace(ssi=ssi,
            config=config, scheduler=scheduler, controller=controller, timers=timers,
            ma_clock=ma_clock, ma_stop=ma_stop, sampler=sampler, decoder=decoder, sol=sol,
            spw_check=spw_check if two else None, line_noise=line_noise,
            delay_check=delay_check, verdict=verdict, confirmation=confirmation, results=results,
            time_base=time_base if p.timestamped else None,
            counters=counters if counter_ports(p) else None,
            counter_ram=counter_ram if p.counter_ram else None,
            chain_results=chain_results if p.chain_words_in_memory else None,
            access=access if cdm else None, cycle=cycle, words=words)

    def _connect_inputs(self, m, b):
        """The control ports and the flat configuration, in."""
        m.d.comb += [field(b.config.live, path).eq(getattr(self, name))
                     for name, path, _ in self._config_fields]
        m.d.comb += [
            b.config.idle.eq(b.controller.idle),
            b.scheduler.start.eq(self.start),
            # A register access asks for periodic cycles when the host does not.
            b.scheduler.periodic.eq(self.periodic | b.access.frames if b.access is not None
                                    else self.periodic),
            b.scheduler.period.eq(self.cfg_request_period),
            b.scheduler.abort.eq(self.abort_cycle),
            b.scheduler.idle.eq(b.controller.idle),
            b.sampler.slo.eq(self.slo),
        ]
        if self.has_trigger:
            m.d.comb += b.scheduler.trigger.eq(self.trigger)
        if self.params.config_hold:
            m.d.comb += b.scheduler.hold.eq(self.cfg_hold)

    def _connect_control(self, m, b):
        """The controller, its limits and the MA clock."""
        p = self.params
        m.d.comb += [
            b.controller.request.eq(b.scheduler.request),
            b.controller.abort.eq(self.abort_cycle),
            b.controller.config_ok.eq(b.config.ok),
            b.controller.end_check.eq(b.cycle.end_check),
            b.controller.slo.eq(b.sampler.level),
            b.controller.ma_busy.eq(b.ma_clock.busy),
            b.controller.ma_arm.eq(b.ma_clock.second_rise),
            b.controller.ma_enough.eq(b.ma_stop.enough),
            b.controller.locked.eq(b.sampler.locked),
            b.controller.early.eq(b.sampler.early),
            # SSI: the frame ends with its stop bit (checked there).
            b.controller.frame_done.eq(b.decoder.frame_end),
            b.controller.ssi.eq(b.ssi),
            b.controller.timeout_over.eq(b.timers.timeout_over if p.ssi else 0),
            b.controller.started.eq(b.decoder.started),
            b.controller.slots_full.eq(b.decoder.slots_full),
            b.controller.stopped.eq(b.decoder.stopped),
            b.controller.stop_bit.eq(b.decoder.stop_bit),
            b.controller.frame_doubtful.eq(b.verdict.doubtful),
            b.controller.break_over.eq(b.timers.break_over),
            b.controller.ack_expired.eq(b.timers.ack_expired),
            b.controller.no_start_expired.eq(b.timers.no_start_expired),
            b.controller.slo_stuck.eq(b.timers.slo_stuck),
            b.controller.slo_stuck_live.eq(b.timers.slo_stuck_live),
            b.controller.delay_over.eq(b.timers.delay_over),

            b.timers.slo.eq(b.sampler.level),
            # The SLO-low timer counts while MA is not clocking: a CDM hold is the encoder's
            # timeout too.
            b.timers.ma_busy.eq(b.ma_clock.clocking if b.access is not None
                                else b.ma_clock.busy),
            b.timers.clear.eq(b.controller.timer_clear),
            b.timers.in_clock.eq(b.controller.in_clock),
            b.timers.restart.eq(b.controller.restart_timer),
            b.timers.break_time.eq(self.cfg_break_time),
            b.timers.timeout_live.eq(self.cfg_timeout_limit),
            b.timers.ack_limit.eq(b.config.ack_limit),
            b.timers.timeout_limit.eq(b.config.timeout_limit),
            b.timers.no_start_limit.eq(b.config.no_start_limit),
            b.timers.delay.eq(b.sampler.delay),
            b.timers.delay_limit.eq(b.config.delay_limit),
            b.timers.quiet_time_live.eq(self.cfg_quiet_time),
            b.timers.quiet_limit.eq(b.config.quiet_time),
            b.controller.quiet.eq(b.timers.quiet),
            b.controller.quiet_live.eq(b.timers.quiet_live),

            b.ma_clock.run.eq(b.controller.ma_run),
            b.ma_clock.half_period.eq(b.cycle.ma_half_period),
            b.ma_stop.started.eq(b.decoder.started),
            b.ma_stop.start_slot.eq(b.decoder.start_slot),
            b.ma_stop.rises.eq(b.ma_clock.rises),
            b.ma_stop.clear.eq(b.controller.receiver_clear),
        ]

    def _connect_receiver(self, m, b):
        """Sampler -> decoder -> checks."""
        p = self.params
        two = p.words >= 2
        # One register stage between the sampler's decision and the decoder: the vote decode and
        # the decoder's shift enables are too much for one clock at 100 MHz (ECP5). The verdict
        # comes one clock later. The strobe is cleared with the receiver, so a decision made in
        # a clock of the clear never reaches the decoder after it.
        # Named apart from the sampler's ``sample``, which stays the decision in the Verilog.
        sample = Signal(name="decoder_sample")
        bit = Signal(name="decoder_bit")
        m.d.sync += [sample.eq(b.sampler.sample & ~b.controller.receiver_clear),
                     bit.eq(b.sampler.bit)]
        m.d.comb += [b.decoder.sample.eq(sample), b.decoder.bit.eq(bit)]
        m.d.comb += [
            b.sampler.half_period.eq(b.cycle.ma_half_period),
            # SSI: the first bit comes with the first rise (BiSS: the Ack with the second).
            b.sampler.arm.eq(Mux(b.ssi, b.ma_clock.first_rise, b.ma_clock.second_rise)),
            b.decoder.word_count.eq(b.config.word_count),
            b.sol.lc.eq(b.decoder.lc),
            b.sol.lc_next.eq(b.decoder.lc_next),
            b.sol.load.eq(b.decoder.lc_load),
            b.sol.check.eq(b.verdict.lc_check),
            b.sol.resync.eq(b.controller.resync),
        ]
        # The line checks (issue 28): noise events, and the round trip against the settled one,
        # judged when Start is found: the delay is final from the Ack's lock on, at least one
        # slot before, and the judgement (a clock later) is ready long before the frame's end.
        off = 2**LINE_CHECK_WIDTH - 1
        started_before = Signal()
        m.d.sync += started_before.eq(b.decoder.started)
        # The round trip is learned one clock after the report (registered: the verdict's
        # ``clean`` comes from the noise judgement through the whole verdict, too long a path
        # in front of the delay check's enables). The frame's results are latched at the
        # report either way, from the state before the learn; the delay and the tolerance hold
        # for that clock (the next cycle's configuration and receiver clear come later).
        learn, clean = Signal(), Signal()
        m.d.sync += [learn.eq(b.controller.report_frame), clean.eq(b.verdict.clean)]
        m.d.comb += [
            b.line_noise.watch.eq(b.controller.waiting),
            b.line_noise.level.eq(b.sampler.level),
            b.line_noise.sampler_noise.eq(b.sampler.noise),
            # A frame's end: its last word bit (BiSS), the bit after the word (SSI, where the
            # verdict waits for that bit too).
            b.line_noise.close.eq(b.decoder.frame_end),
            b.line_noise.restart.eq(b.controller.fault),
            b.line_noise.limit.eq(b.cycle.noise_limit),
            # SSI sets its round trip: nothing to check it against.
            b.delay_check.enable.eq((b.cycle.delay_tolerance != off) & ~b.ssi),
            b.delay_check.tolerance.eq(b.config.delay_tolerance),
            # Writing 15 forgets the settled round trip at once, whatever the master is doing.
            b.delay_check.rearm.eq(self.cfg_delay_tolerance == off),
            b.delay_check.delay.eq(b.sampler.delay),
            b.delay_check.check.eq(b.decoder.started & ~started_before),
            b.delay_check.learn.eq(learn),
            b.delay_check.clean.eq(clean),
            b.verdict.noisy.eq(b.line_noise.noisy),
            b.verdict.delay_jump.eq(b.delay_check.jump),
        ]
        for w, word in enumerate(b.words):
            m.d.comb += [b.decoder.words[w].eq(word), b.ma_stop.words[w].eq(word)]
        m.d.comb += [b.decoder.crc_widths.eq(b.config.crc_widths),
                     b.ma_stop.crc_widths.eq(b.config.crc_widths)]
        if p.words == 1:
            m.d.comb += b.decoder.word0_crc.eq(b.config.crc)
        elif p.crc_table_built:
            m.d.comb += [self.crc_table_addr.eq(b.decoder.crc_table_addr),
                         b.decoder.crc_table_data.eq(self.crc_table_data)]
        else:
            for w, custom in enumerate(config_custom_crcs(b.cycle, p)):
                m.d.comb += b.decoder.customs[w].eq(custom)
        m.d.comb += b.ma_stop.enables.eq(Cat(*config_enables(b.cycle, p)))
        if two:
            m.d.comb += [
                b.spw_check.cpw_top.eq(b.decoder.cpw_top),
                b.spw_check.spw.eq(b.decoder.data1),
                b.spw_check.bits.eq(b.cycle.w1.data_bits),
                b.spw_check.tolerance.eq(b.cycle.spw_tolerance),
                b.verdict.spw_match.eq(b.spw_check.match),
            ]
        if p.ssi:
            m.d.comb += [
                b.sampler.fixed.eq(b.cycle.ssi),
                b.sampler.fixed_delay.eq(b.cycle.ssi_delay),
                b.decoder.ssi.eq(b.cycle.ssi),
                b.decoder.ssi_error.eq(b.cycle.ssi_error),
                b.decoder.ssi_error_low.eq(b.cycle.ssi_error_low),
                b.decoder.ssi_double.eq(b.cycle.ssi_double),
                b.ma_stop.ssi.eq(b.cycle.ssi),
                b.ma_stop.ssi_double.eq(b.cycle.ssi_double),
                b.ma_stop.ssi_error.eq(b.cycle.ssi_error),
                b.verdict.copy_mismatch.eq(b.decoder.mismatch),
            ]

    def _connect_results(self, m, b):
        """Verdict -> result registers."""
        p = self.params
        two = p.words >= 2
        m.d.comb += [
            b.verdict.cfg.eq(b.cycle),
            b.verdict.report_frame.eq(b.controller.report_frame),
            b.verdict.fault.eq(b.controller.fault),
            b.verdict.fault_status.eq(b.controller.fault_status),
            b.verdict.crc_ok.eq(b.decoder.crc_ok),
            b.verdict.lc_repeat_seen.eq(b.sol.repeat),
            b.verdict.lc_skip_seen.eq(b.sol.skip),
            b.verdict.lc_zero_seen.eq(b.sol.zero),
            b.verdict.unconfirmed.eq(b.confirmation.pending),
            b.confirmation.report.eq(b.verdict.report),
            b.confirmation.status.eq(b.verdict.status),
            b.confirmation.setting.eq(b.cycle.confirm_frames),

            b.results.report.eq(b.verdict.report),
            b.results.report_frame.eq(b.controller.report_frame),
            b.results.report_delay.eq(b.controller.report_delay),
            b.results.valid.eq(b.verdict.valid),
        ]
        frame = b.results.frame
        m.d.comb += [
            frame.status.eq(b.verdict.status),
            frame.line_delay.eq(b.sampler.delay),
            frame.cds.eq(b.decoder.cds),
            frame.noise_events.eq(b.line_noise.events),
            frame.delay_settled.eq(b.delay_check.settled),
            frame.settled_delay.eq(b.delay_check.settled_delay),
            frame.delay_spread.eq(b.delay_check.spread),
            frame.lc.eq(b.decoder.lc),
            frame.lc_repeat.eq(b.verdict.lc_repeat),
            frame.lc_skip.eq(b.verdict.lc_skip),
            frame.lc_zero.eq(b.verdict.lc_zero),
        ]
        for w in range(p.words):
            word = frame[f"word{w}"]
            if hasattr(b.decoder, f"data{w}"):
                m.d.comb += word.position.eq(getattr(b.decoder, f"data{w}"))
            m.d.comb += [
                word.ne.eq(b.decoder.ne[w]),
                word.nw.eq(b.decoder.nw[w]),
                word.crc_ok.eq(b.verdict.word_crc_ok[w]),
            ]
        if two:
            m.d.comb += frame.spw_mismatch.eq(b.verdict.spw_mismatch)
        if b.chain_results is not None:
            # Words 2..: written by the decoder as each ends, published with the frame's
            # other fields (the result registers' report_frame), read through their port.
            chain = b.chain_results
            m.d.comb += [
                chain.data.eq(b.decoder.chain_data),
                chain.index.eq(b.decoder.chain_index),
                chain.word_end.eq(b.decoder.chain_end),
                chain.publish.eq(b.controller.report_frame),
                chain.words_published.eq(b.config.word_count),
                chain.read_addr.eq(self.chain_addr),
                chain.read_en.eq(self.chain_en),
                self.chain_data.eq(chain.read_data),
            ]
        if p.timestamped:
            m.d.comb += [b.time_base.first_rise.eq(b.ma_clock.first_rise),
                         frame.timestamp.eq(b.time_base.first_rise_time)]
            if p.time_input:
                m.d.comb += b.time_base.now.eq(self.time_now)

    def _connect_register_access(self, m, b):
        """The register-access engine: its ports, the CDM bit to the controller and MA, the
        CDS of every reported frame back."""
        access = b.access
        m.d.comb += [field(access.request, path).eq(getattr(self, name))
                     for name, path, _ in self._access_request_fields]
        m.d.comb += [field(access.wbuf, path).eq(getattr(self, name))
                     for name, path, _ in self._access_wbuf_fields]
        m.d.comb += [getattr(self, name).eq(field(access.result, path))
                     for name, path, _ in self._access_result_fields]
        m.d.comb += [
            access.start.eq(self.ca_start),
            access.abort.eq(self.ca_abort),
            access.rbuf_addr.eq(self.ca_rbuf_addr),
            access.rbuf_en.eq(self.ca_rbuf_en),
            self.ca_rbuf_data.eq(access.rbuf_data),
            self.ca_busy.eq(access.busy),
            self.ca_done.eq(access.done),

            # SSI has no control channel: no CDM hold, and no frame passes for it (an access
            # ends with DATA_FAULT at its first frame).
            b.controller.cdm.eq(access.cdm & ~b.ssi),
            b.controller.ma_held.eq(b.ma_clock.held),
            b.ma_clock.hold.eq(b.controller.ma_hold),

            access.frame_end.eq(b.verdict.report),
            access.frame_ok.eq(b.verdict.passed & ~b.ssi),
            access.frame_cds.eq(b.decoder.cds),
            access.frame_cdm.eq(b.controller.cdm_cycle),
        ]

    def _connect_counters(self, m, b):
        """The counter bank's events."""
        p = self.params
        two = p.words >= 2
        faults = b.controller.faults
        events = {
            "crc_word0": b.verdict.crc_error[0],
            "no_ack": faults.no_ack,
            "no_start": faults.no_start,
            "delay_range": faults.delay_range,
            "slo_stuck_low": faults.slo_stuck_low,
            "lc_repeat": b.verdict.lc_repeat,
            "lc_skip": b.verdict.lc_skip,
            "lc_zero": b.verdict.lc_zero,
            "overrun": b.scheduler.overrun,
            "aborted": faults.aborted,
            "no_stop": faults.no_stop,
            "noisy_line": b.results.report_frame & (b.verdict.status == Status.NOISY_LINE),
            "delay_jump": b.results.report_frame & (b.verdict.status == Status.DELAY_JUMP),
            "noise_event": b.line_noise.event,
        }
        if b.access is not None:
            for status in (AccessStatus.CRC4_ERROR, AccessStatus.NO_ANSWER,
                           AccessStatus.REFUSED, AccessStatus.ABORTED, AccessStatus.DATA_FAULT):
                events[f"ca_{status.name.lower()}"] = (b.access.done
                                                       & (b.access.result.status == status))
        # Each word's CRC failures (a chain: every word its own counter).
        for w in range(1, p.words):
            events[f"crc_word{w}"] = b.verdict.crc_error[w]
        if two:
            events["spw_mismatch"] = b.controller.report_frame & b.verdict.spw_mismatch
        if b.counters is not None:
            ports = counter_ports(p)
            m.d.comb += [b.counters.events[name].eq(events[name]) for name in ports]
            m.d.comb += b.counters.clear.eq(self.clear_counters)
            m.d.comb += [getattr(self, f"count_{name}").eq(b.counters.counts[name])
                         for name in ports]
        if b.counter_ram is not None:
            ram = b.counter_ram
            m.d.comb += [ram.events[name].eq(events[name])
                         for name in counter_slots(p) if name is not None]
            m.d.comb += [ram.clear.eq(self.clear_counters), ram.read_addr.eq(self.count_addr),
                         ram.read_en.eq(self.count_en), self.count_data.eq(ram.read_data),
                         self.count_busy.eq(ram.busy)]

    def _connect_outputs(self, m, b):
        """The state and result ports, out."""
        m.d.comb += [
            self.ma.eq(b.ma_clock.ma),
            self.busy.eq(~b.controller.idle),
            self.config_error.eq(~b.config.ok),
            self.overrun.eq(b.scheduler.overrun),
            self.done.eq(b.results.done),
            self.valid.eq(b.results.valid_out),
        ]
        m.d.comb += [getattr(self, name).eq(field(b.results.result, path))
                     for name, path, _ in self._result_fields]
