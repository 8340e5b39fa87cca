"""The command line of the generator (`bissmaster-generate`, `python -m bissmaster.generate`):
help, version, the preset list, and the hook through which bus tops add themselves (--top and
their own options) without changing what existing command lines do."""

import re

import pytest
from amaranth.hdl import Const, Module
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

import bissmaster
from bissmaster import generate
from bissmaster.generate import PRESETS, TOPS, Top, main
from bissmaster.params import Crc, MasterParams
from testkit import REPO


def test_help_names_presets_tops_and_every_core_option(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: bissmaster-generate")
    for word in ("--top", "--list-presets", "--version", "-o FILE", "--name", "--sys-clk-hz",
                 "--max-data-bits", "--word-crcs", "--max-line-delay", "--timer-width",
                 "--half-period-width",
                 "--counter-width", "--counter-ram", "--timestamp-width", "examples:", *PRESETS,
                 *TOPS):
        assert word in text, word


def test_version(capsys):
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.split()[:2] == ["bissmaster-generate", bissmaster.__version__]


def test_list_presets_gives_each_preset_its_options_and_parameters(capsys):
    main(["--list-presets"])
    text = capsys.readouterr().out
    blocks = {b.splitlines()[0]: b for b in text.split("\n\n")[1:] if b.strip()}
    assert set(blocks) == set(PRESETS)
    for name, (summary, options) in PRESETS.items():
        assert summary in blocks[name]
        assert " ".join(options) in blocks[name]
    assert "max_data_bits   = [36]" in blocks["biss-c-lean"]
    assert "counter_width   = 0 (no counters)" in blocks["biss-c-lean"]
    assert "max_data_bits   = [36, 28]" in blocks["safety"]
    assert "max_data_bits   = [64, 32, 24]" in blocks["chain"]


def test_bad_max_data_bits_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--max-data-bits", "36,x", "-o", "/dev/null"])
    assert e.value.code == 2
    assert "--max-data-bits takes 1 to 8 integers" in capsys.readouterr().err


def test_nine_words_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--max-data-bits", ",".join(["8"] * 9), "-o", "/dev/null"])
    assert e.value.code == 2
    assert "max_data_bits must name 1 to 8 words" in capsys.readouterr().err


def test_64_bit_words_0_and_1_have_a_bus_top(tmp_path):
    """The register map holds every word up to 64 data bits (7-bit lengths in cfg_words,
    32-bit result.w0_hi / w1_hi, map version 2): the chain preset (a 64-bit word 0) and a
    two-word build of 64-bit words have bus tops (read end to end: sim/scenarios/bus.py,
    chain_words_of_64_bits, and sim/scenarios/driver_chain.py, driver_chain_words_of_64_bits)."""
    for argv in (["--preset", "chain"], ["--max-data-bits", "64,64"]):
        out = tmp_path / "c.v"
        main(["--top", "axil", "--channels", "1", *argv, "-o", str(out)])
        text = out.read_text()
        assert "module biss_master_axil(" in text, argv


def test_a_chain_of_64_bit_words_has_a_bus_top(tmp_path):
    """Words 2..7 may be 64 bits behind the bus: 7-bit lengths, 32-bit chain.wW_hi."""
    out = tmp_path / "c.v"
    main(["--top", "axil", "--preset", "chain", "--max-data-bits", "55,40,64,64",
          "--word-crcs", "6+16,6+16,6+16,6+16", "--channels", "1", "-o", str(out)])
    text = out.read_text()
    assert "module biss_master_axil(" in text


def test_core_top_is_the_default_and_names_biss_master(tmp_path):
    a, b = tmp_path / "a.v", tmp_path / "b.v"
    main(["--preset", "biss-c-lean", "-o", str(a)])
    main(["--top", "core", "--preset", "biss-c-lean", "-o", str(b)])
    assert a.read_text() == b.read_text()
    assert "module biss_master(" in a.read_text()


def test_counter_ram_gives_a_read_port_instead_of_the_count_ports(tmp_path, capsys):
    out = tmp_path / "c.v"
    main(["--preset", "biss-c", "--counter-ram", "1", "-o", str(out)])
    text = out.read_text()
    assert "input [2:0] count_addr" in text and "output [31:0] count_data" in text
    assert "input count_en" in text and "output count_busy" in text
    assert "count_no_ack" not in text
    assert "counter_width   = 16 in memory (count_addr, count_data)" in text
    with pytest.raises(SystemExit) as e:
        main(["--counter-ram", "1", "--counter-width", "0", "-o", "/dev/null"])
    assert e.value.code == 2
    assert "counter_ram needs counter_width 1..16" in capsys.readouterr().err


def test_chain_memory_gives_a_read_port_instead_of_the_chain_words_ports(tmp_path):
    """Words 2.. of a chain in memory: one read port for them (4-bit address: words 2..7, two
    halves each), no word2_position; words 0 and 1 keep their ports and flags stay ports."""
    out = tmp_path / "c.v"
    main(["--preset", "chain", "--chain-memory", "1", "-o", str(out)])
    text = out.read_text()
    assert "input [3:0] chain_addr" in text and "output [31:0] chain_data" in text
    assert "input chain_en" in text and "word2_position" not in text
    assert "output [63:0] word0_position" in text and "output word2_crc_ok" in text
    assert "chain_memory    = on" in text
    # A build of two words has nothing to put there: the same Verilog as without.
    a, b = tmp_path / "a.v", tmp_path / "b.v"
    main(["--preset", "safety", "--chain-memory", "1", "-o", str(a)])
    main(["--preset", "safety", "-o", str(b)])
    assert a.read_text() == b.read_text()


# -- the hook for bus tops ------------------------------------------------------------------------

class FakeBusTop(wiring.Component):
    """Stands in for a bus top: one output bit per channel."""

    def __init__(self, params, channels=1):
        self.params, self.channels = params, channels
        super().__init__({"alive": Out(channels)})

    def elaborate(self, platform):
        m = Module()
        m.d.comb += self.alive.eq(Const(-1, self.channels))
        return m


CHANNELS = ((("--channels",), dict(type=int, default=None, metavar="N", help="channels")),)


@pytest.fixture
def fake_tops(monkeypatch):
    tops = {"core": TOPS["core"]}           # the core, and stand-ins for the bus tops
    for name in ("fake_a", "fake_b"):       # two tops sharing one option, as axil and wb do
        tops[name] = Top(f"{name}: a stand-in", f"biss_master_{name}", FakeBusTop,
                         options=CHANNELS,
                         describe=lambda channels=1: [f"channels        = {channels}"])
    monkeypatch.setattr(generate, "TOPS", tops)


def test_a_registered_top_gets_its_options_and_header(fake_tops, tmp_path, capsys):
    out = tmp_path / "bus.v"
    main(["--top", "fake_b", "--preset", "biss-c", "--channels", "3", "-o", str(out)])
    text = out.read_text()
    assert "module biss_master_fake_b(" in text and "output [2:0] alive" in text
    assert "//   channels        = 3" in text and "//   max_data_bits   = [36]" in text
    main(["--top", "fake_a", "-o", str(out)])      # left out: the top's own default
    assert "output alive" in out.read_text()
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "(--top fake_a, fake_b)" in capsys.readouterr().out


def test_a_top_option_given_to_another_top_is_refused(fake_tops, capsys):
    with pytest.raises(SystemExit) as e:
        main(["--channels", "2", "-o", "/dev/null"])
    assert e.value.code == 2
    assert "--channels applies to --top fake_a, fake_b, not --top core" in capsys.readouterr().err


def test_core_output_does_not_change_when_tops_are_added(fake_tops, tmp_path):
    out = tmp_path / "core.v"
    main(["--preset", "biss-c-lean", "-o", str(out)])
    lean = MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),), counter_width=0,
                        timestamp_width=0, timer_width=16, register_access=False,
                        custom_crc=False, signed_words=False, ssi=False)
    assert out.read_text() == generate.generate(lean)


def test_readme_table_names_every_preset():
    """The README's preset table lists exactly the generator's presets (it once left two out)."""
    text = (REPO / "README.md").read_text()
    table = text[text.index("| preset | what |"):]
    table = table[:table.index("\n\n")]
    names = re.findall(r"^\| `([a-z0-9-]+)` \|", table, re.M)
    assert sorted(names) == sorted(PRESETS)


def test_family_ice40_reads_the_configuration_back_from_flip_flops(tmp_path):
    """--family ice40 builds as the iCE40 board designs are: the counter memory marked for
    block RAM, and no configuration memory in the bus top's bank (iCE40 has no distributed
    RAM); the default leaves both to the tool and reads the configuration from a memory."""
    any_, ice40 = tmp_path / "any.v", tmp_path / "ice40.v"
    main(["--top", "axil", "--channels", "1", "--preset", "biss-c", "-o", str(any_)])
    main(["--top", "axil", "--channels", "1", "--preset", "biss-c", "--family", "ice40",
          "-o", str(ice40)])
    a, i = any_.read_text(), ice40.read_text()
    assert "ch0_config_memory" in a and "ch0_config_memory" not in i
    assert 'ram_style = "block"' not in a and 'ram_style = "block"' in i
    assert "family          = iCE40 (--family ice40)" in i
