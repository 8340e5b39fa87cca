"""BiSS C / BiSS Safety master IP core (Amaranth HDL).

The blocks, one hardware concept each:

=====================  =====================================================================
``MaClock``            MA clock generator (``ma_clock``)
``SloSampler``         line-delay measurement and mid-eye sampling of SLO (``slo_sampler``)
``FrameDecoder``       Ack / Start / CDS / words / stop (``frame_decoder``)
``WordCrc``            CRC-6 / CRC-16 check of one word (``word_crc``)
``SignOfLife``         BiSS Safety LC tracker (``sign_of_life``)
``SpwCheck``           CPW/SPW plausibility (``spw_check``)
``BissMaster``         the top level (``master``)
=====================  =====================================================================

``bissmaster.protocol`` holds the protocol facts and imports nothing, so the encoder model can
use it without pulling in Amaranth.
"""

_EXPORTS = {
    "BissMaster": "master", "MasterParams": "params", "Status": "params", "Crc": "params",
}


def __getattr__(name):
    # Lazy, so that ``import bissmaster.protocol`` does not import Amaranth.
    if name in _EXPORTS:
        import importlib
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
