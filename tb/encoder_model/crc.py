"""Bit-serial CRCs of the encoder model.

The RTL computes its CRCs one received bit at a time; this module does the same arithmetic in
plain Python, written from the textbook shift-register definition (non-reflected, MSB first),
so that a test can compare the two without the model sharing any code with the RTL. Only the
protocol *numbers* (polynomials, widths, output inversion) come from the test side's own
:mod:`protocol_facts` (tb/protocol_facts.py, written from docs/protocol.md), never from ``rtl/``.
"""

import protocol_facts as facts

__all__ = ["crc_msb_first", "crc6_biss", "crc16_biss", "int_to_bits", "bits_to_int"]


def _check_bit(bit):
    if bit not in (0, 1):
        raise ValueError(f"bits must be 0 or 1, got {bit!r}")
    return bit


def crc_msb_first(bits, *, width, poly, init=0, xor_out=0):
    """Compute a non-reflected CRC over a bit sequence, first bit = highest order.

    Parameters
    ----------
    bits : iterable of int
        Message bits (0/1) in transmission order.
    width : int
        CRC register width in bits.
    poly : int
        Generator polynomial without its top (``x**width``) term.
    init : int
        Register value before the first bit.
    xor_out : int
        Value XORed into the register at the end (all ones = "sent inverted").

    Returns
    -------
    int
        The CRC as it appears on the line, MSB first.
    """
    if width < 1:
        raise ValueError(f"CRC width must be >= 1, got {width}")
    mask = (1 << width) - 1
    if not (0 <= poly <= mask and 0 <= init <= mask and 0 <= xor_out <= mask):
        raise ValueError(f"poly, init and xor_out must fit in {width} bits")
    reg = init
    for bit in bits:
        feedback = ((reg >> (width - 1)) & 1) ^ _check_bit(bit)
        reg = (reg << 1) & mask
        if feedback:
            reg ^= poly
    return reg ^ xor_out


def crc6_biss(bits):
    """CRC-6 of a CPW / BiSS C / BP3 data word, as sent (inverted)."""
    return crc_msb_first(bits, width=facts.CRC6_WIDTH, poly=facts.CRC6_POLY,
                         init=facts.CRC_INIT, xor_out=facts.CRC6_XOR_OUT)


def crc16_biss(bits):
    """CRC-16 of a BiSS Safety SPW, as sent (inverted)."""
    return crc_msb_first(bits, width=facts.CRC16_WIDTH, poly=facts.CRC16_POLY,
                         init=facts.CRC_INIT, xor_out=facts.CRC16_XOR_OUT)


def int_to_bits(value, n):
    """``value`` as ``n`` bits, MSB first; ValueError if it does not fit."""
    if n < 0 or not 0 <= value < (1 << n):
        raise ValueError(f"{value!r} does not fit in {n} unsigned bits")
    return [(value >> (n - 1 - i)) & 1 for i in range(n)]


def bits_to_int(bits):
    """Inverse of :func:`int_to_bits` (MSB first)."""
    value = 0
    for bit in bits:
        value = (value << 1) | _check_bit(bit)
    return value
