"""BiSS C / BiSS Safety master IP core (Amaranth HDL).

The package is laid out by concern; each subpackage's ``README.md`` says what it owns, what it
may import and where a new block goes (``tb/tests/project/test_layering.py`` checks the imports):

===============  ===============================================================================
``core``         the data channel: scheduler, controller, timers, MA, SLO sampler, decoder, CRCs,
                 sign of life, CPW/SPW check, verdict, results, counters
``control``      the control channel: register access over CDM/CDS, its CRC-4 (``control.crc4``)
``bus``          the register map (SystemRDL), register bank, AXI4-Lite / Wishbone adapters, the
                 UART bridge, the multi-channel bus top
``host``         software for a CPU or PC, no hardware: BP3 identification and EDS (``host.bp3``),
                 the UART bridge's host side (``host.link``)
===============  ===============================================================================

At the top: ``protocol`` (the protocol facts; imports nothing, so the encoder model's side can
read it without Amaranth), ``params`` (``MasterParams``, the ``Status`` and ``Crc`` enums, the
widths), ``layouts`` (configuration, result, faults, counters as data layouts and the flat port
names made from them), ``master`` (``BissMaster``: connects the data and control channels) and
``generate`` (``bissmaster-generate``). ``bissmaster.bp3`` and ``bissmaster.control_crc`` are
thin re-exports of ``host.bp3`` and ``control.crc4``, kept as the public names.
"""

#: The package's version, the one place it is written: pyproject.toml reads it from here, and
#: biss_master.core's VLNV must match it (tb/tests/project/test_fusesoc.py).
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
