"""Thin re-export, kept so that ``bissmaster.control_crc`` stays the public name: the CRC-4 of
register access lives in :mod:`bissmaster.control.crc4`, beside the control-channel hardware
that is built from the same parameters."""

from .control.crc4 import *  # noqa: F401,F403  (the public names, __all__ below)
from .control.crc4 import __all__  # noqa: F401
