"""The Linux example program (sw/examples/biss_linux.c; docs/driver.md, "On Linux: the example
program"): built by `make -C sw` into a folder of its own, then run as a user runs it.

No test touches /dev/mem or a real UIO device. The register window is a regular file
(``--file``, or a UIO device whose sysfs folder the test writes and names in BISS_UIO_SYSFS):
the test writes the core's registers into it at the addresses of the SystemRDL source
(sim/shared/regspec.py), runs the program and reads back what it wrote there (the
configuration, trigger, periodic mode, register-access requests). A file answers nothing by
itself: `irq_status.done` stays as the test wrote it, so a frame either "ends" at once (done
set, with the result the test put there) or never (the timeout). Expected values come from the
test side (regspec, master_contract, the encoder model), never from the driver or the RTL.
"""

import os
import re
import signal
import subprocess
import time

import pytest

from encoder_model import frames
from encoder_model.control import BANK_SELECT, PROFILE_ID
from master_contract import CA_STATUS, CRC_CODE, ENCODER_PRESETS, STATUS, SYS_CLK_HZ
from sim.shared import regspec
from testkit import REPO

EXIT_OK, EXIT_ARGS, EXIT_DEVICE, EXIT_NOT_CORE, EXIT_ENCODER, EXIT_INTERRUPTED = \
    0, 2, 3, 4, 5, 130
MA_HZ = 1_000_000                   # the program's default MA rate (docs/driver.md)
#: An upper bound for any run that must not hang (the slowest here waits 0.2 s on purpose).
BOUND_S = 10


@pytest.fixture(scope="module")
def prog(tmp_path_factory):
    """`make -C sw BUILD=...`: the program linked with the strict flags against the static
    library."""
    out = tmp_path_factory.mktemp("linux_example")
    r = subprocess.run(["make", "-C", str(REPO / "sw"), f"BUILD={out}"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "warning" not in r.stderr, r.stderr
    link = [line for line in r.stdout.splitlines() if "-o " + str(out / "biss_linux") in line]
    assert len(link) == 1, r.stdout
    for flag in ("-std=c99", "-pedantic", "-Werror", "-Wconversion", "-Wshadow",
                 str(out / "libbissmaster.a")):
        assert flag in link[0].split(), f"{flag} not in: {link[0]}"
    return out / "biss_linux"


def run(prog, *args, env=None, timeout=BOUND_S):
    t0 = time.monotonic()
    r = subprocess.run([str(prog), *map(str, args)], capture_output=True, text=True,
                       timeout=timeout, env={**os.environ, **(env or {})})
    r.elapsed = time.monotonic() - t0
    return r


def one_line_error(r, code, *words):
    """Exit `code`, exactly one line on stderr naming the program and `words`."""
    assert r.returncode == code, (r.returncode, r.stdout, r.stderr)
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("biss_linux: "), lines[0]
    for w in words:
        assert w in lines[0], f"{w!r} not in {lines[0]!r}"
    return lines[0]


class Window:
    """The register window as bytes: every register at its address from the SystemRDL source,
    written and read by field. A new window holds what the core's default build reads after
    reset (id, version, channel count, caps: their reset values) at byte ``at``."""

    def __init__(self, size=None, at=0, channels=None):
        self.map = regspec.load()
        self.at = at
        self.data = bytearray(at + (self.map.size if size is None else size))
        for path in ("id", "version", "channels"):
            self.put(path, **{f: s.reset for f, s in self.map.reg(path).fields.items()})
        if channels is not None:
            self.put("channels", count=channels)
        for ch in range(self.map.channel_slots):
            if self.address("caps", ch) + 4 <= len(self.data):
                self.put("caps", ch, **{f: s.reset for f, s in
                                        self.map.reg("caps", ch).fields.items()})

    def address(self, path, ch=None, index=0):
        return self.at + self.map.address(path, ch, index)

    def word(self, path, ch=None, index=0):
        a = self.address(path, ch, index)
        return int.from_bytes(self.data[a:a + 4], "little")

    def put(self, path, ch=None, index=0, **fields):
        spec, w = self.map.reg(path, ch), self.word(path, ch, index)
        for name, value in fields.items():
            w = spec.fields[name].put(w, value)
        a = self.address(path, ch, index)
        self.data[a:a + 4] = w.to_bytes(4, "little")

    def get(self, path, ch=None, index=0):
        w = self.word(path, ch, index)
        return {n: f.get(w) for n, f in self.map.reg(path, ch).fields.items()}

    def frame(self, ch=0, status="OK", position=0, word1=0, seq=0, line_delay=0, lc=0,
              timestamp=0):
        """A frame that has ended: its result, and irq_status.done set."""
        self.put("irq_status", ch, done=1)
        self.put("result.status", ch, status=STATUS[status], w0_ne=1, w0_nw=1, w0_crc_ok=1,
                 w1_ne=1, w1_nw=1, w1_crc_ok=1, lc=lc)
        self.put("result.seq", ch, seq=seq, line_delay=line_delay)
        self.put("result.w0_lo", ch, data=position & 0xFFFFFFFF)
        self.put("result.w0_hi", ch, data=position >> 32)
        self.put("result.w1_lo", ch, data=word1 & 0xFFFFFFFF)
        self.put("result.w1_hi", ch, data=word1 >> 32)
        self.put("result.timestamp", ch, time=timestamp)

    def save(self, path):
        path.write_bytes(self.data)
        return path

    def load(self, path):
        self.data = bytearray(path.read_bytes())
        return self


def frame_lines(out):
    return [line for line in out.splitlines() if line.startswith("frame ")]


def half_period(ma_hz=MA_HZ, clk_hz=SYS_CLK_HZ):
    return -(-clk_hz // (2 * ma_hz))


def assert_configured(win, ch, preset):
    """cfg_ma and cfg_words / cfg_checks as the encoder model's format of `preset` says."""
    fmt = frames.PRESETS[preset]
    assert win.get("cfg_ma", ch)["ma_half_period"] == half_period()
    words = win.get("cfg_words", ch)
    for w, word in enumerate(fmt.words):
        assert (words[f"w{w}_data_bits"], words[f"w{w}_crc"], words[f"w{w}_nenw"],
                words[f"w{w}_lc"]) == (word.data_bits, CRC_CODE[word.crc], word.nenw,
                                       word.lc), f"{preset} word {w}"
    assert words["w1_enable"] == (len(fmt.words) == 2)
    assert win.get("cfg_checks", ch)["spw_check"] == fmt.is_safety


# -- Help, presets, arguments ----------------------------------------------------------------
def test_help_prints_usage_and_exits_0(prog):
    r = run(prog, "--help")
    assert (r.returncode, r.stderr) == (EXIT_OK, "")
    assert r.stdout.startswith("usage: biss_linux")
    for opt in ("--uio", "--mem", "--file", "--channel", "--preset", "--list-presets",
                "--clock-hz", "--ma-hz", "--count", "--period-us", "--periodic",
                "--timeout-ms", "--identify", "--slave", "--eds-offset", "--trace", "--help"):
        assert opt in r.stdout, opt
    assert "Exit codes: 0" in r.stdout


def test_list_presets_is_the_drivers_table(prog):
    """One line per preset of the driver: every named encoder of the test side, its words'
    data bits and CRCs as the encoder model's formats."""
    r = run(prog, "--list-presets")
    assert (r.returncode, r.stderr) == (EXIT_OK, "")
    lines = {line.split()[0]: line for line in r.stdout.splitlines()}
    assert sorted(lines) == sorted(ENCODER_PRESETS)
    crc = {"crc6": "CRC-6", "crc16": "CRC-16"}
    for name, line in lines.items():
        fmt = frames.PRESETS[name]
        assert re.findall(r"(\d+) bits (CRC-\d+)( nE nW)?( LC)?", line) == [
            (str(w.data_bits), crc[w.crc], " nE nW" if w.nenw else "", " LC" if w.lc else "")
            for w in fmt.words], line
        assert ("SPW check" in line) == fmt.is_safety, line


@pytest.mark.parametrize("args,words", [
    ((), ["no register window"]),
    (("--preset", "resolute_c_26"), ["no register window"]),
    (("--FILE", "--preset", "resolute_c_26", "--bogus"), ["unknown option", "--bogus"]),
    (("--FILE", "--preset", "resolute_c_26", "stray"), ["unexpected argument", "stray"]),
    (("--FILE",), ["--preset"]),
    (("--FILE", "--preset"), ["--preset needs a value"]),
    (("--FILE", "--preset", "resolute_c_25"), ["no preset", "resolute_c_25"]),
    (("--FILE", "--preset", "resolute_c_26,evolute_32"), ["2 names for 1 channels"]),
    (("--FILE", "--preset", "resolute_c_26", "--channel", "8"), ["--channel", "0..7"]),
    (("--FILE", "--preset", "resolute_c_26", "--channel", "0,1,0"), ["given twice"]),
    (("--FILE", "--preset", "resolute_c_26", "--count", "ten"), ["--count", "not a number"]),
    (("--FILE", "--preset", "resolute_c_26", "--count", "-1"), ["--count", "not a number"]),
    (("--FILE", "--preset", "resolute_c_26", "--ma-hz", "10000001"), ["--ma-hz", "10 MHz"]),
    (("--FILE", "--preset", "resolute_c_26", "--ma-hz", "79999"), ["--ma-hz", "80 kHz"]),
    (("--FILE", "--preset", "resolute_c_26", "--clock-hz", "19999999", "--ma-hz",
      "10000000"), ["BISS_ERR_MA_HALF_PERIOD"]),
    (("--FILE", "--identify", "--slave", "8"), ["--slave", "0..7"]),
    (("--FILE", "--identify", "--eds-offset", "2"), ["--eds-offset"]),
    (("--mem", "0x43C00002", "--preset", "resolute_c_26"), ["not 4-byte aligned"]),
    (("--mem", "0xG0", "--preset", "resolute_c_26"), ["--mem", "not a number"]),
    (("--uio", "/dev/uio0", "--mem", "0x43C00000", "--preset", "resolute_c_26"),
     ["one register window"]),
])
def test_bad_arguments_exit_2_before_any_device(prog, tmp_path, args, words):
    """Exit 2, one line on stderr, nothing on stdout; the window is a file that does not
    exist, so an argument checked after opening it would exit 3 instead."""
    missing = tmp_path / "no_such_window"
    args = [a for arg in args for a in (("--file", missing) if arg == "--FILE" else (arg,))]
    r = run(prog, *args)
    one_line_error(r, EXIT_ARGS, *words)
    assert r.stdout == ""


# -- The device: cannot open or map (3), not this core (4) ------------------------------------
def test_missing_or_unusable_device_exits_3(prog, tmp_path):
    short = tmp_path / "short"
    short.write_bytes(bytes(2))
    for args, words in [
        (("--uio", tmp_path / "uio99"), ["cannot open", "uio99", "No such file"]),
        (("--uio", "uio99"), ["cannot open /dev/uio99"]),         # a bare name is in /dev
        (("--file", tmp_path / "nothing"), ["cannot open", "No such file"]),
        (("--file", tmp_path), ["not a regular file"]),
        (("--file", short), ["too short"]),
        (("--file", Window(size=0x1000).save(tmp_path / "w"), "--mem", "0x1240"),
         ["too short", "0x1240"]),
    ]:
        r = run(prog, *args, "--preset", "resolute_c_26")
        one_line_error(r, EXIT_DEVICE, *words)
        assert r.stdout == ""


def test_uio_map_size_comes_from_sysfs(prog, tmp_path):
    """--uio DEV maps map 0 with the size sysfs gives (BISS_UIO_SYSFS stands in for
    /sys/class/uio): the whole map reads frames; a map too small for the channel asked for, and
    a device without a size in sysfs, exit 3."""
    sysfs = tmp_path / "sys"
    (sysfs / "uio3" / "maps" / "map0").mkdir(parents=True)
    size = sysfs / "uio3" / "maps" / "map0" / "size"
    dev = tmp_path / "uio3"
    win = Window(size=0x2000, channels=8)
    win.frame(7, position=0x1234567, seq=3, line_delay=40)
    win.save(dev)
    size.write_text("0x00002000\n")
    r = run(prog, "--uio", dev, "--channel", 7, "--preset", "resolute_c_26", "--count", 1,
            env={"BISS_UIO_SYSFS": str(sysfs)})
    assert r.returncode == EXIT_OK, r.stderr
    assert f"{dev} (map 0, 0x2000 bytes): BiSS master, register map 2.0, 8 channels" in r.stdout
    assert frame_lines(r.stdout) == [
        "frame 1 ch 7 status OK position 19088743 (0x1234567) nE 1 nW 1 crc ok "
        "line_delay 40 (400 ns) seq 3 timestamp 0"]
    assert_configured(Window().load(dev), 7, "resolute_c_26")

    size.write_text("0x1000\n")         # channel 7 is at 0x1000..0x11FF
    r = run(prog, "--uio", dev, "--channel", 7, "--preset", "resolute_c_26",
            env={"BISS_UIO_SYSFS": str(sysfs)})
    one_line_error(r, EXIT_DEVICE, "channel 7 needs a window of 0x1200 bytes")
    size.unlink()
    r = run(prog, "--uio", dev, "--preset", "resolute_c_26", env={"BISS_UIO_SYSFS": str(sysfs)})
    one_line_error(r, EXIT_DEVICE, "cannot read the size", str(size))


@pytest.mark.parametrize("change,words", [
    ({"size": 0x2000, "zero": True}, ["id reads 0x00000000", "not 0x42695353"]),
    ({"id": int.from_bytes(b"BiSs", "big")}, ["id reads 0x42695373"]),
    ({"major": 1}, ["register map version 1.0", "major version 2"]),
    ({"channels": 0}, ["reports 0 channels"]),
    ({"channels": 9}, ["reports 9 channels"]),
])
def test_window_that_is_not_this_core_exits_4_untouched(prog, tmp_path, change, words):
    """id ("BiSS"), the map's major version and the channel count, from the SystemRDL source,
    checked before anything is written: the file is unchanged afterwards."""
    win = Window()
    if change.get("zero"):
        win.data = bytearray(change["size"])
    if "id" in change:
        win.put("id", id=change["id"])
    if "major" in change:
        win.put("version", major=change["major"])
    if "channels" in change:
        win.put("channels", count=change["channels"])
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--preset", "resolute_c_26")
    one_line_error(r, EXIT_NOT_CORE, *words)
    assert path.read_bytes() == win.data, "the program wrote into a window that is not the core"


def test_a_window_smaller_than_the_channel_exits_3(prog, tmp_path):
    """Channel 0 needs 0x400 bytes of window, channel 1 0x600."""
    path = Window(size=0x400).save(tmp_path / "w")
    r = run(prog, "--file", path, "--channel", 1, "--preset", "resolute_c_26")
    one_line_error(r, EXIT_DEVICE, "channel 1 needs a window of 0x600 bytes")


@pytest.mark.parametrize("setup,args,words", [
    ({"channels": 1}, ("--channel", 1, "--preset", "resolute_c_26"),
     ["--channel 1", "1 channel (0..0)"]),
    ({"data_bits_w0": 18}, ("--preset", "resolute_c_26"),
     ["resolute_c_26 does not fit", "BISS_ERR_DATA_BITS", "up to 18 bits"]),
    ({"data_bits_w1": 0}, ("--preset", "resolute_fs_rsh"), ["BISS_ERR_WORD1"]),
    ({"register_access": 0}, ("--identify",), ["no register-access engine"]),
    ({}, ("--preset", "resolute_c_26", "--periodic", "--period-us", 167773),
     ["16777300 clocks", "24-bit request period"]),
])
def test_what_this_build_cannot_do_exits_2(prog, tmp_path, setup, args, words):
    """Arguments that the build in the window cannot do (its channel count and caps) are
    argument errors, told with what the build has."""
    win = Window()
    if "channels" in setup:
        win.put("channels", count=setup.pop("channels"))
    if setup:
        win.put("caps", 0, **setup)
    r = run(prog, "--file", win.save(tmp_path / "w"), *args)
    one_line_error(r, EXIT_ARGS, *words)


# -- Frames ------------------------------------------------------------------------------------
@pytest.mark.parametrize("preset,position,word1", [
    ("resolute_c_36", 0x9_2345_6789, 0),            # a position above 32 bits: w0_hi
    ("resolute_fs_rsh", 0xA_BCDE_F012, 0x0765_4321),
])
def test_frames_read_at_the_rate_then_counters(prog, tmp_path, preset, position, word1):
    """Trigger mode: the configuration of the preset written, the channel trigger-enabled and
    the global trigger written; each frame printed with its position (two registers), word 1
    and LC for BiSS Safety, line delay in clocks and ns, seq, timestamp; the counters at the
    end; three frames 50 ms apart take at least 100 ms."""
    win = Window()
    win.frame(0, position=position, word1=word1, seq=17, line_delay=23, lc=0x2A,
              timestamp=123456)
    win.put("count_ack", 0, no_ack=5, no_start=1)
    win.put("count_cycle", 0, overrun=3)
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--preset", preset, "--count", 3, "--period-us", 50_000)
    assert (r.returncode, r.stderr) == (EXIT_OK, ""), r.stderr
    assert 0.1 <= r.elapsed < BOUND_S
    want = f"status OK position {position} ({position:#x}) nE 1 nW 1 crc ok"
    if len(frames.PRESETS[preset].words) == 2:
        want += f" word1 {word1} ({word1:#x}) nE 1 nW 1 crc ok lc 42"
    want += " line_delay 23 (230 ns) seq 17 timestamp 123456"
    assert frame_lines(r.stdout) == [f"frame {i} ch 0 {want}" for i in (1, 2, 3)]
    counters = [line for line in r.stdout.splitlines() if line.startswith("ch 0 counters:")]
    assert len(counters) == 1 and " no_ack 5 no_start 1 " in counters[0] \
        and " overrun 3 " in counters[0], r.stdout
    after = Window().load(path)
    assert_configured(after, 0, preset)
    assert after.get("trigger")["start"] == 1
    assert (after.get("ctrl", 0)["trigger_enable"], after.get("ctrl", 0)["periodic"]) == (1, 0)


def test_two_channels_two_presets(prog, tmp_path):
    """--channel 0,1 with a preset each: one trigger per frame, the channels' lines in order,
    each channel configured from its own preset."""
    win = Window()
    win.frame(0, position=1000, seq=1)
    win.frame(1, position=2000, seq=2)
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--channel", "0,1", "--preset", "resolute_c_26,resolute_fs_lmm",
            "--count", 2, "--period-us", 0)
    assert r.returncode == EXIT_OK, r.stderr
    assert [" ".join(line.split()[:8]) for line in frame_lines(r.stdout)] == [
        f"frame {f} ch {ch} status OK position {pos}"
        for f in (1, 2) for ch, pos in ((0, 1000), (1, 2000))]
    after = Window().load(path)
    assert_configured(after, 0, "resolute_c_26")
    assert_configured(after, 1, "resolute_fs_lmm")


@pytest.mark.parametrize("status,shown", [("NO_ACK", ""),
                                          ("DELAY_RANGE", " line_delay 23 (230 ns)")])
def test_frames_not_ok_exit_5(prog, tmp_path, status, shown):
    """Every frame ends without a decoded frame: each printed with its status and seq (and the
    line delay that DELAY_RANGE measured), no position or timestamp (the frame fields are the
    last decoded frame's); then exit 5 with the count on stderr."""
    win = Window()
    win.frame(0, status=status, position=77, seq=9, line_delay=23, timestamp=5)
    r = run(prog, "--file", win.save(tmp_path / "w"), "--preset", "resolute_c_26",
            "--count", 3, "--period-us", 0)
    one_line_error(r, EXIT_ENCODER, "3 of 3 frames not OK")
    assert frame_lines(r.stdout) == [f"frame {i} ch 0 status {status}{shown} seq 9"
                                     for i in (1, 2, 3)]


@pytest.mark.parametrize("mode", [(), ("--periodic", "--period-us", 1000)])
def test_nothing_answers_times_out_with_exit_5(prog, tmp_path, mode):
    """irq_status.done never sets: exit 5 after the timeout (not before, not much after), one
    line; in periodic mode the periodic requests are stopped on the way out."""
    path = Window().save(tmp_path / "w")
    r = run(prog, "--file", path, "--preset", "resolute_c_26", "--timeout-ms", 300,
            "--trace", *mode)
    assert r.returncode == EXIT_ENCODER, r.stderr
    errors = [line for line in r.stderr.splitlines() if not line.startswith("trace: ")]
    assert errors == [f"biss_linux: ch 0: frame 1: no frame ended within "
                      f"{300 + (1 if mode else 0)} ms (irq_status.done never set: is the core "
                      "clocked and out of reset?)"]
    assert 0.3 <= r.elapsed < 0.8, r.elapsed
    ctrl = Window().map.address("ctrl", 0)
    periodic = Window().map.reg("ctrl", 0).fields["periodic"]
    writes = [int(line.split("<- ")[1], 16) for line in r.stderr.splitlines()
              if line.startswith(f"trace: write {ctrl:#06x} <- ")]
    assert [periodic.get(w) for w in writes][-2:] == ([1, 0] if mode else [0, 0])
    assert Window().load(path).get("ctrl", 0)["periodic"] == 0


def test_periodic_mode_sets_the_period_and_stops(prog, tmp_path):
    """--periodic: cfg_period = the period in clocks, ctrl.periodic set while reading and
    cleared at the end; no software trigger."""
    win = Window()
    win.frame(0, position=5)
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--preset", "resolute_c_26", "--periodic", "--period-us", 100,
            "--count", 2, "--trace")
    assert r.returncode == EXIT_OK, r.stderr
    assert len(frame_lines(r.stdout)) == 2
    after = Window().load(path)
    assert after.get("cfg_period", 0)["request_period"] == 100 * SYS_CLK_HZ // 1_000_000
    assert (after.get("ctrl", 0)["periodic"], after.get("ctrl", 0)["trigger_enable"]) == (0, 0)
    assert after.get("trigger")["start"] == 0
    ctrl = win.map.address("ctrl", 0)
    assert any(line.startswith(f"trace: write {ctrl:#06x} <- ") and
               win.map.reg("ctrl", 0).fields["periodic"].get(int(line.split("<- ")[1], 16))
               for line in r.stderr.splitlines())


def test_mem_address_inside_a_file(prog, tmp_path):
    """--file PATH --mem ADDR: the file stands in for /dev/mem, the window starts at byte ADDR
    (not page aligned): the /dev/mem path's page arithmetic."""
    win = Window(at=0x1240, size=0x2000)
    win.frame(0, position=321)
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--mem", "0x1240", "--preset", "resolute_c_18", "--count", 1)
    assert r.returncode == EXIT_OK, r.stderr
    assert f"{path} at 0x1240 (0x1200 bytes): BiSS master" in r.stdout
    assert "position 321 " in frame_lines(r.stdout)[0]
    after = Window(at=0x1240, size=0x2000).load(path)
    assert_configured(after, 0, "resolute_c_18")
    assert after.data[:0x1240] == bytes(0x1240), "a write outside the window"


@pytest.mark.parametrize("mode", ["trigger", "periodic"])
def test_interrupt_stops_cleanly(prog, tmp_path, mode):
    """--count 0 reads until SIGINT: exit 130 with one line, the counters printed. Trigger
    mode: frames every millisecond until then. Periodic mode: waiting for a frame that does not
    come (a 60 s timeout), the signal ends the wait at once and the periodic requests are
    stopped."""
    win = Window()
    if mode == "trigger":
        win.frame(0, position=1)
    path = win.save(tmp_path / "w")
    args = ["--periodic", "--timeout-ms", "60000"] if mode == "periodic" else []
    p = subprocess.Popen([str(prog), "--file", str(path), "--preset", "resolute_c_26",
                          "--count", "0", "--period-us", "1000", *args],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(0.3)
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=BOUND_S)
    assert time.monotonic() - t0 < 2
    assert p.returncode == EXIT_INTERRUPTED, err
    assert err.startswith("biss_linux: interrupted after ") and len(err.splitlines()) == 1
    assert "ch 0 counters:" in out
    assert (len(frame_lines(out)) > 10) if mode == "trigger" else frame_lines(out) == []
    assert Window().load(path).get("ctrl", 0)["periodic"] == 0


# -- BP3 identification --------------------------------------------------------------------------
def test_identify_without_control_side_exits_5(prog, tmp_path):
    """--identify: first the identification frame (the longest the build reads, nE/nW, no CRC:
    docs/control.md), then a read of the profile ID registers; an encoder without a control
    side (ca.state NO_ANSWER) exits 5 naming the error."""
    win = Window()
    win.put("ca.state", 0, status=CA_STATUS["NO_ANSWER"])
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--identify")
    one_line_error(r, EXIT_ENCODER, "BP3 identify (slave 0)", "BISS_ERR_CA_NO_ANSWER")
    after = Window().load(path)
    caps = win.get("caps", 0)
    words = after.get("cfg_words", 0)
    assert (words["w0_data_bits"], words["w0_nenw"], words["w0_crc"], words["w1_enable"],
            words["w1_data_bits"], words["w1_nenw"], words["w1_crc"]) == \
        (caps["data_bits_w0"], 1, CRC_CODE["none"], 1, caps["data_bits_w1"], 1, CRC_CODE["none"])
    assert after.get("ca.request", 0) == {"slave_id": 0, "address": PROFILE_ID, "count": 2,
                                          "write": 0}
    assert after.get("ca.ctrl", 0)["start"] == 1


def test_identify_prints_the_profile_then_reads_the_eds(prog, tmp_path):
    """Registers 0x42 / 0x43 = 0x62, 28 (BP3, VER 1, C 0, 26 position bits) printed; the EDS
    read then selects the bank (a file reads back the same bytes, not the bank written: exit 5,
    BISS_ERR_BANK_SELECT) and writes the previous bank select back."""
    win = Window()
    win.put("ca.state", 0, status=CA_STATUS["OK"], bytes_done=64)
    # Every access reads these bytes: 0x42/0x43 for the identify, 0x40..0x43 for the EDS read.
    win.put("ca.rbuf", 0, 0, byte0=0x62, byte1=28, byte2=0x62, byte3=28)
    path = win.save(tmp_path / "w")
    r = run(prog, "--file", path, "--identify", "--slave", 3, "--eds-offset", 1)
    one_line_error(r, EXIT_ENCODER, "BP3 EDS (slave 3, --eds-offset 1)", "BISS_ERR_BANK_SELECT")
    assert "ch 0: BP3 profile ID: VER 1, C 0 (CRC separate), DL 28: 26 position bits" in r.stdout
    after = Window().load(path)
    # The last access: the bank select (0x40) written back with what it read (0x62).
    assert after.get("ca.request", 0) == {"slave_id": 3, "address": BANK_SELECT, "count": 1,
                                          "write": 1}
    assert after.get("ca.wbuf", 0, 0)["byte0"] == 0x62
