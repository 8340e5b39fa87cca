"""The committed Verilog is what the Amaranth source generates today (users without Python
instantiate it), and bad elaboration parameters are refused with a clear message."""

from pathlib import Path

import pytest

from bissmaster.generate import generate
from bissmaster.params import Crc, MasterParams

COMMITTED = Path(__file__).resolve().parents[2] / "rtl" / "generated" / "biss_master.v"


def test_committed_verilog_is_up_to_date():
    assert COMMITTED.read_text() == generate(), \
        "rtl/generated/biss_master.v is stale: run `make rtl` and commit it"


def test_header_names_generator_and_parameters():
    head = COMMITTED.read_text().splitlines()[:12]
    assert any("amaranth 0.5.10" in line for line in head)
    assert any("max_data_bits   = [55, 40]" in line for line in head)


@pytest.mark.parametrize("kwargs, message", [
    ({"max_data_bits": (64,)}, "max_data_bits"),
    ({"max_data_bits": (36, 28, 20)}, "1 or 2 words"),
    ({"word_crcs": ((Crc.CRC6,),)}, "one entry per word"),
    ({"word_crcs": ((Crc.NONE,), (Crc.CRC16,))}, "Crc.CRC6 or Crc.CRC16"),
    ({"sys_clk_hz": 100}, "sys_clk_hz"),
    ({"max_line_delay": 3}, "max_line_delay"),
    ({"sys_clk_hz": 1_000_000_000, "timer_width": 16}, "cannot hold"),
])
def test_bad_parameters_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        MasterParams(**kwargs)


def test_biss_c_only_configuration_generates():
    text = generate(MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)))
    assert "word1_position" not in text and "cfg_w1_enable" not in text
    assert "input [5:0] cfg_w0_data_bits" in text
