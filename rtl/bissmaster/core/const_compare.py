"""Compares of a value with a constant, written as logic: no carry chain per compare."""

from amaranth.hdl import C, Value


def above(value, k):
    """``value > k`` for a constant ``k``, as AND-OR logic on ``value``'s bits (the constant 0
    where ``value`` cannot exceed ``k``).

    Why not ``value > k``: Yosys maps every ``$gt`` / ``$le`` to an ``$alu`` and so, on ECP5, to
    a carry chain of its own, a carry cell (two LUT sites) per two bits, even against a
    constant (issue 27: 70 of the SPW check's 94 carry cells at 40 bits). Against a constant
    the compare is a small function of a few bits, which ABC maps to a LUT or two.
    ``value > k`` exactly when, at the highest bit where the two differ, ``value`` has a 1 and
    ``k`` a 0: for each 0 bit ``j`` of ``k``, ``value[j]`` and ``value`` equal to ``k`` above
    ``j``.
    """
    value = Value.cast(value)
    width = len(value)
    if k < 0:
        return C(1, 1)
    if k >= 2**width - 1:
        return C(0, 1)
    terms = []
    for j in range(width):
        if not (k >> j) & 1:
            term = value[j]
            for i in range(j + 1, width):
                term = term & (value[i] if (k >> i) & 1 else ~value[i])
            terms.append(term)
    out = terms[0]
    for term in terms[1:]:
        out = out | term
    return out


def at_most(value, k):
    """``value <= k`` for a constant ``k``: ``~above(value, k)`` (see :func:`above`)."""
    return ~above(value, k)
