"""The committed Verilog is what the Amaranth source generates today (users without Python
instantiate it), and bad elaboration parameters are refused with a clear message."""

from pathlib import Path

import pytest

from bissmaster.generate import PRESETS, generate, main
from bissmaster.params import Crc, MasterParams
from testkit import REPO

COMMITTED = REPO / "rtl" / "generated" / "biss_master.v"


def test_committed_verilog_is_up_to_date():
    assert COMMITTED.read_text() == generate(), \
        "rtl/generated/biss_master.v is stale: run `make rtl` and commit it"


def test_header_names_generator_and_parameters():
    head = COMMITTED.read_text().splitlines()[:12]
    assert any("amaranth 0.5.10" in line for line in head)
    assert any("max_data_bits   = [55, 40]" in line for line in head)


@pytest.mark.parametrize("kwargs, message", [
    ({"max_data_bits": (65, 40)}, "max_data_bits"),
    ({"max_data_bits": (0, 40)}, "max_data_bits"),
    ({"max_data_bits": (36,) * 9, "word_crcs": ((Crc.CRC6,),) * 9}, "1 to 8 words"),
    ({"max_data_bits": ()}, "1 to 8 words"),
    ({"word_crcs": ((Crc.CRC6,),)}, "one entry per word"),
    ({"word_crcs": ((Crc.NONE,), (Crc.CRC16,))}, "Crc.CRC6 or Crc.CRC16"),
    ({"sys_clk_hz": 100}, "sys_clk_hz"),
    ({"max_line_delay": 3}, "max_line_delay"),
    ({"sys_clk_hz": 1_000_000_000, "timer_width": 16}, "cannot hold"),
    ({"counter_width": -1}, "counter_width"),
    ({"timestamp_width": 8}, "timestamp_width"),
    ({"half_period_width": 3}, "half_period_width"),
    ({"half_period_width": 17}, "half_period_width"),
    ({"crc_table": True}, "crc_table needs config_hold"),
    ({"crc_table": 1, "config_hold": True}, "crc_table must be a bool"),
])
def test_bad_parameters_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        MasterParams(**kwargs)


def test_a_crc_table_build_reads_its_custom_crcs_from_the_table():
    """docs/ports.md, "CRC table": in a build of two words the custom CRCs' polynomial, start
    value and inversion are not ports but ``crc_table_addr`` / ``crc_table_data`` (33 bits);
    the widths stay ports. A one-word build is not changed by the option."""
    two = MasterParams(config_hold=True, crc_table=True)
    text = generate(two)
    assert "output crc_table_addr" in text and "input [32:0] crc_table_data" in text
    for w in (0, 1):
        assert f"cfg_w{w}_crc_width" in text
        for name in ("poly", "start", "inverted"):
            assert f"cfg_w{w}_crc_{name}" not in text
    one = dict(max_data_bits=(36,), word_crcs=((Crc.CRC6,),), config_hold=True)
    assert (generate(MasterParams(**one, crc_table=True)).split("\n")[12:]
            == generate(MasterParams(**one)).split("\n")[12:])


def test_biss_c_only_configuration_generates():
    text = generate(MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)))
    assert "word1_position" not in text and "cfg_w1_enable" not in text
    assert "input [5:0] cfg_w0_data_bits" in text


def test_a_narrower_half_period_setting_narrows_the_port_and_says_so(tmp_path):
    """``--half-period-width 8`` at 24 MHz: an 8-bit ``cfg_ma_half_period`` (the default build's
    is 16 bits), and the header gives the slowest MA clock: 24 MHz / (2 x 255) = 47.1 kHz."""
    out = tmp_path / "narrow.v"
    main(["--preset", "biss-c-lean", "--sys-clk-hz", "24000000", "--half-period-width", "8",
          "-o", str(out)])
    text = out.read_text()
    assert "input [7:0] cfg_ma_half_period" in text
    assert "half_period_width = 8 (MA down to 47.1 kHz)" in text
    assert "input [15:0] cfg_ma_half_period" in COMMITTED.read_text()


def test_lean_build_has_no_counters_and_no_timestamp(tmp_path):
    out = tmp_path / "lean.v"
    main(["--preset", "biss-c-lean", "-o", str(out)])
    text = out.read_text()
    assert "counter_width   = 0 (no counters)" in text and "timer_width     = 16" in text
    ports = text[text.index("module biss_master("):].split(";")[0]
    assert "count_" not in ports and "clear_counters" not in ports and "timestamp" not in ports
    assert "word0_position" in ports and "cfg_request_period" in ports
    assert "input [15:0] cfg_request_period" in text


def test_preset_options_can_be_overridden(tmp_path):
    out = tmp_path / "x.v"
    main(["--preset", "biss-c-lean", "--counter-width", "8", "-o", str(out)])
    assert "output [7:0] count_no_ack" in out.read_text()
    for name in PRESETS:        # every preset names a valid build
        main(["--preset", name, "-o", str(out)])


def test_bad_generator_option_exits_with_message(capsys):
    with pytest.raises(SystemExit):
        main(["--preset", "biss-c", "--timestamp-width", "8", "-o", "/dev/null"])
    assert "timestamp_width must be 0" in capsys.readouterr().err


def test_time_input_replaces_the_counter(tmp_path, capsys):
    """``--time-input 1``: the timestamp captures the input time_now (a time base shared by
    several cores); refused without a timestamp."""
    out = tmp_path / "x.v"
    main(["--preset", "biss-c", "--time-input", "1", "-o", str(out)])
    text = out.read_text()
    assert "input [31:0] time_now" in text and "output [31:0] timestamp" in text
    main(["--preset", "biss-c", "-o", str(out)])
    assert "time_now" not in out.read_text()
    with pytest.raises(SystemExit):
        main(["--preset", "biss-c-lean", "--time-input", "1", "-o", "/dev/null"])
    assert "time_input needs a timestamp" in capsys.readouterr().err


def test_register_access_only_where_asked(tmp_path):
    """The default build has the register-access engine (ca_* ports and their counters); the
    Renishaw presets (unidirectional encoders) and the lean build leave it out, and
    ``--register-access`` overrides a preset."""
    out = tmp_path / "x.v"

    def ports(*args):
        main([*args, "-o", str(out)])
        text = out.read_text()
        return text[text.index("module biss_master("):].split(";")[0]

    assert "ca_start" in ports() and "count_ca_refused" in ports()
    for preset in ("biss-c", "biss-c-lean", "safety"):
        assert "ca_" not in ports("--preset", preset), preset
    assert "ca_start" in ports("--preset", "biss-c", "--register-access", "1")
    assert "ca_start" not in ports("--register-access", "0")


def test_bad_start_wait_is_refused():
    with pytest.raises(ValueError, match="start_wait_frames"):
        MasterParams(start_wait_frames=0)
