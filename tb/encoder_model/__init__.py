"""Independent pure-Python model of BiSS encoder frames (checks the RTL; shares no logic with it)."""

from .control import (Bp3Eds, ControlFaults, ControlSlave, RegisterFile, SlaveAccess, crc4,
                      crc4_data, crc4_header, eds_checksum)
from .control_master import (ControlMaster, ControlResult, ControlStatus, RegisterAccess,
                             control_frame_cdm, decode_cds, exchange)
from .crc import bits_to_int, crc6_biss, crc16_biss, crc_msb_first, int_to_bits
from .frames import (CRC6, CRC16, CRC_NONE, PRESETS, CustomCrc, EncoderFrameSource, FrameFaults,
                     FrameFormat, SignOfLife, WordFormat, WordValue, bp3, build_frame,
                     parse_frame, word_bits)
from .ssi import (SsiEncoder, SsiFormat, SsiReading, SsiTrain, line_high_at, line_levels,
                  parse_ssi, read_at_rising_edges, ssi_bits)

__all__ = [
    "bits_to_int", "crc6_biss", "crc16_biss", "crc_msb_first", "int_to_bits",
    "CRC6", "CRC16", "CRC_NONE", "PRESETS", "CustomCrc", "EncoderFrameSource", "FrameFaults", "FrameFormat",
    "SignOfLife", "WordFormat", "WordValue", "bp3", "build_frame", "parse_frame", "word_bits",
    "Bp3Eds", "ControlFaults", "ControlSlave", "RegisterFile", "SlaveAccess", "crc4",
    "crc4_data", "crc4_header", "eds_checksum",
    "ControlMaster", "ControlResult", "ControlStatus", "RegisterAccess", "control_frame_cdm",
    "decode_cds", "exchange",
    "SsiEncoder", "SsiFormat", "SsiReading", "SsiTrain", "line_high_at", "line_levels",
    "parse_ssi", "read_at_rising_edges", "ssi_bits",
]
