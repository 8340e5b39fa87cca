"""What the unit tests of ``tb/tests/`` share (``README.md`` in ``tb/tests/`` says where things go).

``block_sim``: the Amaranth-simulator bench of one block and its cycle conventions;
``limits_bench``: the whole core against a tiny explicit encoder, every limit to the clock;
``control_slave``: a slave's control side (register access) and that encoder with it;
``cocotb_encoder_checks``: the cocotb encoder model's self-checks (on ``hdl/ma_loopback.v``);
``data/``: the expected port lists of every preset and the BP3 EDS examples.
"""

from pathlib import Path

#: The repository's root and this folder's data, so no test counts ``parents[...]``.
REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
HDL = Path(__file__).resolve().parent / "hdl"
