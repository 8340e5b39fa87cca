"""BiSS C / BiSS Safety master IP core (Amaranth HDL).

The blocks, one hardware concept each (docs/architecture.md draws how they connect):

=======================  ===================================================================
``Configuration``        configuration check, per-cycle latch, defaults (``configuration``)
``RequestScheduler``     single shot, periodic, overrun (``request_scheduler``)
``CycleController``      the request cycle's state machine (``cycle_controller``)
``LimitTimers``          break, Ack, NO_START, SLO-low and delay limits (``limit_timers``)
``MaClock``              MA clock generator (``ma_clock``)
``MaStop``               when MA has clocked out the whole frame (``ma_stop``)
``SloSampler``           SLO synchronizer, line delay, mid-eye sampling (``slo_sampler``)
``FrameDecoder``         Ack / Start / CDS / words / stop (``frame_decoder``)
``WordCrc``              CRC-6 / CRC-16 check of one word (``word_crc``)
``SignOfLife``           BiSS Safety LC tracker (``sign_of_life``)
``SpwCheck``             CPW/SPW plausibility (``spw_check``)
``FrameVerdict``         status priority and ``valid`` (``frame_verdict``)
``ResultRegisters``      the last cycle's result (``results``)
``TimeBase``             the time base behind ``timestamp`` (``time_base``)
``CounterBank``          saturating error counters (``counters``)
``BissMaster``           the top level, which only connects (``master``)
=======================  ===================================================================

Interfaces: ``layouts`` (configuration, result, faults, counters as data layouts, and the flat
port names made from them), ``params`` (``MasterParams``, the ``Status`` and ``Crc`` enums).

Host side, no hardware: ``control_crc`` (the CRC-4 of register access) and ``bp3`` (BP3
identification, EDS decoding, the settings derived from them; docs/control.md).

``bissmaster.protocol`` holds the protocol facts and imports nothing, so the encoder model can
use it without pulling in Amaranth.
"""

#: The package's version, the one place it is written: pyproject.toml reads it from here, and
#: biss_master.core's VLNV must match it (tb/tests/test_fusesoc.py).
__version__ = "0.1.0"

_EXPORTS = {
    "BissMaster": "master", "MasterParams": "params", "Status": "params", "Crc": "params",
}


def __getattr__(name):
    # Lazy, so that ``import bissmaster.protocol`` does not import Amaranth.
    if name in _EXPORTS:
        import importlib
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
