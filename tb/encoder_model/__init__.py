"""Independent pure-Python model of BiSS encoder frames (checks the RTL; shares no logic with it)."""

from .crc import bits_to_int, crc6_biss, crc16_biss, crc_msb_first, int_to_bits
from .frames import (CRC6, CRC16, CRC_NONE, PRESETS, EncoderFrameSource, FrameFaults,
                     FrameFormat, SignOfLife, WordFormat, WordValue, bp3, build_frame,
                     parse_frame, word_bits)

__all__ = [
    "bits_to_int", "crc6_biss", "crc16_biss", "crc_msb_first", "int_to_bits",
    "CRC6", "CRC16", "CRC_NONE", "PRESETS", "EncoderFrameSource", "FrameFaults", "FrameFormat",
    "SignOfLife", "WordFormat", "WordValue", "bp3", "build_frame", "parse_frame", "word_bits",
]
