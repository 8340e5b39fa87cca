"""Board designs around the UART bridge top (docs/bench.md): :data:`BOARDS` by name,
:class:`BoardTop` (the design on a board's Amaranth platform from amaranth-boards),
:class:`BoardLogic` (the same without clock and pins, for simulation)."""

from .designs import BOARDS, Board, BoardTop, Channel
from .logic import BoardLogic

__all__ = ["BOARDS", "Board", "BoardTop", "BoardLogic", "Channel"]
