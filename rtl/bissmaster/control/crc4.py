"""CRC-4 of BiSS control communication (register access over CDM/CDS).

One :class:`amaranth.lib.crc.Algorithm` holds the parameters: the software model here
(:meth:`~amaranth.lib.crc.Parameters.compute`) and any hardware built later from the same
object agree by construction, as :data:`bissmaster.core.word_crc.ALGORITHMS` does for the data CRCs.

A register access carries two CRC-4s (docs/protocol.md, section 10): one after the 11 bits CTS,
ID[2:0], ADR[6:0] (the start bit S is not covered), and one after each 8-bit data byte, in both
directions. Both are computed MSB first from start value 0 and sent inverted; the functions
below return the 4 bits *as sent*, MSB first in bit 3.
"""

from amaranth.lib import crc

from .. import protocol

__all__ = ["CRC4", "crc4", "crc4_address", "crc4_data"]


#: x^4 + x + 1, start 0, MSB first (not reflected), sent inverted.
CRC4 = crc.Algorithm(crc_width=protocol.CRC4_WIDTH, polynomial=protocol.CRC4_POLY,
                     initial_crc=protocol.CRC_INIT, reflect_input=False,
                     reflect_output=False, xor_output=protocol.CRC4_XOR_OUT)

_BIT_SERIAL = CRC4(data_width=1)

#: CTS = 1: the frame is a register access (CTS = 0, commands, are not covered here).
_CTS_REGISTER = 1


def _bits(value, width):
    return [(value >> (width - 1 - i)) & 1 for i in range(width)]


def _check_uint(name, value, width):
    if not isinstance(value, int) or not 0 <= value < 2**width:
        raise ValueError(f"{name} must be an integer from 0 to {2**width - 1}, not {value!r}")


def crc4(bits):
    """CRC-4 of a bit sequence in transmission order, as sent (inverted).

    Parameters
    ----------
    bits : iterable of int
        0 or 1, first transmitted first.

    Returns
    -------
    int
        4 bits, the first one sent in bit 3.
    """
    bits = list(bits)
    for bit in bits:
        if bit not in (0, 1):
            raise ValueError(f"bits must be 0 or 1, not {bit!r}")
    return _BIT_SERIAL.compute(bits)


def crc4_address(slave_id, address):
    """CRC-4 sent after the address of a register access: over CTS = 1, ID[2:0], ADR[6:0].

    Parameters
    ----------
    slave_id : int
        0..7, the slave's position in the chain (0 for a single encoder).
    address : int
        Register address, 0x00..0x7F.
    """
    _check_uint("slave_id", slave_id, protocol.CONTROL_ID_BITS)
    _check_uint("address", address, protocol.CONTROL_ADDRESS_BITS)
    return crc4([_CTS_REGISTER, *_bits(slave_id, protocol.CONTROL_ID_BITS),
                 *_bits(address, protocol.CONTROL_ADDRESS_BITS)])


def crc4_data(byte):
    """CRC-4 sent after a data byte (written by the master or read from the slave).

    Parameters
    ----------
    byte : int
        0x00..0xFF, sent MSB first.
    """
    _check_uint("byte", byte, protocol.REGISTER_BITS)
    return crc4(_bits(byte, protocol.REGISTER_BITS))
