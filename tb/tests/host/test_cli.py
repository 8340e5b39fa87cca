"""The host tool ``bissmaster`` (rtl/bissmaster/host/cli.py): every command against a fake
board (tb/testkit/fake_board.py: MemoryBridge, the UART bridge in software, in front of a model
of the register map whose addresses come from the SystemRDL source), what each prints, what it
writes to the registers, the CSV and the PNG, and the exit code of every kind of failure.

Pure Python, virtual time: a sampling run at 10 Hz takes no wall-clock time.
"""

import csv
import io
import re
import struct
import subprocess
import sys
import tomllib

import pytest

from bissmaster.host import cli
from bissmaster.host.link import MemoryBridge
from encoder_model.control import USER_REGISTERS, Bp3Eds, RegisterFile
from testkit import REPO
from testkit.fake_board import FakeBridge, FakeEncoder, RegisterModel, biss_c_board

#: The exit codes docs/bench.md gives (the test's own copy).
EXIT = {"ok": 0, "bad argument": 2, "port": 3, "no board": 4, "link": 5, "no encoder": 6,
        "encoder errors": 7, "interrupted": 130}
CLOCK_HZ = 100e6


class Tty(io.StringIO):
    def isatty(self):
        return True


def run(argv, transport=None, stdout=None):
    out, err = stdout or io.StringIO(), io.StringIO()
    code = cli.main(argv, transport=transport, stdout=out, stderr=err)
    return code, out.getvalue(), err.getvalue()


def writes(model, path, ch=0):
    return [entry for entry in model.log if entry == ("w", path, ch)]


def ctrl(model, ch=0):
    return model.ctrl(ch)


# -- read -----------------------------------------------------------------------------------

def test_read_triggers_one_cycle_per_sample_and_prints_one_line_each():
    bridge = biss_c_board(bits=26)
    model = bridge.model
    model.encoders[0] = FakeEncoder(positions=lambda n: 0x3FF_FFFF + n)   # wraps at 26 bits
    bridge.now = 100.0                                  # times are counted from the first sample
    code, out, err = run(["read", "--count", "5", "--rate", "20"], bridge)
    assert code == EXIT["ok"], err
    lines = out.splitlines()
    assert lines[0].split()[:8] == ["time_s", "ch", "seq", "status", "position", "nE", "nW", "crc"]
    rows = [line.split() for line in lines[1:]]
    assert len(rows) == 5
    for n, row in enumerate(rows):
        assert float(row[0]) == pytest.approx(n / 20)              # paced at --rate
        assert row[1:4] == ["0", str(n + 1), "OK"]
        assert int(row[4]) == (0x3FF_FFFF + n) & (2**26 - 1)
        assert row[5:8] == ["1", "1", "ok"]
        assert row[8:] == ["37", "370.0"]                           # 37 clocks at 100 MHz
    assert len(writes(model, "trigger", None)) == 5                 # the software trigger
    # Per sample: the trigger and one burst of the result block (result.status first); the
    # end of the cycle seen in result.seq, no interrupt status touched.
    assert [e for e in model.log if e[1] in ("trigger", "result.status")] == \
        [("r", "result.status", 0)] + [("w", "trigger", None), ("r", "result.status", 0)] * 5
    assert not writes(model, "irq_status")
    assert model.encoders[0].cycles == 5
    assert ctrl(model)["trigger_enable"] == 0, "trigger_enable left as it was"
    assert "\x1b[" not in out


def test_read_on_a_terminal_rewrites_its_table_in_place():
    bridge = biss_c_board()
    tty = Tty()
    code, out, _ = run(["read", "--count", "3"], bridge, stdout=tty)
    assert code == EXIT["ok"]
    # Header, one row, a status line: 3 lines, redrawn with the cursor moved up 3 lines.
    assert out.count("\x1b[3A") == 2
    assert out.count("\r\x1b[K") == 9
    assert "sample 3, 0 result(s) not OK" in out


def test_read_two_channels_one_of_them_two_words():
    model = RegisterModel()
    model.configure(0, ma_half_period=50, w0_data_bits=26, w0_nenw=1, w0_crc=1)
    model.configure(1, ma_half_period=20, w0_data_bits=36, w0_nenw=1, w0_crc=1, w1_enable=1,
                    w1_data_bits=28, w1_nenw=1, w1_lc=1, w1_crc=2, spw_check=1)
    model.encoders[1] = FakeEncoder(positions=lambda n: 5 << 30, word1=lambda n: 77 + n)
    code, out, err = run(["read", "-c", "0,1", "--count", "2"], FakeBridge(model))
    assert code == EXIT["ok"], err
    header, *rows = out.splitlines()
    assert "word1" in header and "crc1" in header
    ch1 = [r.split() for r in rows if r.split()[1] == "1"]
    assert [int(r[4]) for r in ch1] == [5 << 30] * 2
    assert [int(r[8]) for r in ch1] == [77, 78]
    assert len(writes(model, "trigger", None)) == 2, "one trigger starts both channels"


def test_read_shows_the_line_delay_in_ns_to_one_decimal():
    """At a clock whose period is not a whole number of ns (the iCEBreaker's 24 MHz), the
    table's delay_ns has one decimal, as the CSV's line_delay_ns (37 clocks: 1541.7 ns)."""
    code, out, err = run(["read", "--count", "1", "--clock-hz", "24e6"], biss_c_board())
    assert code == EXIT["ok"], err
    assert out.splitlines()[1].split()[8:] == ["37", "1541.7"]


def test_read_and_log_show_a_signed_word_as_a_negative_number(tmp_path):
    """cfg_words.wN_signed: the core sign-extends the word to its register's width
    (caps.data_bits_wN, 55 and 40 here); the tool shows the negative number, in the table and
    in the CSV, as the C driver's biss_signed_data; an unsigned word of the same bits stays
    positive."""
    model = RegisterModel()
    model.configure(0, ma_half_period=50, w0_data_bits=26, w0_nenw=1, w0_crc=1, w0_signed=1)
    model.configure(1, ma_half_period=20, w0_data_bits=36, w0_nenw=1, w0_crc=1, w1_enable=1,
                    w1_data_bits=28, w1_nenw=1, w1_lc=1, w1_crc=2, w1_signed=1)
    model.encoders[0] = FakeEncoder(positions=lambda n: (n - 1) % 2**26)     # -1, 0, 1
    model.encoders[1] = FakeEncoder(positions=lambda n: 2**36 - 5, word1=lambda n: 2**28 - 3)
    code, out, err = run(["read", "-c", "0,1", "--count", "3"], FakeBridge(model))
    assert code == EXIT["ok"], err
    rows = [r.split() for r in out.splitlines()[1:]]
    assert [int(r[4]) for r in rows if r[1] == "0"] == [-1, 0, 1]
    ch1 = [r for r in rows if r[1] == "1"]
    assert [(int(r[4]), int(r[8])) for r in ch1] == [(2**36 - 5, -3)] * 3, "w0 unsigned"
    path = tmp_path / "run.csv"
    code, _, err = run(["log", "-c", "0", "--count", "2", "-o", str(path)], FakeBridge(model))
    assert code == EXIT["ok"], err
    assert [r["position"] for r in csv.DictReader(path.open())] == ["2", "3"]
    model.encoders[0] = FakeEncoder(positions=lambda n: 2**26 - 2)
    code, _, err = run(["log", "-c", "0", "--count", "1", "-o", str(path)], FakeBridge(model))
    assert [r["position"] for r in csv.DictReader(path.open())] == ["-2"]


def test_read_shows_64_bit_words_whole():
    """Map version 2: words 0 and 1 of up to 64 bits (caps.data_bits_w0 / w1 64, the whole of
    result.w0_hi / w1_hi): an unsigned word with bit 63 set reads as its full value, a
    signed one as the negative number."""
    model = RegisterModel(caps={"data_bits_w0": 64, "data_bits_w1": 64})
    model.configure(0, ma_half_period=50, w0_data_bits=64, w0_nenw=1, w0_crc=2, w1_enable=1,
                    w1_data_bits=64, w1_nenw=1, w1_crc=2, w1_signed=1)
    model.encoders[0] = FakeEncoder(positions=lambda n: 2**64 - 5 - n,
                                    word1=lambda n: 2**64 - 3)
    code, out, err = run(["read", "-c", "0", "--count", "2"], FakeBridge(model))
    assert code == EXIT["ok"], err
    rows = [r.split() for r in out.splitlines()[1:]]
    assert [(int(r[4]), int(r[8])) for r in rows] == [(2**64 - 5, -3), (2**64 - 6, -3)], rows


@pytest.mark.parametrize("status, code", [("NO_ACK", "no encoder"),
                                          ("SLO_STUCK_LOW", "no encoder"),
                                          ("CRC_ERROR_WORD0", "encoder errors")])
def test_read_reports_a_bad_encoder_with_its_exit_code(status, code):
    bridge = biss_c_board()
    bridge.model.encoders[0] = FakeEncoder(statuses=lambda n: status if n >= 1 else "OK")
    got, out, err = run(["read", "--count", "4"], bridge)
    assert got == EXIT[code]
    assert f"3 of 4 results not OK ({status} 3)" in err
    rows = [r.split() for r in out.splitlines()[1:]]
    assert [r[3] for r in rows] == ["OK"] + [status] * 3
    if status != "CRC_ERROR_WORD0":
        assert rows[1][4:] == ["-"] * 6, "no frame: no position, nE/nW, CRC or delay"
    else:
        assert rows[1][7] == "bad"


def test_a_cycle_that_never_ends():
    bridge = biss_c_board()
    bridge.model.cycle = lambda ch: None                  # no done ever
    code, out, err = run(["read", "--count", "2", "--cycle-timeout", "0.02"], bridge)
    assert code == EXIT["no encoder"] and "TIMEOUT 2" in err
    assert [r.split()[3] for r in out.splitlines()[1:]] == ["TIMEOUT"] * 2


def test_read_free_running():
    bridge = biss_c_board()
    model = bridge.model
    model.configure(0, request_period=1234)
    code, out, err = run(["read", "--count", "3", "--free-run", "50"], bridge)
    assert code == EXIT["ok"], err
    assert not writes(model, "trigger", None)
    # periodic set with cfg_period = 50 us at 100 MHz while sampling, both restored after.
    periods = [w for w in model.log if w == ("w", "cfg_period", 0)]
    assert len(periods) == 2
    assert ctrl(model)["periodic"] == 0 and model.cfg(0)["request_period"] == 1234
    assert [r.split()[3] for r in out.splitlines()[1:]] == ["OK"] * 3


def test_read_free_running_sees_no_new_result():
    bridge = biss_c_board()
    bridge.model.ctrl = lambda ch: {"periodic": 0, "trigger_enable": 0}   # the core never runs
    code, out, err = run(["read", "--count", "2", "--free-run"], bridge)
    assert code == EXIT["no encoder"]
    assert "NO_NEW_RESULT 2" in err


def test_read_refuses_an_unconfigured_or_periodic_channel():
    code, _, err = run(["read", "--count", "1"], biss_c_board(ma_half_period=0))
    assert code == EXIT["bad argument"] and "not configured" in err
    bridge = biss_c_board()
    bridge.model.configure(0, periodic=1)
    code, _, err = run(["read", "--count", "1"], bridge)
    assert code == EXIT["bad argument"] and "--free-run" in err


def _stop_after(n):
    """A request hook: Ctrl-C at the n-th request."""
    state = {"n": 0}

    def hook(data):
        state["n"] += 1
        if state["n"] == n:
            raise KeyboardInterrupt
        return data
    return hook


def test_ctrl_c_stops_and_restores_the_channel():
    bridge = biss_c_board()

    def position(n):
        if n == 2:
            raise KeyboardInterrupt
        return n
    bridge.model.encoders[0] = FakeEncoder(positions=position)
    bridge.requests = _stop_after(1000)                     # (a bound if the cycles stop)
    code, out, err = run(["read"], bridge)                  # --count 0: until Ctrl-C
    assert code == EXIT["interrupted"]
    assert len(out.splitlines()) == 3                       # header and two samples
    assert ctrl(bridge.model)["trigger_enable"] == 0


# -- log and plot ---------------------------------------------------------------------------

def test_log_writes_the_csv(tmp_path):
    bridge = biss_c_board(bits=20)
    bridge.model.encoders[0] = FakeEncoder(
        positions=lambda n: 100 * n, line_delay=41,
        statuses=lambda n: "NO_ACK" if n == 2 else "OK")
    path = tmp_path / "run.csv"
    code, out, err = run(["log", "--count", "4", "--rate", "5", "-o", str(path)], bridge)
    assert code == EXIT["no encoder"] and "NO_ACK 1" in err
    assert "4 results to" in out
    rows = list(csv.DictReader(path.open()))
    assert list(rows[0]) == ["time_s", "channel", "seq", "status", "position", "ne", "nw",
                             "crc_ok", "word1", "w1_ne", "w1_nw", "w1_crc_ok", "lc",
                             "line_delay", "line_delay_ns", "timestamp"]
    assert [float(r["time_s"]) for r in rows] == pytest.approx([0, 0.2, 0.4, 0.6])
    assert [r["status"] for r in rows] == ["OK", "OK", "NO_ACK", "OK"]
    assert [r["position"] for r in rows] == ["0", "100", "", "300"]
    assert [r["seq"] for r in rows] == ["1", "2", "3", "4"]
    ok = rows[1]
    assert (ok["ne"], ok["nw"], ok["crc_ok"], ok["line_delay"], ok["line_delay_ns"]) == \
        ("1", "1", "1", "41", "410.0")
    assert ok["word1"] == "" and rows[2]["line_delay"] == ""
    assert int(rows[3]["timestamp"]) > int(rows[1]["timestamp"])


def test_log_to_stdout():
    code, out, _ = run(["log", "--count", "2"], biss_c_board())
    assert code == EXIT["ok"]
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r["position"] for r in rows] == ["1000", "1007"]


def png_size(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_plot_writes_a_png_with_its_three_axes(tmp_path):
    bridge = biss_c_board()
    bridge.model.encoders[0] = FakeEncoder(statuses=lambda n: "CRC_ERROR_WORD0" if n % 5 == 4
                                           else "OK")
    path = tmp_path / "run.png"
    code, out, err = run(["plot", "--count", "20", "-o", str(path)], bridge)
    assert code == EXIT["encoder errors"] and "CRC_ERROR_WORD0 4" in err
    assert "20 results plotted" in out
    data = path.read_bytes()
    assert png_size(data) == (800, 900) and len(data) > 10_000


def test_plot_figure_content():
    bridge = biss_c_board()
    bridge.model.encoders[0] = FakeEncoder(statuses=lambda n: "NO_ACK" if n == 3 else "OK")
    results = []

    def keep(index, rs):
        results.extend(rs)
    from bissmaster.host.board import Board
    from bissmaster.host.link import Link
    board = Board(Link(bridge))
    board.probe()
    args = cli.build_parser().parse_args(["read", "--count", "10"])
    kept, counts = cli.sample(board, args, keep)
    assert kept == results and counts == {"OK": 9, "NO_ACK": 1}
    fig = cli.make_figure(results, CLOCK_HZ)
    pos, hist, errs = fig.axes
    assert (pos.get_xlabel(), pos.get_ylabel()) == ("time (s)", "position (counts)")
    assert (hist.get_xlabel(), hist.get_ylabel()) == ("line delay (ns)", "samples")
    assert (errs.get_xlabel(), errs.get_ylabel()) == ("status", "samples not OK")
    (line,) = pos.get_lines()
    assert list(line.get_ydata()) == [1000 + 7 * n for n in range(10) if n != 3]
    assert sum(p.get_height() for p in hist.patches) == 9            # frames only
    assert [t.get_text() for t in errs.get_xticklabels()] == ["NO_ACK"]
    assert [p.get_height() for p in errs.patches] == [1]
    assert errs.get_title() == "9 of 10 results OK"


def test_plot_from_a_log(tmp_path):
    csv_path, png = tmp_path / "a.csv", tmp_path / "a.png"
    assert run(["log", "--count", "6", "-o", str(csv_path)], biss_c_board())[0] == 0
    code, out, err = run(["plot", "--input", str(csv_path), "-o", str(png)])   # no board
    assert code == EXIT["ok"], err
    assert png_size(png.read_bytes()) == (800, 900)
    results = cli.read_csv(csv_path)
    assert [r.position for r in results] == [1000 + 7 * n for n in range(6)]
    (tmp_path / "bad.csv").write_text("a,b\n1,2\n")
    code, _, err = run(["plot", "--input", str(tmp_path / "bad.csv"), "-o", str(png)])
    assert code == EXIT["bad argument"] and "not a `bissmaster log` CSV" in err


# -- identify and regs ------------------------------------------------------------------------

DL_POS = 24


def bp3_board(eds=None, **encoder):
    eds = eds or Bp3Eds(DL_POS)
    registers = RegisterFile.bp3(eds, eds_bank=1)
    bridge = biss_c_board(bits=13)
    bridge.model.encoders[0] = FakeEncoder(registers=registers, **encoder)
    return bridge, registers


def test_identify_prints_the_profile_the_eds_and_the_derived_config():
    bridge, registers = bp3_board()
    before = bridge.model.cfg(0)
    code, out, err = run(["identify", "--eds-offset", "0"], bridge)
    assert code == EXIT["ok"], err
    assert "BP3 profile ID: version 1, C = 0 (SEPARATE), DL = 26 (24 position bits" in out
    assert "BP3 bank 0x01" in out
    eds_rows = {line.split()[0]: line.split() for line in out.splitlines()
                if line.startswith("  ") and len(line.split()) >= 4}
    assert eds_rows["BP_ID"][1:3] == ["0x02", "98"]                 # 0x62
    assert eds_rows["CPOLY"][2] == "33"                             # 0x21: CRC-6 0x43
    assert eds_rows["FB1"][2:4] == ["ERROR", "(1)"]
    assert eds_rows["CPOLY"][3:] == ["0x21", "CRC", "polynomial", "0x43"]
    assert eds_rows["TMP_MIN"][2:] == ["233", "0xe9", "K", "(-40.1", "C)"]
    assert "w0_data_bits   24" in out and "w0_crc         1" in out
    assert "not applied" in out
    assert bridge.model.cfg(0) == before, "the channel is left as it was"
    # The accesses ran on the longest frame, no CRC (docs/control.md): every cycle ends OK.
    accesses = bridge.model.encoders[0].accesses
    # 0x40..0x43; the BP3 bank selected and read back; the bank; bank 0 selected again.
    assert [(a["address"], a["count"], a["write"]) for a in accesses] == \
        [(0x40, 4, 0), (0x40, 1, 1), (0x40, 1, 0), (0x00, 64, 0), (0x40, 1, 1)]
    assert registers.bank_select == 0
    assert all(a["cfg"]["w0_data_bits"] == 55 and a["cfg"]["w0_crc"] == 0 and
               a["cfg"]["w1_data_bits"] == 40 for a in accesses)


def test_identify_apply_configures_the_channel_and_restores_the_bank():
    bridge, registers = bp3_board()
    code, out, err = run(["identify", "--apply"], bridge)           # offset 1: bank 2 read
    assert code == EXIT["encoder errors"], "bank 2 holds no BP3 EDS"
    assert "BP3" in err and registers.bank_select == 0, "bank select restored"
    assert bridge.model.cfg(0)["w0_data_bits"] == 13, "not applied after a failure"
    code, out, err = run(["identify", "--apply", "--eds-offset", "0", "--ma-hz", "2e6"], bridge)
    assert code == EXIT["ok"], err
    cfg = bridge.model.cfg(0)
    assert (cfg["w0_data_bits"], cfg["w0_nenw"], cfg["w0_crc"], cfg["w1_enable"],
            cfg["spw_check"], cfg["ma_half_period"]) == (DL_POS, 1, 1, 0, 0, 25)
    assert "applied to channel 0" in out


def test_identify_errors():
    bridge = biss_c_board()
    bridge.model.encoders[0] = FakeEncoder(registers=None)         # no control side
    code, _, err = run(["identify"], bridge)
    assert code == EXIT["no encoder"] and "NO_ANSWER" in err
    bad = Bp3Eds(DL_POS)
    bridge, registers = bp3_board(bad)
    registers.set_bank(1, bytes(63) + b"\x01")                      # a bad CHKSUM
    code, _, err = run(["identify", "--eds-offset", "0"], bridge)
    assert code == EXIT["encoder errors"] and "CHKSUM" in err
    no_engine = RegisterModel(caps={"register_access": 0})
    no_engine.configure(0, ma_half_period=50)
    code, _, err = run(["identify"], FakeBridge(no_engine))
    assert code == EXIT["bad argument"] and "register-access engine" in err


def test_regs_read_and_write_as_the_driver_does():
    bridge, registers = bp3_board()
    model = bridge.model
    user = USER_REGISTERS.start
    model.log.clear()
    code, out, err = run(["regs", "write", hex(user), "0xA5", "0x5A", "7", "0x3c", "255"],
                         bridge)
    assert code == EXIT["ok"], err
    assert bytes(registers.read(user + i) for i in range(5)) == bytes([0xA5, 0x5A, 7, 0x3C, 255])
    # The C driver's sequence (docs/driver.md): buffer, irq_status.access_done cleared,
    # ca.request, ca.ctrl.start, irq_status polled, ca.state.
    seq = [(k, p) for k, p, ch in model.log if p.startswith("ca.") or p == "irq_status"]
    after = seq[seq.index(("w", "ca.wbuf")):]
    assert after[:7] == [("w", "ca.wbuf"), ("w", "ca.wbuf"), ("w", "irq_status"),
                         ("w", "ca.request"), ("w", "ca.ctrl"), ("r", "irq_status"),
                         ("w", "irq_status")]
    assert ("r", "ca.state") in after
    code, out, err = run(["regs", "read", hex(user), "5"], bridge)
    assert code == EXIT["ok"], err
    assert out.strip() == f"{user:#04x}: a5 5a 07 3c ff"
    code, out, _ = run(["regs", "read", "0x40", "20"], bridge)
    lines = out.splitlines()
    assert lines[0].startswith("0x40: 00 01 62 1a") and lines[1].startswith("0x50: ")
    assert len(lines[0].split()) == 17 and len(lines[1].split()) == 5


def test_regs_errors():
    bridge, registers = bp3_board()
    code, _, err = run(["regs", "write", "0x42", "1"], bridge)      # profile ID: read only
    assert code == EXIT["encoder errors"] and "REFUSED" in err
    code, _, err = run(["regs", "read", "0x7F", "2"], bridge)
    assert code == EXIT["bad argument"] and "0x7F" in err
    code, _, err = run(["regs", "read", "0x80"], bridge)
    assert code == EXIT["bad argument"]
    code, _, err = run(["regs", "read", "0x10", "65"], bridge)
    assert code == EXIT["bad argument"]
    bridge.model.encoders[0].access_status = "DATA_FAULT"
    code, _, err = run(["regs", "read", "0x10"], bridge)
    assert code == EXIT["encoder errors"] and "configure the channel" in err
    bridge.model.encoders[0].access_status = "CRC4_ERROR"
    assert run(["regs", "read", "0x10"], bridge)[0] == EXIT["encoder errors"]


def test_regs_on_an_unconfigured_channel():
    bridge, _ = bp3_board()
    bridge.model.configure(0, ma_half_period=0)
    code, _, err = run(["regs", "read", "0x40"], bridge)
    assert code == EXIT["bad argument"] and "not configured" in err
    assert bridge.model.encoders[0].accesses == [], "no access started"


def test_an_output_that_cannot_be_written(tmp_path):
    bridge = biss_c_board()
    for argv in (["plot", "-o", str(tmp_path / "no" / "a.png")],
                 ["log", "-o", str(tmp_path / "no" / "a.csv")]):
        code, _, err = run(argv, bridge)
        assert code == EXIT["bad argument"] and "cannot write" in err, argv
    assert bridge.model.encoders.get(0) is None or bridge.model.encoders[0].cycles == 0


def test_a_register_access_that_never_ends_is_aborted():
    bridge, _ = bp3_board()
    model = bridge.model
    model.access = lambda ch: None                              # the engine never ends
    code, _, err = run(["regs", "read", "0x40", "--timeout", "0.05"], bridge)
    assert code == EXIT["no encoder"] and "did not end within 0.05 s (aborted)" in err
    assert ("w", "ca.ctrl", 0) in model.log[-3:]


# -- counters and config ------------------------------------------------------------------------

def test_counters_by_name_and_clear():
    bridge = biss_c_board()
    model = bridge.model
    model.counters[0] = {"no_ack": 3, "crc_word0": 65535, "no_stop": 2, "ca_no_answer": 9}
    code, out, _ = run(["counters"], bridge)
    assert code == EXIT["ok"]
    values = {line.split()[0]: int(line.split()[1]) for line in out.splitlines()[1:]}
    assert len(values) == 16 + 5        # docs/ports.md, Counters; docs/control.md
    assert (values["no_ack"], values["crc_word0"], values["no_stop"], values["ca_no_answer"],
            values["lc_skip"]) == (3, 65535, 2, 9, 0)
    code, out, _ = run(["counters", "--clear"], bridge)
    assert "counters cleared" in out and model.counters[0] == {}


def test_config_show_preset_and_set():
    bridge = biss_c_board(bits=26, ma_half_period=50)
    model = bridge.model
    code, out, _ = run(["config"], bridge)
    assert code == EXIT["ok"]
    assert "ma_half_period        50  MA 1000000 Hz" in out
    assert "w0_crc                 1  crc6" in out
    code, out, err = run(["config", "--preset", "resolute_fs_lmm", "--ma-hz", "5e6"], bridge)
    assert code == EXIT["ok"], err
    cfg = model.cfg(0)
    assert (cfg["ma_half_period"], cfg["w0_data_bits"], cfg["w1_data_bits"], cfg["w1_lc"],
            cfg["w1_crc"], cfg["w1_enable"], cfg["spw_check"]) == (10, 32, 32, 1, 2, 1, 1)
    code, out, err = run(["config", "--set", "w0_data_bits=30", "--set", "cfg_end_check=1",
                          "--set", "trigger_enable=1"], bridge)
    assert code == EXIT["ok"], err
    assert (model.cfg(0)["w0_data_bits"], model.cfg(0)["end_check"],
            model.cfg(0)["w1_data_bits"]) == (30, 1, 32)
    assert model.ctrl(0)["trigger_enable"] == 1
    code, out, err = run(["config", "--set", "ma_half_period=1"], bridge)
    assert code == EXIT["bad argument"] and "refuses" in err


def test_config_refusals():
    bridge = biss_c_board()
    for argv, text in ((["config", "--set", "w0_data_bits=128"], "7 bit"),
                       (["config", "--set", "nonsense=1"], "no configuration field"),
                       (["config", "--set", "w0_data_bits"], "name=value"),
                       (["config", "--preset", "nope"], "no preset"),
                       (["config", "--preset", "evolute_26", "--ma-hz", "20e6"], "MA rate")):
        code, _, err = run(argv, bridge)
        assert code == EXIT["bad argument"], argv
        assert text in err, (argv, err)
    narrow = RegisterModel(caps={"data_bits_w0": 26, "data_bits_w1": 0})
    code, _, err = run(["config", "--preset", "resolute_c_36"], FakeBridge(narrow))
    assert code == EXIT["bad argument"] and "reads up to 26" in err


def _crc(model, w=0):
    """Word w's CRC as the model's registers hold it: (code, width, poly, start, inverted)."""
    cfg = model.cfg(0)
    return tuple(cfg[f"w{w}_crc{k}"] for k in ("", "_width", "_poly", "_start", "_inverted"))


def test_config_sets_a_words_crc():
    """--wN-crc: a named CRC (custom settings 0), iC-MB4's CRC of a width, or custom:WIDTH,
    POLY[,START[,inverted|plain]] (docs/bench.md); config then shows the custom CRC. The
    expected register values are worked out here: iC-MB4's 8-bit 0x12F is 0x2F without its
    top term; x^16 + x^12 + x^5 + 1 is 0x1021."""
    bridge = biss_c_board(bits=26, ma_half_period=50)
    model = bridge.model
    code, out, err = run(["config", "--w0-crc", "custom:16,0x1021,0xFFFF,plain"], bridge)
    assert code == EXIT["ok"], err
    assert _crc(model) == (3, 16, 0x1021, 0xFFFF, 0)
    assert "custom: 16 bits, polynomial 0x1021, start 0xFFFF, sent plain" in out
    code, out, err = run(["config", "--w0-crc", "icmb4-8"], bridge)
    assert code == EXIT["ok"], err
    assert _crc(model) == (3, 8, 0x2F, 0, 1)
    assert "custom: 8 bits, polynomial 0x2F, start 0x0, sent inverted" in out
    code, out, err = run(["config", "--w0-crc", "custom:5,0x15"], bridge)   # start 0, inverted
    assert (code, _crc(model)) == (EXIT["ok"], (3, 5, 0x15, 0, 1)), err
    code, out, err = run(["config", "--w0-crc", "CRC6"], bridge)
    assert code == EXIT["ok"], err
    assert _crc(model) == (1, 0, 0, 0, 0)
    assert "w0_crc                 1  crc6" in out
    # After --preset, before --set; word 1 too.
    code, out, err = run(["config", "--preset", "resolute_fs_rsh", "--w1-crc", "icmb4-16",
                          "--w0-crc", "icmb4-3", "--set", "w0_crc_start=5"], bridge)
    assert code == EXIT["ok"], err
    assert _crc(model, 0) == (3, 3, 0x3, 5, 1)
    assert _crc(model, 1) == (3, 16, 0x90D9, 0, 1)
    assert model.cfg(0)["w1_data_bits"] == 28


@pytest.mark.parametrize("spec, text", [
    ("custom:17,0x1", "1..16"),
    ("custom:0,0x0", "1..16"),
    ("custom:8,0x107", "does not fit 8 bits"),
    ("custom:8,0x07,0x100", "START 0x100 does not fit"),
    ("custom:8,0x07,0,maybe", "'inverted' nor 'plain'"),
    ("custom:8", "WIDTH,POLY"),
    ("custom:x,1", "not a number"),
    ("icmb4-9", "iC-MB4 names no CRC of 9 bits"),
    ("crc7", "not a CRC"),
])
def test_config_refuses_a_bad_crc(spec, text):
    bridge = biss_c_board()
    before = bridge.model.cfg(0)
    code, _, err = run(["config", "--w0-crc", spec], bridge)
    assert code == EXIT["bad argument"], err
    assert text in err and "usage:" in err, err
    assert bridge.model.cfg(0) == before


def test_config_with_a_custom_crc_the_core_refuses():
    """A custom CRC made invalid by --set (width 0 with code 3: BAD_CONFIG, docs/ports.md)."""
    bridge = biss_c_board()
    code, _, err = run(["config", "--w0-crc", "icmb4-8", "--set", "w0_crc_width=0"], bridge)
    assert code == EXIT["bad argument"] and "refuses" in err


def test_identify_apply_writes_a_custom_crc():
    """An EDS naming x^16 + x^12 + x^5 + 1 (CPOLY 0x8810: the polynomial 0x11021 without x^0,
    shifted down) from 0xFFFF: identify shows it, --apply writes code 3 and the CRC."""
    bridge, _ = bp3_board(Bp3Eds(DL_POS, cpoly=0x8810, cstart=0xFFFF))
    code, out, err = run(["identify", "--apply", "--eds-offset", "0"], bridge)
    assert code == EXIT["ok"], err
    assert "CRC polynomial 0x11021" in out
    assert _crc(bridge.model) == (3, 16, 0x1021, 0xFFFF, 1)
    assert bridge.model.cfg(0)["w0_data_bits"] == DL_POS
    code, out, err = run(["config"], bridge)
    assert "custom: 16 bits, polynomial 0x1021, start 0xFFFF, sent inverted" in out


def test_list_presets_needs_no_board():
    code, out, _ = run(["config", "--list-presets"])
    assert code == EXIT["ok"]
    assert "resolute_fs_rsh  word 0 36 bits nE nW CRC6, word 1 28 bits nE nW LC CRC16" in out


# -- Chain words (words 2..7) -----------------------------------------------------------------

def chain_board(**encoder):
    """Channel 0 of a four-word build (chain words 2 and 3, up to 24 and 16 bits) set up for a
    chain of four slaves: word 0 26 bits, word 1 17 bits, word 2 20 bits two's complement (the
    fake sign-extends it to 24), word 3 12 bits; nE/nW and CRC-6 each. Word 2 of cycle n is
    n - 1 (-1, 0, 1, ...), word 3 0xABC + n."""
    model = RegisterModel(chain_bits={2: 24, 3: 16})
    for ch in (0, 1):
        model.configure(ch, ma_half_period=50, w0_data_bits=26, w0_nenw=1, w0_crc=1)
    model.configure(0, w1_enable=1, w1_data_bits=17, w1_nenw=1, w1_crc=1)
    model.configure_chain(0, 2, enable=1, data_bits=20, nenw=1, crc=1, is_signed=1)
    model.configure_chain(0, 3, enable=1, data_bits=12, nenw=1, crc=1)
    model.encoders[0] = FakeEncoder(positions=lambda n: 1000 + n, word1=lambda n: 50 + n,
                                    chain=lambda w, n: {2: (n - 1) % 2**20, 3: 0xABC + n}[w],
                                    **encoder)
    return FakeBridge(model)


def reads(model, *paths):
    return [e[1] for e in model.log if e[0] == "r" and e[1] in paths]


def test_read_shows_each_chain_word_with_its_verdicts():
    bridge = chain_board()
    model = bridge.model
    code, out, err = run(["read", "--count", "3"], bridge)
    assert code == EXIT["ok"], err
    header, *rows = out.splitlines()
    assert header.split() == ["time_s", "ch", "seq", "status", "position", "nE", "nW", "crc",
                              "word1", "nE1", "nW1", "crc1", "lc", "word2", "nE2", "nW2",
                              "crc2", "word3", "nE3", "nW3", "crc3", "delay", "delay_ns"]
    rows = [r.split() for r in rows]
    assert [r[4] for r in rows] == ["1000", "1001", "1002"]
    assert [r[8] for r in rows] == ["50", "51", "52"]
    assert [r[13:21] for r in rows] == [
        ["-1", "1", "1", "ok", "2748", "1", "1", "ok"],             # 0xABC
        ["0", "1", "1", "ok", "2749", "1", "1", "ok"],
        ["1", "1", "1", "ok", "2750", "1", "1", "ok"]]
    # The read rule (docs/bus.md, Chains): chain.updates, the result block (status first),
    # chain.flags and the words, chain.updates again; once per read when no frame ends.
    one = ["chain.updates", "result.status", "chain.flags", "chain.updates"]
    assert reads(model, *one) == one * 4                            # the first seq, 3 samples
    assert reads(model, "chain.w4_lo") == [], "only the words up to the last enabled one"


def test_a_chain_read_torn_by_new_frames_is_read_again():
    """Frames end during the second sample's reads, three times (at chain.flags, after the
    snapshot): the tool reads the set again, the snapshot too, until chain.updates agrees: the
    row is of one frame (cycle 4: every word of it), not the snapshot of cycle 1 with cycle
    2's chain words."""
    holder = {}

    def statuses(n):
        if n == 1:
            holder["model"].tears[0] = 3
        return "OK"
    bridge = chain_board(statuses=statuses)
    holder["model"] = model = bridge.model
    code, out, err = run(["read", "--count", "3"], bridge)
    assert code == EXIT["ok"], err
    rows = [r.split() for r in out.splitlines()[1:]]
    assert [(r[2], r[4], r[8], r[13], r[17]) for r in rows] == [
        ("1", "1000", "50", "-1", str(0xABC)),
        ("5", "1004", "54", "3", str(0xABC + 4)),                   # after three tries torn
        ("6", "1005", "55", "4", str(0xABC + 5))]
    # The second sample's four tries: chain.updates read 5 times (the second count of a try
    # the next one's first), the snapshot 4 times.
    sample2 = model.log.index(("w", "trigger", None), model.log.index(("w", "trigger", None)) + 1)
    sample3 = model.log.index(("w", "trigger", None), sample2 + 1)
    window = [e[1] for e in model.log[sample2:sample3] if e[0] == "r"]
    assert window.count("chain.updates") == 5 and window.count("result.status") == 4


@pytest.mark.parametrize("tears, code", [(7, "ok"), (8, "bad argument")])
def test_a_chain_read_torn_every_time_is_an_error(tears, code):
    """Eight tries (the C driver's BISS_READ_RETRIES): seven torn ones still end with a read
    of one frame; eight end the run with exit 2, the channel left as it was."""
    holder = {}

    def statuses(n):
        if n == 1:
            holder["model"].tears[0] = tears
        return "OK"
    bridge = chain_board(statuses=statuses)
    holder["model"] = model = bridge.model
    code_, out, err = run(["read", "--count", "2"], bridge)
    assert code_ == EXIT[code], err
    rows = out.splitlines()[1:]
    if code == "ok":
        assert len(rows) == 2 and rows[1].split()[2] == str(2 + tears)
    else:
        assert len(rows) == 1
        assert "chain.updates changed during each of 8 reads" in err
        assert "frames end faster than the tool reads them" in err
        assert ctrl(model)["trigger_enable"] == 0


def test_log_has_chain_columns_only_with_chain_words(tmp_path):
    """Columns per enabled chain word after the usual ones; a CRC error of word 3 is
    CRC_ERROR_WORD1 (word 0 good, a later word bad) with w3_crc_ok 0 (exit 7). A channel
    without chain words on the same build writes the usual columns, unchanged."""
    bridge = chain_board(chain_bad=lambda n: (3,) if n == 1 else ())
    path = tmp_path / "chain.csv"
    code, out, err = run(["log", "--count", "2", "-o", str(path)], bridge)
    assert code == EXIT["encoder errors"] and "CRC_ERROR_WORD1 1" in err
    rows = list(csv.DictReader(path.open()))
    assert list(rows[0]) == list(cli.CSV_COLUMNS) + [
        "word2", "w2_ne", "w2_nw", "w2_crc_ok", "word3", "w3_ne", "w3_nw", "w3_crc_ok"]
    assert [(r["status"], r["word2"], r["w2_crc_ok"], r["word3"], r["w3_crc_ok"]) for r in rows] \
        == [("OK", "-1", "1", str(0xABC), "1"), ("CRC_ERROR_WORD1", "0", "1", str(0xABD), "0")]
    assert rows[1]["w3_ne"] == rows[1]["w3_nw"] == "1"
    code, out, err = run(["log", "--count", "1", "-c", "1"], bridge)
    assert code == EXIT["ok"], err
    assert out.splitlines()[0].split(",") == list(cli.CSV_COLUMNS)
    code, out, err = run(["log", "--count", "1", "-c", "0,1"], bridge)
    by_channel = {r["channel"]: r for r in csv.DictReader(io.StringIO(out))}
    assert by_channel["0"]["word3"] == str(0xABC + 2) and by_channel["1"]["word3"] == ""
    code, _, err = run(["plot", "--input", str(path), "-o", str(tmp_path / "c.png")])
    assert code == EXIT["ok"], err


def test_counters_name_the_chain_words_crc_counts():
    bridge = chain_board()
    bridge.model.counters[0] = {"crc_word2": 4, "crc_word3": 65535, "crc_word0": 1}
    code, out, err = run(["counters"], bridge)
    assert code == EXIT["ok"], err
    values = {line.split()[0]: int(line.split()[1]) for line in out.splitlines()[1:]}
    assert len(values) == 16 + 2 + 5
    assert (values["crc_word0"], values["crc_word2"], values["crc_word3"]) == (1, 4, 65535)
    assert "crc_word4" not in values
    assert reads(bridge.model, "count_chain2") == [], "only the counts of words built"


def test_config_sets_up_and_shows_chain_words():
    bridge = chain_board()
    model = bridge.model
    code, out, err = run(["config"], bridge)
    assert code == EXIT["ok"], err
    assert "caps: 4 word(s), word 0 up to 55 bits, word 1 up to 40, word 2 up to 24, " \
           "word 3 up to 16," in out
    assert "\n  w2_data_bits          20\n" in out and "\n  w2_is_signed           1\n" in out
    assert "\n  w3_crc                 1  crc6\n" in out and "w4_" not in out
    code, out, err = run(["config", "--set", "w2_data_bits=24", "--set", "cfg_w3_gray=1",
                          "--w3-crc", "custom:8,0x07,0xFF,plain", "--set", "w2_is_signed=0"],
                         bridge)
    assert code == EXIT["ok"], err
    assert (model.chain_cfg(0, 2)["data_bits"], model.chain_cfg(0, 2)["is_signed"]) == (24, 0)
    # wW_signed, as words 0 and 1 name it, sets the same field.
    code, _, err = run(["config", "--set", "w2_signed=1"], bridge)
    assert code == EXIT["ok"], err
    assert model.chain_cfg(0, 2)["is_signed"] == 1
    w3 = model.chain_cfg(0, 3)
    assert (w3["gray"], w3["crc"], w3["crc_width"], w3["crc_poly"], w3["crc_start"],
            w3["crc_inverted"], w3["data_bits"]) == (1, 3, 8, 0x07, 0xFF, 0, 12)
    assert "w3_crc                 3  custom: 8 bits, polynomial 0x7, start 0xFF, sent plain" in out
    # A preset is one encoder: the chain words off; then added back by --set after it.
    code, out, err = run(["config", "--preset", "resolute_c_26"], bridge)
    assert code == EXIT["ok"], err
    assert model.chain_enabled(0) == [] and model.chain_cfg(0, 3)["crc"] == 0
    code, out, err = run(["config", "--preset", "resolute_fs_rsh", "--set", "w2_enable=1",
                          "--set", "w2_data_bits=16", "--set", "w2_nenw=1", "--w2-crc", "crc6"],
                         bridge)
    assert code == EXIT["ok"], err
    assert model.chain_enabled(0) == [2] and not model.config_error(0)
    code, out, err = run(["read", "--count", "1"], bridge)
    assert code == EXIT["ok"], err
    assert out.splitlines()[0].split()[13:17] == ["word2", "nE2", "nW2", "crc2"]
    assert "word3" not in out


def test_config_refuses_chain_words_the_build_lacks_or_cannot_read():
    bridge = chain_board()
    model = bridge.model
    before = {w: model.chain_cfg(0, w) for w in (2, 3)}
    for argv, text in (
            (["--set", "w4_data_bits=8"], "--set w4_data_bits=8: channel 0 has no word 4: its "
                                          "build decodes words 0..3 (caps.words 4)"),
            (["--w5-crc", "crc6"], "--w5-crc: channel 0 has no word 5"),
            (["--set", "w2_data_bits=25"], "word 2 has 25 bits, channel 0 reads up to 24"),
            (["--set", "w3_data_bits=17"], "word 3 has 17 bits, channel 0 reads up to 16"),
            (["--set", "w0_data_bits=56"], "word 0 has 56 bits, channel 0 reads up to 55"),
            (["--set", "w2_sign=1"], "no configuration field 'w2_sign'"),
            (["--w2-crc", "custom:17,1"], "1..16")):
        code, _, err = run(["config", *argv], bridge)
        assert code == EXIT["bad argument"], (argv, err)
        assert text in err, (argv, err)
    assert {w: model.chain_cfg(0, w) for w in (2, 3)} == before, "nothing written"
    assert not [e for e in model.log if e[0] == "w" and e[1].startswith("cfg_")]
    # A build of two words has no chain word.
    code, _, err = run(["config", "--set", "w2_enable=1"], biss_c_board())
    assert code == EXIT["bad argument"] and "channel 0 has no word 2" in err
    # A gap (word 3 without word 2): the core refuses it, the tool says why.
    code, _, err = run(["config", "--set", "w2_enable=0"], bridge)
    assert code == EXIT["bad argument"]
    assert "refuses" in err and "word 3 is enabled without word 2" in err


def test_identify_leaves_the_chain_words_out_while_it_reads():
    bridge = chain_board(registers=RegisterFile.bp3(Bp3Eds(DL_POS), eds_bank=1))
    code, out, err = run(["identify", "--eds-offset", "0"], bridge)
    assert code == EXIT["ok"], err
    accesses = bridge.model.encoders[0].accesses
    assert accesses and all(a["chain"] == [] for a in accesses)
    assert bridge.model.chain_enabled(0) == [2, 3], "put back afterwards"


# -- Failures and their exit codes ----------------------------------------------------------

def test_no_port_and_the_port_from_the_environment(monkeypatch):
    monkeypatch.delenv("BISSMASTER_PORT", raising=False)
    code, _, err = run(["read"])
    assert code == EXIT["bad argument"] and "no port given" in err
    monkeypatch.setenv("BISSMASTER_PORT", "/dev/ttyNONEXISTENT7")
    code, _, err = run(["read"])
    assert code == EXIT["port"] and "/dev/ttyNONEXISTENT7" in err


def test_a_missing_port():
    code, _, err = run(["counters", "--port", "/dev/ttyNONEXISTENT7"])
    assert code == EXIT["port"]
    assert err.startswith("bissmaster: cannot open /dev/ttyNONEXISTENT7")


def test_without_pyserial_the_port_error_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "serial", None)
    code, _, err = run(["counters", "--port", "/dev/ttyUSB0"])
    assert code == EXIT["port"] and "pip install pyserial" in err


def test_a_board_that_does_not_answer():
    silent = MemoryBridge(requests=lambda data: b"")            # nothing reaches a bridge
    code, _, err = run(["counters"], silent)
    assert code == EXIT["no board"] and "the board does not answer" in err


def test_something_else_on_the_port():
    code, _, err = run(["counters"], MemoryBridge({0: 0x12345678}))
    assert code == EXIT["no board"] and "not a BiSS master" in err
    code, _, err = run(["counters"], MemoryBridge({0: 0x42695353, 4: 1 << 16 | 1, 8: 2}))
    assert code == EXIT["no board"] and "version 1.1" in err


def test_a_garbled_link():
    flip = lambda data: data[:-1] + bytes([data[-1] ^ 0x10])   # every answer's CRC damaged
    code, _, err = run(["counters"], FakeBridge(responses=flip))
    assert code == EXIT["link"] and "garbled link" in err
    # Answers good at first, damaged later (a cable pulled mid-run).
    state = {"n": 0}

    def later(data):
        state["n"] += 1
        return data if state["n"] < 40 else flip(data)
    bridge = biss_c_board()
    bridge.responses = later
    code, out, err = run(["read", "--count", "50"], bridge)
    assert code == EXIT["link"] and "no good answer in 4 attempts" in err
    assert len(out.splitlines()) >= 2, "the samples before the fault were shown"


@pytest.mark.parametrize("argv, text", [
    (["read", "--rate", "0"], "must be above 0"),
    (["read", "--count", "-1"], "must be 0 or more"),
    (["read", "-c", "9"], "channels must be distinct, 0..7"),
    (["read", "-c", "0,0"], "distinct"),
    (["regs", "write", "0x10", "256"], "VALUE must be"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_arguments(argv, text):
    code, _, err = run(argv, biss_c_board())
    assert code == EXIT["bad argument"]
    assert text in err


def test_a_channel_the_build_lacks():
    code, _, err = run(["read", "-c", "2"], biss_c_board())
    assert code == EXIT["bad argument"] and "channels 0..1" in err
    code, _, err = run(["counters", "-c", "0,1"], biss_c_board())
    assert code == EXIT["ok"]
    code, _, err = run(["regs", "read", "0", "-c", "0,1"], biss_c_board())
    assert code == EXIT["bad argument"] and "one channel" in err


def test_help_lists_the_exit_codes():
    code, text, _ = run(["--help"])
    assert code == 0
    for name in ("read", "identify", "regs", "counters", "config", "plot", "log"):
        assert name in text
    for code in (2, 3, 4, 5, 6, 7, 130):
        assert f"\n  {code} " in text
    assert cli.EXIT_CODES == EXIT


def test_the_entry_point_and_python_m():
    meta = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert meta["project"]["scripts"]["bissmaster"] == "bissmaster.host.cli:main"
    run_ = subprocess.run([sys.executable, "-m", "bissmaster.host.cli", "counters", "--port",
                           "/dev/ttyNONEXISTENT7"], capture_output=True, text=True, timeout=60)
    assert run_.returncode == EXIT["port"], run_.stderr


def test_the_board_takes_its_clock_from_the_transport():
    """Virtual time (MemoryBridge's ``now`` attribute: sleeping advances it), a simulator's
    (``now()`` and ``sleep``), else the computer's."""
    from bissmaster.host.board import Board
    from bissmaster.host.link import Link
    bridge = biss_c_board()
    board = Board(Link(bridge))
    t0 = board.now()
    board.sleep(2.5)
    assert board.now() - t0 == pytest.approx(2.5) and bridge.now - t0 == pytest.approx(2.5)

    class Sim:
        def __init__(self):
            self.slept = []
            self.t = 7.0

        def write(self, data):
            pass

        def read(self, n, timeout):
            return b""

        def now(self):
            return self.t

        def sleep(self, s):
            self.slept.append(s)
            self.t += s
    sim = Sim()
    board = Board(Link(sim))
    board.sleep(0.25)
    assert sim.slept == [0.25] and board.now() == 7.25
    import time

    class Plain:
        def write(self, data):
            pass

        def read(self, n, timeout):
            return b""
    board = Board(Link(Plain()))
    assert board.sleep is time.sleep and board.now is time.monotonic


def test_docs_bench_md_gives_every_exit_code_command_and_column():
    page = (REPO / "docs" / "bench.md").read_text()
    assert "\n## Host tool: bissmaster\n" in page
    text = page.split("\n## Host tool: bissmaster\n", 1)[1]
    table = text.split("### Exit codes", 1)[1]
    codes = {int(m) for m in re.findall(r"^\| (\d+) \|", table, flags=re.M)}
    assert codes == {0} | set(EXIT.values())
    for command in ("read", "log", "plot", "identify", "regs read", "regs write", "counters",
                    "config", "config --preset", "config --set"):
        assert f"| `{command}" in text, command
    csv_text = text.split("**The CSV of `log`**", 1)[1].split("\n\n", 1)[0]
    for column in cli.CSV_COLUMNS:
        assert f"`{column}`" in csv_text, column
    for column in cli.Table(io.StringIO(), False, CLOCK_HZ, True, (2,)).header().split():
        assert f"`{column}`" in text, column
    chain = text.split("### Chains (words 2..7)", 1)[1].split("\n### ", 1)[0]
    for column in cli.chain_csv_columns((2,)):
        assert f"`{column}`" in chain, column
    for name in ("w2_data_bits",) + tuple(f"`wW_{f}`" for f in (
            "data_bits", "nenw", "lc", "crc", "gray", "is_signed", "enable", "crc_poly",
            "crc_width", "crc_inverted", "crc_start")):
        assert name in chain, name
    assert "8 tries" in chain and "`crc_word2`" in chain
