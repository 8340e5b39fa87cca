"""Word ``k``'s settings out of the settings of every word: one multiplexer, by compares."""

import functools
import operator

from amaranth.hdl import Mux, Value, ValueCastable


def select_word(index, values):
    """``values[index]``: an AND-OR of each value gated by ``index == k`` (0 for an index past
    the last value). A value-castable (a layout's or an enum's view) comes back as the same
    kind of view.

    Why not ``Array(values)[index]``: Icarus runs an Array's case block only once one of its
    inputs changes, so an index that has not changed since reset, over settings written long
    before, reads X there (723f240, 1344a83). The compares read the index and the values like
    any other logic; Yosys builds the same multiplexer from either form.
    """
    values = list(values)
    if not values:
        raise ValueError("select_word needs at least one value")
    picked = functools.reduce(operator.or_, (Mux(index == k, Value.cast(v), 0)
                                             for k, v in enumerate(values)))
    if isinstance(values[0], ValueCastable):
        return values[0].shape()(picked[:Value.cast(values[0]).shape().width])
    return picked
