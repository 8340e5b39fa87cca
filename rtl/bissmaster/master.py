"""BiSS C / BiSS Safety master: the top level, which only connects the blocks."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .configuration import Configuration
from .counters import CounterBank
from .cycle_controller import CycleController
from .frame_decoder import FrameDecoder
from .frame_verdict import FrameVerdict
from .layouts import (config_layout, config_words, counter_names, field, flat_fields,
                      result_layout)
from .limit_timers import LimitTimers
from .ma_clock import MaClock
from .ma_stop import MaStop
from .params import MasterParams
from .request_scheduler import RequestScheduler
from .results import ResultRegisters
from .sign_of_life import SignOfLife
from .slo_sampler import SloSampler
from .spw_check import SpwCheck
from .time_base import TimeBase


class BissMaster(wiring.Component):
    """BiSS C / BiSS Safety master for one encoder.

    See ``docs/ports.md`` for the port table and ``docs/timing.md`` for one request cycle.
    Runtime settings (``cfg_*``) are checked when a request arrives and latched for the
    cycle: changing them mid-cycle never mixes two configurations in one frame.

    The ports are flat (Verilog users wire them one by one); inside, the configuration, the
    result and the counters are the structures of :mod:`~bissmaster.layouts`, and the port
    names are derived from them by :func:`~bissmaster.layouts.flat_fields` alone.

    The data flow: :class:`RequestScheduler` -> :class:`CycleController` (with
    :class:`Configuration`, :class:`LimitTimers`) -> :class:`MaClock` -> line ->
    :class:`SloSampler` -> :class:`FrameDecoder` (:class:`WordCrc` per word) ->
    :class:`SignOfLife`, :class:`SpwCheck` -> :class:`FrameVerdict` -> :class:`ResultRegisters`,
    :class:`CounterBank`.

    Parameters
    ----------
    params : MasterParams
    """

    def __init__(self, params=None):
        if params is None:
            params = MasterParams()
        if not isinstance(params, MasterParams):
            raise TypeError(f"params must be a MasterParams, not {params!r}")
        self.params = p = params
        self._config_fields = flat_fields(config_layout(p), "cfg_")
        self._result_fields = flat_fields(result_layout(p))
        ports = {
            # Line
            "ma": Out(1, init=1),
            "slo": In(1, init=1),
            # Control
            "start": In(1),
            "periodic": In(1),
            "abort_cycle": In(1),
            **({"clear_counters": In(1)} if p.counters else {}),
            # Runtime configuration
            **{name: In(shape) for name, _, shape in self._config_fields},
            # State
            "busy": Out(1),
            "config_error": Out(1),
            "overrun": Out(1),
            # Result of the last cycle
            "done": Out(1),
            "valid": Out(1),
            **{name: Out(shape) for name, _, shape in self._result_fields},
            # Error counters
            **{f"count_{name}": Out(p.counter_width) for name in self.counter_names},
        }
        super().__init__(ports)

    @property
    def counter_names(self):
        """The error counters this build has (``count_<name>`` ports)."""
        return counter_names(self.params)

    def elaborate(self, platform):
        m = Module()
        p = self.params
        two = p.words == 2

        # -- Blocks ---------------------------------------------------------------------------
        m.submodules.config = config = Configuration(p)
        m.submodules.scheduler = scheduler = RequestScheduler(p.timer_width)
        m.submodules.controller = controller = CycleController()
        m.submodules.timers = timers = LimitTimers(p)
        m.submodules.ma_clock = ma_clock = MaClock()
        m.submodules.ma_stop = ma_stop = MaStop(p.words)
        # The receiver is held in reset between cycles: every cycle starts from scratch.
        sampler = SloSampler(p.delay_width)
        decoder = FrameDecoder(p)
        m.submodules.sampler = ResetInserter(controller.receiver_clear)(sampler)
        m.submodules.decoder = ResetInserter(controller.receiver_clear)(decoder)
        m.submodules.sign_of_life = sol = SignOfLife(early=True)
        if two:
            m.submodules.spw_check = spw_check = SpwCheck(p.max_data_bits[1])
        m.submodules.verdict = verdict = FrameVerdict(p)
        m.submodules.results = results = ResultRegisters(p)
        if p.timestamped:
            m.submodules.time_base = time_base = TimeBase(p.timestamp_width)
        if p.counters:
            m.submodules.counters = counters = CounterBank(self.counter_names, p.counter_width)

        cycle = config.cycle
        words = config_words(cycle, p)

        # -- Ports in: control and the flat configuration ---------------------------------------
        m.d.comb += [field(config.live, path).eq(getattr(self, name))
                     for name, path, _ in self._config_fields]
        m.d.comb += [
            config.idle.eq(controller.idle),
            scheduler.start.eq(self.start),
            scheduler.periodic.eq(self.periodic),
            scheduler.period.eq(self.cfg_request_period),
            scheduler.abort.eq(self.abort_cycle),
            scheduler.idle.eq(controller.idle),
            sampler.slo.eq(self.slo),
        ]

        # -- Controller, its limits and the MA clock -----------------------------------------------
        m.d.comb += [
            controller.request.eq(scheduler.request),
            controller.abort.eq(self.abort_cycle),
            controller.config_ok.eq(config.ok),
            controller.end_check.eq(cycle.end_check),
            controller.slo.eq(sampler.level),
            controller.ma_busy.eq(ma_clock.busy),
            controller.ma_arm.eq(ma_clock.second_rise),
            controller.ma_enough.eq(ma_stop.enough),
            controller.locked.eq(sampler.locked),
            controller.early.eq(sampler.early),
            controller.frame_done.eq(decoder.done),
            controller.started.eq(decoder.started),
            controller.slots_full.eq(decoder.slots_full),
            controller.stopped.eq(decoder.stopped),
            controller.stop_bit.eq(decoder.stop_bit),
            controller.frame_doubtful.eq(verdict.doubtful),
            controller.break_over.eq(timers.break_over),
            controller.ack_expired.eq(timers.ack_expired),
            controller.no_start_expired.eq(timers.no_start_expired),
            controller.slo_stuck.eq(timers.slo_stuck),
            controller.slo_stuck_live.eq(timers.slo_stuck_live),
            controller.delay_over.eq(timers.delay_over),

            timers.slo.eq(sampler.level),
            timers.ma_busy.eq(ma_clock.busy),
            timers.clear.eq(controller.timer_clear),
            timers.in_clock.eq(controller.in_clock),
            timers.restart.eq(controller.restart_timer),
            timers.break_time.eq(self.cfg_break_time),
            timers.timeout_live.eq(self.cfg_timeout_limit),
            timers.ack_limit.eq(config.ack_limit),
            timers.timeout_limit.eq(config.timeout_limit),
            timers.no_start_limit.eq(config.no_start_limit),
            timers.delay.eq(sampler.delay),
            timers.delay_limit.eq(config.delay_limit),

            ma_clock.run.eq(controller.ma_run),
            ma_clock.half_period.eq(cycle.ma_half_period),
            ma_stop.started.eq(decoder.started),
            ma_stop.start_slot.eq(decoder.start_slot),
            ma_stop.rises.eq(ma_clock.rises),
            ma_stop.clear.eq(controller.receiver_clear),
        ]

        # -- Receiver: sampler -> decoder -> checks -----------------------------------------------
        m.d.comb += [
            sampler.half_period.eq(cycle.ma_half_period),
            sampler.arm.eq(ma_clock.second_rise),
            decoder.sample.eq(sampler.sample),
            decoder.bit.eq(sampler.bit),
            decoder.word_count.eq(config.word_count),
            sol.lc.eq(decoder.lc),
            sol.lc_next.eq(decoder.lc_next),
            sol.load.eq(decoder.lc_load),
            sol.check.eq(verdict.lc_check),
            sol.resync.eq(controller.resync),
        ]
        for w, word in enumerate(words):
            m.d.comb += [decoder.words[w].eq(word), ma_stop.words[w].eq(word)]
        if two:
            m.d.comb += [
                ma_stop.w1_enable.eq(cycle.w1_enable),
                spw_check.cpw_top.eq(decoder.cpw_top),
                spw_check.spw.eq(decoder.data1),
                spw_check.bits.eq(cycle.w1.data_bits),
                spw_check.tolerance.eq(cycle.spw_tolerance),
                verdict.spw_match.eq(spw_check.match),
            ]

        # -- Verdict -> results ---------------------------------------------------------------------
        m.d.comb += [
            verdict.cfg.eq(cycle),
            verdict.report_frame.eq(controller.report_frame),
            verdict.fault.eq(controller.fault),
            verdict.fault_status.eq(controller.fault_status),
            verdict.crc_ok.eq(decoder.crc_ok),
            verdict.lc_repeat_seen.eq(sol.repeat),
            verdict.lc_skip_seen.eq(sol.skip),
            verdict.lc_zero_seen.eq(sol.zero),

            results.report.eq(verdict.report),
            results.report_frame.eq(controller.report_frame),
            results.report_delay.eq(controller.report_delay),
            results.valid.eq(verdict.valid),
        ]
        frame = results.frame
        m.d.comb += [
            frame.status.eq(verdict.status),
            frame.line_delay.eq(sampler.delay),
            frame.cds.eq(decoder.cds),
            frame.lc.eq(decoder.lc),
            frame.lc_repeat.eq(verdict.lc_repeat),
            frame.lc_skip.eq(verdict.lc_skip),
            frame.lc_zero.eq(verdict.lc_zero),
        ]
        for w in range(p.words):
            word = frame[f"word{w}"]
            m.d.comb += [
                word.position.eq(getattr(decoder, f"data{w}")),
                word.ne.eq(decoder.ne[w]),
                word.nw.eq(decoder.nw[w]),
                word.crc_ok.eq(verdict.word_crc_ok[w]),
            ]
        if two:
            m.d.comb += frame.spw_mismatch.eq(verdict.spw_mismatch)
        if p.timestamped:
            m.d.comb += [time_base.first_rise.eq(ma_clock.first_rise),
                         frame.timestamp.eq(time_base.first_rise_time)]

        # -- Counters -------------------------------------------------------------------------------
        if p.counters:
            faults = controller.faults
            events = {
                "crc_word0": verdict.crc_error[0],
                "no_ack": faults.no_ack,
                "no_start": faults.no_start,
                "delay_range": faults.delay_range,
                "slo_stuck_low": faults.slo_stuck_low,
                "lc_repeat": verdict.lc_repeat,
                "lc_skip": verdict.lc_skip,
                "lc_zero": verdict.lc_zero,
                "overrun": scheduler.overrun,
                "aborted": faults.aborted,
                "no_stop": faults.no_stop,
            }
            if two:
                events["crc_word1"] = verdict.crc_error[1]
                events["spw_mismatch"] = controller.report_frame & verdict.spw_mismatch
            m.d.comb += [counters.events[name].eq(events[name]) for name in self.counter_names]
            m.d.comb += counters.clear.eq(self.clear_counters)
            m.d.comb += [getattr(self, f"count_{name}").eq(counters.counts[name])
                         for name in self.counter_names]

        # -- Ports out ------------------------------------------------------------------------------
        m.d.comb += [
            self.ma.eq(ma_clock.ma),
            self.busy.eq(~controller.idle),
            self.config_error.eq(~config.ok),
            self.overrun.eq(scheduler.overrun),
            self.done.eq(results.done),
            self.valid.eq(results.valid_out),
        ]
        m.d.comb += [getattr(self, name).eq(field(results.result, path))
                     for name, path, _ in self._result_fields]
        return m
