"""``bissmaster``: the host tool for a board with the BiSS master behind its UART bridge.

    bissmaster read --port /dev/ttyUSB1 --rate 20            # positions, live
    bissmaster identify --port /dev/ttyUSB1 --apply          # BP3: profile ID, EDS, configure
    bissmaster regs read 0x40 4 --port /dev/ttyUSB1          # encoder registers
    bissmaster config --preset resolute_c_26 --ma-hz 2e6 --port /dev/ttyUSB1
    bissmaster counters --port /dev/ttyUSB1
    bissmaster log --count 1000 -o run.csv --port /dev/ttyUSB1
    bissmaster plot --count 500 -o run.png --port /dev/ttyUSB1

Every command talks to the register map (docs/registers.md) through :class:`.board.Board` over
:class:`.link.Link`: a serial port (``--port``, pyserial), or any transport a caller passes to
:func:`main` (the software model ``MemoryBridge``, a simulator). docs/bench.md, "Host tool",
describes the commands, their output and the exit codes (:data:`EXIT_CODES`).

Only the standard library is imported with this module: pyserial when a port is opened,
matplotlib by ``plot``, the BP3 decoder (and with it Amaranth, for the settings' names) by
``identify``.
"""

import argparse
import contextlib
import csv
import os
import re
import sys
from dataclasses import fields as dataclass_fields

from . import presets, regmap
from .board import (AccessError, Board, BoardError, CapabilityError, EncoderSilentError,
                    NoBoardError, NotTheCoreError, Result, TornReadError, chain_settings,
                    setting_register, signed_data)
from .link import Link, LinkError, SerialTransport

#: Exit codes, by what went wrong (docs/bench.md, "Exit codes").
EXIT_CODES = {
    "ok": 0,
    "bad argument": 2,          # also what the build cannot do (a channel, register access)
    "port": 3,                  # the port is missing or cannot be opened (or no pyserial)
    "no board": 4,              # nothing answers the PING, or it is not this core
    "link": 5,                  # answers come, but damaged, after every retry
    "no encoder": 6,            # the encoder does not answer (NO_ACK, SLO stuck, NO_ANSWER ...)
    "encoder errors": 7,        # it answers with errors (CRC, sign of life, refused, bad EDS)
    "interrupted": 130,         # Ctrl-C
}

EPILOG = """exit codes:
  0    done; every sample OK
  2    bad argument, or something this build cannot do (a channel or word it lacks,
       a word longer than it reads, no register-access engine, a configuration the
       core refuses); a chain read torn on every try (frames end faster than read)
  3    the port is missing or cannot be opened (or pyserial is not installed)
  4    the board does not answer (PING unanswered), or is not a BiSS master
  5    garbled link: answers damaged after every retry, or refused by the bridge
  6    the encoder does not answer: NO_ACK, NO_START, DELAY_RANGE, SLO_STUCK_LOW,
       NO_STOP, no cycle end in time; a register access with NO_ANSWER or no end
  7    the encoder answers with errors: CRC / sign-of-life / SPW errors, a register
       access CRC4_ERROR, REFUSED, DATA_FAULT or ABORTED, an invalid BP3 EDS
  130  interrupted (Ctrl-C)
environment: BISSMASTER_PORT is the default of --port."""

#: Clock of the committed biss_master_uart (docs/uart_bridge.md): the default of --clock-hz.
DEFAULT_CLOCK_HZ = 100e6


class UsageError(Exception):
    """A bad argument, found after parsing (exit 2)."""


class PortError(Exception):
    """The port cannot be opened (exit 3)."""


class EncoderErrors(Exception):
    """The encoder answered with errors (exit 7)."""


# -- Arguments --------------------------------------------------------------------------------

def _int(text):
    try:
        return int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None


def _ranged(low, high, name):
    def parse(text):
        value = _int(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{name} must be {low:#x}..{high:#x}, "
                                             f"not {text}")
        return value
    return parse


def _positive(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be above 0, not {text}")
    return value


def _count(text):
    value = _int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, not {text}")
    return value


def _channels(text):
    try:
        chans = [int(c, 0) for c in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"channels are numbers, e.g. 0 or 0,1: {text!r}") \
            from None
    if any(not 0 <= c < regmap.MAX_CHANNELS for c in chans) or len(set(chans)) != len(chans):
        raise argparse.ArgumentTypeError(f"channels must be distinct, 0..{regmap.MAX_CHANNELS - 1}: "
                                         f"{text!r}")
    return chans


def _setting(text):
    name, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"--set takes name=value, not {text!r}")
    return name.strip(), _int(value.strip())


def _crc_choice(word):
    """The argparse type of ``--wN-crc``: word ``word``'s CRC fields (presets.crc_settings)."""
    def parse(text):
        try:
            return presets.crc_settings(word, text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
    return parse


#: Every word the map has: 0, 1 and the chain words 2..7 (--wN-crc; a build has caps.words).
WORDS = (0, 1, *regmap.CHAIN_WORDS)


def build_parser():
    common = argparse.ArgumentParser(add_help=False)
    g = common.add_argument_group("board")
    g.add_argument("--port", default=os.environ.get("BISSMASTER_PORT"),
                   help="serial port of the board (/dev/ttyUSB1, COM4); default $BISSMASTER_PORT")
    g.add_argument("--baud", type=_ranged(300, 12_000_000, "--baud"), default=115200,
                   help="the bridge's baud rate (default 115200)")
    g.add_argument("--channel", "-c", type=_channels, default=[0],
                   help="channel(s), e.g. 0 or 0,1 (default 0)")
    g.add_argument("--clock-hz", type=_positive, default=DEFAULT_CLOCK_HZ,
                   help="the core's clock, for MA rates and line delays in ns (default 100e6)")
    g.add_argument("--retries", type=_count, default=3, help="link retries per access")
    g.add_argument("--timeout-bits", type=_ranged(16, 1 << 20, "--timeout-bits"),
                   default=1000, help="the bridge's inter-byte timeout (its --uart-timeout-bits)")
    g.add_argument("--latency", type=float, default=0.05,
                   help="seconds a round trip may take beyond its bytes (USB adapters)")

    sampling = argparse.ArgumentParser(add_help=False)
    s = sampling.add_argument_group("sampling")
    s.add_argument("--rate", type=_positive, default=10.0, help="samples per second (default 10)")
    s.add_argument("--free-run", type=float, metavar="PERIOD_US", nargs="?", const=0.0,
                   help="the core requests cycles itself every PERIOD_US (0 or none: as fast "
                        "as the encoder allows) and each sample reads the newest result; "
                        "default: one software trigger (register trigger) per sample")
    s.add_argument("--cycle-timeout", type=_positive, default=0.1,
                   help="seconds to wait for a triggered cycle's end (default 0.1)")

    parser = argparse.ArgumentParser(
        prog="bissmaster", description="Host tool for a board with the BiSS master behind its "
        "UART bridge: positions, BP3 identification, encoder registers, counters, "
        "configuration, logs and plots (docs/bench.md).",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name, help_, parents=(common,), **kw):
        p = sub.add_parser(name, help=help_, description=help_, parents=list(parents),
                           epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
                           **kw)
        return p

    p = command("read", "positions, status, nE/nW, CRC verdicts and line delay, live",
                (common, sampling))
    p.add_argument("--count", type=_count, default=0, help="samples (default 0: until Ctrl-C)")
    p.set_defaults(func=cmd_read)

    p = command("log", "samples to CSV", (common, sampling))
    p.add_argument("--count", type=_count, default=100, help="samples (default 100)")
    p.add_argument("--output", "-o", default="-", help="CSV file (default: stdout)")
    p.set_defaults(func=cmd_log)

    p = command("plot", "position against time, line-delay histogram, errors: a PNG",
                (common, sampling))
    p.add_argument("--count", type=_count, default=200, help="samples (default 200)")
    p.add_argument("--output", "-o", default="bissmaster.png", help="PNG file")
    p.add_argument("--input", "-i", help="plot a CSV written by `log` instead of sampling")
    p.set_defaults(func=cmd_plot)

    p = command("identify", "BP3 identification: profile ID, EDS, derived configuration")
    p.add_argument("--slave", type=_ranged(0, 7, "--slave"), default=0)
    p.add_argument("--eds-offset", type=_ranged(0, 255, "--eds-offset"), default=1,
                   help="banks from the EDS pointer (register 0x41) to the BP3 bank (default "
                        "1; 0 when the pointer names the BP3 bank)")
    p.add_argument("--apply", action="store_true",
                   help="configure the channel from the EDS (else it is left as it was)")
    p.add_argument("--ma-hz", type=_positive,
                   help="MA rate to use (default: the channel's, 1 MHz if unconfigured)")
    p.add_argument("--timeout", type=_positive, default=5.0,
                   help="seconds per register access")
    p.set_defaults(func=cmd_identify)

    p = command("regs", "read or write encoder registers over the control channel")
    regs = p.add_subparsers(dest="op", required=True, metavar="OP")
    r = regs.add_parser("read", parents=[common], help="read N registers from ADDR",
                        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("address", type=_ranged(0, 0x7F, "ADDR"), metavar="ADDR")
    r.add_argument("n", type=_ranged(1, regmap.MAX_ACCESS_BYTES, "N"), nargs="?", default=1,
                   metavar="N")
    w = regs.add_parser("write", parents=[common], help="write VALUE... from ADDR on",
                        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    w.add_argument("address", type=_ranged(0, 0x7F, "ADDR"), metavar="ADDR")
    w.add_argument("values", type=_ranged(0, 0xFF, "VALUE"), nargs="+", metavar="VALUE")
    for q in (r, w):
        q.add_argument("--slave", type=_ranged(0, 7, "--slave"), default=0)
        q.add_argument("--timeout", type=_positive, default=2.0,
                       help="seconds the access may take")
    p.set_defaults(func=cmd_regs)

    p = command("counters", "the error counters by name")
    p.add_argument("--clear", action="store_true", help="clear them after reading")
    p.set_defaults(func=cmd_counters)

    p = command("config", "show a channel's settings; set them by preset or by name")
    p.add_argument("--preset", help="encoder preset (--list-presets)")
    p.add_argument("--ma-hz", type=_positive, default=1e6,
                   help="MA rate for --preset (at most; default 1e6)")
    p.add_argument("--set", type=_setting, action="append", default=[], metavar="NAME=VALUE",
                   help="a configuration field (cfg_* of docs/registers.md), or periodic / "
                        "trigger_enable of ctrl; repeatable")
    for w in WORDS:
        p.add_argument(f"--w{w}-crc", type=_crc_choice(w), metavar="CRC",
                       help=f"word {w}'s CRC: {presets.CRC_SYNTAX}; after --preset, before "
                            f"--set")
    p.add_argument("--list-presets", action="store_true")
    p.set_defaults(func=cmd_config)
    return parser


# -- Opening the board ------------------------------------------------------------------------

def open_board(args, transport=None):
    """The Board on ``transport``, or on the serial port of ``args``; probed."""
    if transport is None:
        if not args.port:
            raise UsageError("no port given: --port /dev/ttyUSB1 (or set BISSMASTER_PORT)")
        try:
            transport = SerialTransport(args.port, args.baud)
        except ImportError as e:
            raise PortError(str(e)) from None
        except (OSError, ValueError) as e:
            raise PortError(f"cannot open {args.port}: {e}") from None
    link = Link(transport, baud=args.baud, timeout_bits=args.timeout_bits,
                latency=args.latency, retries=args.retries)
    board = Board(link)
    board.probe()
    for ch in args.channel:
        board.check_channel(ch)
    return board


def _one_channel(args):
    if len(args.channel) != 1:
        raise UsageError(f"{args.command} works on one channel, not {len(args.channel)}")
    return args.channel[0]


# -- Sampling (read, log, plot) ---------------------------------------------------------------

def sample(board, args, on_sample, keep=True):
    """Take ``args.count`` samples (0: until Ctrl-C) of ``args.channel`` at ``args.rate``,
    calling ``on_sample(index, results)``. Returns ``(results, counts)``: every result taken
    (with ``keep``; else an empty list, for a run without end) and ``{status: number}``. The
    channels are left as they were (trigger_enable, periodic, cfg_period), also on Ctrl-C."""
    chans = args.channel
    frames, ctrl_before, period_before = {}, {}, {}
    for ch in chans:
        if board.read_fields("state", ch)["config_error"]:
            raise UsageError(f"channel {ch} is not configured (state.config_error 1): e.g. "
                             f"bissmaster config --preset resolute_c_26 --ma-hz 1e6")
        # A signed word (cfg_words.wN_signed, cfg_wW.is_signed): the core sign-extends it to
        # its register's width (caps); shown as the negative number it is (Frame.signed).
        frames[ch] = board.frame(ch)
        ctrl_before[ch] = board.read_fields("ctrl", ch)
        if args.free_run is None and ctrl_before[ch]["periodic"]:
            raise UsageError(f"channel {ch} runs periodic requests (ctrl.periodic 1): read it "
                             f"with --free-run, or stop them: bissmaster config --set periodic=0")
    taken, counts = [], {}
    last_seq = {}
    try:
        for ch in chans:
            last_seq[ch] = board.result(ch, frames[ch]).seq      # (result.status first)
            if args.free_run is None:
                board.update("ctrl", ch, trigger_enable=1)
            else:
                period = round(args.free_run * 1e-6 * args.clock_hz)
                period_before[ch] = board.read_fields("cfg_period", ch)["request_period"]
                try:
                    board.configure(ch, {"request_period": period})
                except ValueError as e:
                    raise UsageError(f"--free-run {args.free_run:g} us: {e}") from None
                board.update("ctrl", ch, periodic=1)
        start = board.now()
        i = 0
        while args.count == 0 or i < args.count:
            wait = start + i / args.rate - board.now()
            if wait > 0:
                board.sleep(wait)
            t = board.now()
            if args.free_run is None:
                results = board.trigger_and_read(chans, args.cycle_timeout, frames, last_seq)
            else:
                results = [board.result(ch, frames[ch]) for ch in chans]
                for r in results:
                    if r.seq == last_seq[r.channel]:
                        r.status = "NO_NEW_RESULT"      # no cycle ended since the last sample
                    last_seq[r.channel] = r.seq
            for r in results:
                r.time_s = t - start
                if r.frame:
                    signed = frames[r.channel].signed
                    r.position = signed_data(r.position, signed[0])
                    if r.word1 is not None:
                        r.word1 = signed_data(r.word1, signed[1])
                    for w, word in r.chain.items():
                        word.data = signed_data(word.data, signed[w])
                counts[r.status] = counts.get(r.status, 0) + 1
            if keep:
                taken += results
            on_sample(i, results)
            i += 1
    finally:
        try:
            for ch in chans:
                before = ctrl_before.get(ch)
                if before is not None:
                    board.update("ctrl", ch, periodic=before["periodic"],
                                 trigger_enable=before["trigger_enable"])
                if ch in period_before:
                    board.configure(ch, {"request_period": period_before[ch]})
        except LinkError:
            pass                # the error that stopped the sampling is the one to report
    return taken, counts


def verdict(counts, err):
    """The exit code of a run from its ``{status: number}``, with one line on ``err`` if not
    every result was OK."""
    total = sum(counts.values())
    bad = {name: n for name, n in counts.items() if name != "OK"}
    if not bad:
        return EXIT_CODES["ok"]
    listed = ", ".join(f"{name} {n}" for name, n in sorted(bad.items()))
    nbad = sum(bad.values())
    if any(Result(0, 0.0, name).encoder_silent for name in bad):
        print(f"bissmaster: {nbad} of {total} results not OK ({listed}): the encoder "
              f"does not answer as it should (power, cable, transceiver, MA rate, "
              f"configuration)", file=err)
        return EXIT_CODES["no encoder"]
    if set(bad) == {"UNCONFIRMED"}:
        print(f"bissmaster: {nbad} of {total} results not OK ({listed}): the first frame(s) "
              f"after a fault, withheld until the line proves clean (cfg_confirm_frames; "
              f"docs/ports.md, \"Confirmation after a fault\")", file=err)
        return EXIT_CODES["encoder errors"]
    print(f"bissmaster: {nbad} of {total} results not OK ({listed}): the encoder "
          f"answers with errors (noise, cable, a wrong frame configuration)", file=err)
    return EXIT_CODES["encoder errors"]


def _ns(clocks, clock_hz):
    return clocks * 1e9 / clock_hz


class Table:
    """The rows of ``read``: one per channel, rewritten in place on a terminal (carriage return,
    ANSI cursor up, erase line), one line per result otherwise."""

    def __init__(self, out, tty, clock_hz, two_words, chain=()):
        self.out, self.tty, self.clock_hz, self.two_words = out, tty, clock_hz, two_words
        self.chain = chain          # the chain words shown: the enabled ones of any channel
        self.lines_drawn = 0
        self.bad = 0

    def header(self):
        cols = f"{'time_s':>9} {'ch':>2} {'seq':>5} {'status':<15} {'position':>17} nE nW crc"
        if self.two_words:
            cols += f" {'word1':>13} nE1 nW1 crc1 {'lc':>2}"
        for w in self.chain:
            # 20 columns: a 64-bit word in decimal, with its sign.
            cols += f" {f'word{w}':>20} nE{w} nW{w} crc{w}"
        return cols + f" {'delay':>5} {'delay_ns':>8}"

    def row(self, r):
        frame = r.frame
        dash = "-"
        text = (f"{r.time_s:9.3f} {r.channel:>2} {r.seq:>5} {r.status:<15} "
                f"{r.position if frame else dash:>17} {r.ne if frame else dash:>2} "
                f"{r.nw if frame else dash:>2} "
                f"{('ok' if r.crc_ok else 'bad') if frame else dash:>3}")
        if self.two_words:
            w1 = frame and r.word1 is not None
            text += (f" {r.word1 if w1 else dash:>13} {r.w1_ne if w1 else dash:>3} "
                     f"{r.w1_nw if w1 else dash:>3} "
                     f"{('ok' if r.w1_crc_ok else 'bad') if w1 else dash:>4} "
                     f"{r.lc if w1 else dash:>2}")
        for w in self.chain:
            c = r.chain.get(w) if frame else None
            text += (f" {c.data if c else dash:>20} {c.ne if c else dash:>3} "
                     f"{c.nw if c else dash:>3} {('ok' if c.crc_ok else 'bad') if c else dash:>4}")
        delay = frame or r.status == "DELAY_RANGE"
        text += (f" {r.line_delay if delay else dash:>5} "
                 f"{f'{_ns(r.line_delay, self.clock_hz):.1f}' if delay else dash:>8}")
        return text

    def show(self, index, results):
        self.bad += sum(r.status != "OK" for r in results)
        if not self.tty:
            if index == 0:
                print(self.header(), file=self.out)
            for r in results:
                print(self.row(r), file=self.out)
            self.out.flush()
            return
        lines = [self.header()] + [self.row(r) for r in results]
        lines.append(f"sample {index + 1}, {self.bad} result(s) not OK; Ctrl-C stops")
        if self.lines_drawn:
            self.out.write(f"\x1b[{self.lines_drawn}A")
        for line in lines:
            self.out.write("\r\x1b[K" + line + "\n")
        self.out.flush()
        self.lines_drawn = len(lines)


def _shown_chain(frames):
    """The chain words any of ``frames`` has enabled, in order: the chain columns shown."""
    return tuple(sorted({w for f in frames.values() for w in f.chain}))


def cmd_read(board, args, out, err):
    frames = {ch: board.frame(ch) for ch in args.channel}
    table = Table(out, _isatty(out), args.clock_hz,
                  any(f.two_words for f in frames.values()), _shown_chain(frames))
    _, counts = sample(board, args, table.show, keep=False)
    return verdict(counts, err)


def _isatty(stream):
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


#: The columns of a `log` CSV, in order.
CSV_COLUMNS = ("time_s", "channel", "seq", "status", "position", "ne", "nw", "crc_ok", "word1",
               "w1_ne", "w1_nw", "w1_crc_ok", "lc", "line_delay", "line_delay_ns", "timestamp")


def chain_csv_columns(chain):
    """The CSV columns of the chain words ``chain``, after :data:`CSV_COLUMNS`: per word
    ``wordW``, ``wW_ne``, ``wW_nw``, ``wW_crc_ok``."""
    return tuple(c for w in chain
                 for c in (f"word{w}", f"w{w}_ne", f"w{w}_nw", f"w{w}_crc_ok"))


def csv_row(r, clock_hz, columns=CSV_COLUMNS):
    """A result as a CSV row (dict of ``columns``: :data:`CSV_COLUMNS` and any
    :func:`chain_csv_columns`); frame fields empty without a frame, word 1's empty in a
    one-word configuration, a chain word's when the channel has it disabled."""
    row = {"time_s": f"{r.time_s:.6f}", "channel": r.channel, "seq": r.seq, "status": r.status,
           "timestamp": r.timestamp}
    if r.frame:
        row.update(position=r.position, ne=r.ne, nw=r.nw, crc_ok=r.crc_ok, lc=r.lc)
        if r.word1 is not None:
            row.update(word1=r.word1, w1_ne=r.w1_ne, w1_nw=r.w1_nw, w1_crc_ok=r.w1_crc_ok)
        for w, c in r.chain.items():
            row.update({f"word{w}": c.data, f"w{w}_ne": c.ne, f"w{w}_nw": c.nw,
                        f"w{w}_crc_ok": c.crc_ok})
    if r.frame or r.status == "DELAY_RANGE":
        row.update(line_delay=r.line_delay, line_delay_ns=f"{_ns(r.line_delay, clock_hz):.1f}")
    return {c: row.get(c, "") for c in columns}


def read_csv(path):
    """Results back from a `log` CSV."""
    names = {f.name for f in dataclass_fields(Result)} - {"chain"}
    results = []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = set(CSV_COLUMNS) - set(reader.fieldnames or ())
        if missing:
            raise UsageError(f"{path}: not a `bissmaster log` CSV (no {', '.join(sorted(missing))})")
        for row in reader:
            values = {"channel": int(row["channel"]), "time_s": float(row["time_s"]),
                      "status": row["status"]}
            for key in names - {"channel", "time_s", "status"}:
                if row.get(key, "") != "":
                    values[key] = int(row[key])
            results.append(Result(**values))
    return results


def cmd_log(board, args, out, err):
    frames = {ch: board.frame(ch) for ch in args.channel}
    columns = CSV_COLUMNS + chain_csv_columns(_shown_chain(frames))
    f = out if args.output == "-" else _open_output(args.output, "w", newline="")
    try:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()

        def on_sample(index, results):
            for r in results:
                writer.writerow(csv_row(r, args.clock_hz, columns))
            f.flush()
        _, counts = sample(board, args, on_sample, keep=False)
    finally:
        if f is not out:
            f.close()
    if args.output != "-":
        print(f"{sum(counts.values())} results to {args.output}", file=out)
    return verdict(counts, err)


def _open_output(path, mode, **kw):
    try:
        return open(path, mode, **kw)
    except OSError as e:
        raise UsageError(f"cannot write {path}: {e.strerror or e}") from None


def make_figure(results, clock_hz, title="bissmaster"):
    """The plot's figure (matplotlib, no pyplot): position against time per channel, a
    histogram of the line delay, the count of each status other than OK. Axes in that order."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator
    fig = Figure(figsize=(8, 9), dpi=100)
    pos, hist, errs = fig.subplots(3, 1)
    chans = sorted({r.channel for r in results})
    for ch in chans:
        frames = [r for r in results if r.channel == ch and r.frame]
        pos.plot([r.time_s for r in frames], [r.position for r in frames], ".-", ms=3,
                 label=f"channel {ch}")
    pos.set_xlabel("time (s)")
    pos.set_ylabel("position (counts)")
    pos.set_title(title)
    if chans:
        pos.legend(loc="best")
    # The line delay is counted in clocks: one bin per clock, a few clocks of margin.
    step = 1e9 / clock_hz
    delays = [_ns(r.line_delay, clock_hz) for r in results if r.frame]
    if delays:
        lo, hi = min(delays), max(delays)
        n = round((hi - lo) / step) + 1
        if n <= 200:
            hist.hist(delays, bins=[lo + (i - 0.5) * step for i in range(n + 1)])
        else:
            hist.hist(delays, bins=100)
        margin = max(3 * step, (hi - lo) * 0.05)
        hist.set_xlim(lo - margin, hi + margin)
    hist.set_xlabel("line delay (ns)")
    hist.set_ylabel("samples")
    counts = {}
    for r in results:
        if r.status != "OK":
            counts[r.status] = counts.get(r.status, 0) + 1
    names = sorted(counts) or ["none"]
    errs.bar(range(len(names)), [counts.get(n, 0) for n in names])
    errs.set_xticks(range(len(names)), names, rotation=20, fontsize=8)
    errs.set_ylim(0, max([1, *counts.values()]) * 1.15)
    errs.yaxis.set_major_locator(MaxNLocator(integer=True))
    errs.set_xlabel("status")
    errs.set_ylabel("samples not OK")
    errs.set_title(f"{len(results) - sum(counts.values())} of {len(results)} results OK")
    fig.tight_layout()
    return fig


def cmd_plot(board, args, out, err):
    with _open_output(args.output, "wb") as f:       # before sampling: a bad path fails first
        if args.input:
            results = read_csv(args.input)
            code = EXIT_CODES["ok"]
        else:
            results, counts = sample(board, args, lambda i, r: None)
            code = verdict(counts, err)
        make_figure(results, args.clock_hz).savefig(f, format="png")
    print(f"{len(results)} results plotted to {args.output}", file=out)
    return code


# -- identify -----------------------------------------------------------------------------------

def cmd_identify(board, args, out, err):
    ch = _one_channel(args)
    caps = board.caps(ch)
    if not caps["register_access"]:
        raise CapabilityError(f"channel {ch} was built without the register-access engine: "
                              f"no BP3 identification")
    from . import bp3                       # (imports Amaranth, for the settings' names)
    from ..params import Crc, MasterParams
    saved = board.config(ch)
    # The data channel before identification (docs/control.md): the longest frame the build
    # reads, no check that can fail, so that every cycle of the accesses ends OK.
    words = 2 if caps["data_bits_w1"] else 1
    longest = {"w0_data_bits": caps["data_bits_w0"], "w0_nenw": 1, "w0_lc": 0, "w0_crc": 0,
               "w1_enable": int(words == 2), "spw_check": 0, "end_check": 0}
    if words == 2:
        longest.update(w1_data_bits=caps["data_bits_w1"], w1_nenw=1, w1_lc=0, w1_crc=0)
    longest.update({f"w{w}_enable": 0 for w in board.chain_words(ch)})    # no chain words
    try:
        if args.ma_hz:
            longest["ma_half_period"] = presets.half_period(args.clock_hz, args.ma_hz)
        elif saved["ma_half_period"] < 2:
            longest["ma_half_period"] = presets.half_period(args.clock_hz, 1e6)
    except ValueError as e:
        raise UsageError(str(e)) from None
    params = MasterParams(max_data_bits=tuple(caps[f"data_bits_w{w}"] for w in range(words)),
                          word_crcs=((Crc.CRC6, Crc.CRC16),) * words)
    applied = False
    try:
        if board.configure(ch, longest):
            raise UsageError(f"channel {ch}: the core refuses the identification frame "
                             f"(state.config_error 1)")
        try:
            ident = bp3.identify(
                lambda slave, address, count: board.reg_read(ch, slave, address, count,
                                                             args.timeout),
                lambda slave, address, data: board.reg_write(ch, slave, address, data,
                                                             args.timeout),
                slave_id=args.slave, profile_bank_offset=args.eds_offset, params=params)
        except bp3.Bp3Error as e:
            raise EncoderErrors(f"channel {ch}: BP3: {e}") from None
        print_identification(ident, ch, args.slave, out)
        if args.apply:
            if board.configure(ch, ident.config):
                raise UsageError(f"channel {ch}: the core refuses the derived configuration")
            applied = True
            print(f"applied to channel {ch} (MA half period "
                  f"{board.config(ch)['ma_half_period']} clocks)", file=out)
        else:
            print("not applied (--apply configures the channel from it)", file=out)
    finally:
        if not applied:
            try:
                board.configure(ch, saved)
            except LinkError:
                pass
    return EXIT_CODES["ok"]


def print_identification(ident, ch, slave, out):
    p = ident.profile
    print(f"channel {ch}, slave {slave}: BP3 profile ID: version {p.version}, "
          f"C = {int(p.crc_mode)} ({p.crc_mode.name}), DL = {p.data_length}"
          + (f" ({p.position_bits} position bits + nE, nW)" if p.position_bits else ""), file=out)
    print(f"EDS: pointer (register 0x41) bank {ident.eds_bank:#04x}, BP3 bank "
          f"{ident.profile_bank:#04x}", file=out)
    from .bp3 import EDS_LAYOUT
    eds = ident.eds
    notes = {
        "PON_PDL": "ms until position data after power-on",
        "MT_CNT": "revolutions (periods) counted", "SIP_CNT": "signal periods per revolution "
        "(linear: period in nm)", "SIP_RES": "steps per signal period",
        "CPOLY": f"CRC polynomial {eds.crc_polynomial:#x}", "CSTART": "CRC start value",
        "SPD_MAX": "1/min (linear: m/min)",
        "TMP_MIN": f"K ({eds.tmp_min - 273.15:.1f} C)",
        "TMP_MAX": f"K ({eds.tmp_max - 273.15:.1f} C)",
        "VLT_MIN": "mV", "VLT_MAX": "mV", "CUR_MAX": "mA", "CHKSUM": "checked",
    }
    print(f"  {'field':<8} {'byte':>4}  {'value':>12}  {'hex':<10} note", file=out)
    for symbol, addr, _ in EDS_LAYOUT:
        value = getattr(eds, symbol.lower())
        shown = f"{value.name} ({int(value)})" if hasattr(value, "name") else str(value)
        print(f"  {symbol:<8} {addr:#04x}  {shown:>12}  {f'{int(value):#x}':<10} "
              f"{notes.get(symbol, '')}".rstrip(), file=out)
    print("derived configuration:", file=out)
    for port, value in ident.config.items():
        print(f"  {port[4:] if port.startswith('cfg_') else port:<14} {value}", file=out)


# -- regs, counters, config ---------------------------------------------------------------------

def cmd_regs(board, args, out, err):
    ch = _one_channel(args)
    if board.read_fields("state", ch)["config_error"]:
        raise UsageError(f"channel {ch} is not configured (state.config_error 1): a register "
                         f"access needs data-channel cycles that end OK; configure the channel "
                         f"for the encoder's frame first (bissmaster config --preset ..., or "
                         f"bissmaster identify --apply)")
    if args.op == "read":
        if args.address + args.n - 1 > 0x7F:
            raise UsageError(f"registers {args.address:#04x}..{args.address + args.n - 1:#04x}: "
                             f"the last encoder register is 0x7F")
        data = board.reg_read(ch, args.slave, args.address, args.n, args.timeout)
        for i in range(0, len(data), 16):
            print(f"{args.address + i:#04x}: " + " ".join(f"{b:02x}" for b in data[i:i + 16]),
                  file=out)
    else:
        if args.address + len(args.values) - 1 > 0x7F:
            raise UsageError(f"{len(args.values)} values from {args.address:#04x}: the last "
                             f"encoder register is 0x7F")
        if len(args.values) > regmap.MAX_ACCESS_BYTES:
            raise UsageError(f"at most {regmap.MAX_ACCESS_BYTES} values in one access")
        board.reg_write(ch, args.slave, args.address, bytes(args.values), args.timeout)
        print(f"wrote {len(args.values)} register(s) from {args.address:#04x} of slave "
              f"{args.slave}", file=out)
    return EXIT_CODES["ok"]


def cmd_counters(board, args, out, err):
    for ch in args.channel:
        counts = board.counters(ch)
        width = max(map(len, counts))
        print(f"channel {ch} counters:", file=out)
        for name, value in counts.items():
            print(f"  {name:<{width}} {value}", file=out)
        if args.clear:
            board.clear_counters(ch)
            print(f"channel {ch}: counters cleared", file=out)
    return EXIT_CODES["ok"]


#: ctrl fields `config --set` accepts besides the configuration registers'.
CTRL_SETTINGS = ("periodic", "trigger_enable")


def cmd_config(board, args, out, err):
    if args.list_presets:
        for name in presets.PRESETS:
            print(f"{name:<16} {presets.describe(name)}", file=out)
        print(f"{'biss-c-N':<16} word 0 N bits nE nW CRC6 (N 1..64)", file=out)
        return EXIT_CODES["ok"]
    ch = _one_channel(args)
    settings, ctrl = {}, {}
    if args.preset:
        try:
            settings = presets.config(args.preset, args.clock_hz, args.ma_hz)
        except (KeyError, ValueError) as e:
            raise UsageError(str(e.args[0])) from None
        # A preset is one encoder's frame (words 0 and 1): the build's chain words off.
        settings.update({name: 0 for w in board.chain_words(ch) for name in chain_settings(w)})
        check_words(board, ch, settings, f"preset {args.preset}")
    for w in WORDS:
        crc = getattr(args, f"w{w}_crc") or {}
        check_words(board, ch, crc, f"--w{w}-crc")
        settings.update(crc)
    for name, value in args.set:
        if name in CTRL_SETTINGS:
            ctrl[name] = value
            continue
        try:
            register, field = setting_register(name)
            regmap.put(register, 0, **{field: value})
        except (KeyError, ValueError) as e:
            raise UsageError(f"--set {name}={value}: {e.args[0]}") from None
        bare = name[4:] if name.startswith("cfg_") else name
        check_words(board, ch, {bare: value}, f"--set {name}={value}")
        settings[bare] = value
    if settings or ctrl:
        if settings:
            refused = board.configure(ch, settings)
        if ctrl:
            try:
                board.update("ctrl", ch, **ctrl)
            except ValueError as e:
                raise UsageError(str(e)) from None
        print(f"channel {ch}: " + ", ".join(f"{k}={v}" for k, v in {**settings, **ctrl}.items()),
              file=out)
    cfg = show_config(board, ch, args.clock_hz, out)
    if settings and refused:
        print(f"bissmaster: channel {ch}: the core refuses this configuration "
              f"(state.config_error 1): a request now ends BAD_CONFIG"
              + chain_gap(cfg, board.chain_words(ch)), file=err)
        return EXIT_CODES["bad argument"]
    return EXIT_CODES["ok"]


def check_words(board, ch, settings, what):
    """Refuse (CapabilityError, exit 2) settings ``{name: value}`` of a chain word channel
    ``ch``'s build lacks (caps.words), and a word's ``wN_data_bits`` above what the build reads
    for it (caps.data_bits_w0 / _w1, caps_chain / caps_chain2). ``what`` names their origin."""
    caps = board.word_caps(ch)
    for name, value in settings.items():
        m = re.match(r"w(\d+)_", name)
        if not m:
            continue
        w = int(m.group(1))
        if w not in caps:
            n = board.words(ch)
            raise CapabilityError(f"{what}: channel {ch} has no word {w}: its build decodes "
                                  f"words 0..{n - 1} (caps.words {n})")
        if name == f"w{w}_data_bits" and value > caps[w]:
            raise CapabilityError(f"{what}: word {w} has {value} bits, channel {ch} reads up "
                                  f"to {caps[w]}")


def chain_gap(cfg, chain_words):
    """Why a chain configuration is refused, if it is a gap (docs/bus.md, Chains: the words
    in the frame are words 0..N-1, word 1 by cfg_words.w1_enable): a clause, or ""."""
    enabled = [1, cfg["w1_enable"], *(cfg[f"w{w}_enable"] for w in chain_words)]
    for w in range(2, len(enabled)):
        if enabled[w] and not enabled[w - 1]:
            return (f"; word {w} is enabled without word {w - 1}: a chain is words 0..N-1 "
                    f"with no gap")
    return ""


def show_config(board, ch, clock_hz, out):
    caps = board.caps(ch)
    state = board.read_fields("state", ch)
    ctrl = board.read_fields("ctrl", ch)
    cfg = board.config(ch)
    yes = {0: "no", 1: "yes"}
    chain = board.chain_words(ch)
    lengths = board.word_caps(ch)
    print(f"channel {ch}: caps: {board.words(ch)} word(s), word 0 up to {caps['data_bits_w0']} "
          f"bits, word 1 up to {caps['data_bits_w1']}"
          + "".join(f", word {w} up to {lengths[w]}" for w in chain)
          + f", timers {caps['timer_width']} bits, counters "
          f"{yes[caps['counters']]}, timestamp {yes[caps['timestamp']]}, register access "
          f"{yes[caps['register_access']]}, SSI {yes[caps['ssi']]}", file=out)
    print(f"channel {ch}: state: busy {state['busy']}, config_error {state['config_error']}; "
          f"ctrl: periodic {ctrl['periodic']}, trigger_enable {ctrl['trigger_enable']}",
          file=out)
    hp = cfg["ma_half_period"]
    notes = {
        "ma_half_period": f"MA {clock_hz / (2 * hp):.0f} Hz at {clock_hz:.0f} Hz" if hp else
                          "unset: the core refuses it",
        "delay_limit": "the build's maximum" if not cfg["delay_limit"] else
                       f"{_ns(cfg['delay_limit'], clock_hz):.0f} ns",
        "request_period": "as fast as the encoder allows" if not cfg["request_period"] else
                          f"{cfg['request_period'] / clock_hz * 1e6:.1f} us",
        "break_time": "default (40 us)", "ack_limit": "default (40 us)",
        "timeout_limit": "default (80 us)",
    }
    for w in (0, 1, *chain):
        notes[f"w{w}_crc"] = regmap.CRC_NAMES.get(cfg[f"w{w}_crc"], "invalid")
        if cfg[f"w{w}_crc"] == regmap.CRC_CODES["custom"]:
            notes[f"w{w}_crc"] = (f"custom: {cfg[f'w{w}_crc_width']} bits, polynomial "
                                  f"0x{cfg[f'w{w}_crc_poly']:X}, start 0x{cfg[f'w{w}_crc_start']:X}, "
                                  + ("sent inverted" if cfg[f"w{w}_crc_inverted"] else "sent plain"))
    for key in ("break_time", "ack_limit", "timeout_limit"):
        if cfg[key]:
            notes[key] = f"{cfg[key] / clock_hz * 1e6:.1f} us"
    names = [name for register in regmap.CONFIG_REGISTERS for name in regmap.FIELDS[register]]
    names += [name for w in chain for name in chain_settings(w)]
    for name in names:
        print(f"  {name:<15} {cfg[name]:>8}  {notes.get(name, '')}".rstrip(), file=out)
    return cfg


# -- main -------------------------------------------------------------------------------------

def main(argv=None, *, transport=None, stdout=None, stderr=None):
    """Run the tool; returns the exit code (:data:`EXIT_CODES`). ``transport``: talk over it
    instead of opening ``--port`` (the software model, a simulator)."""
    out = stdout or sys.stdout
    err = stderr or sys.stderr
    parser = build_parser()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            args = parser.parse_args(argv)
    except SystemExit as e:             # argparse: --help (0) or a usage error (2)
        return e.code if isinstance(e.code, int) else EXIT_CODES["bad argument"]

    def fail(kind, message):
        print(f"bissmaster: {message}", file=err)
        return EXIT_CODES[kind]

    board = None
    try:
        if args.command == "config" and args.list_presets:
            return cmd_config(None, args, out, err)
        if args.command == "plot" and args.input:
            return cmd_plot(None, args, out, err)
        board = open_board(args, transport)
        return args.func(board, args, out, err)
    except KeyboardInterrupt:
        return fail("interrupted", "interrupted")
    except UsageError as e:
        return fail("bad argument", e)
    except CapabilityError as e:
        return fail("bad argument", e)
    except PortError as e:
        return fail("port", e)
    except (NoBoardError, NotTheCoreError) as e:
        return fail("no board", e)
    except LinkError as e:
        return fail("link", f"garbled link: {e}")
    except EncoderSilentError as e:
        return fail("no encoder", e)
    except (AccessError, EncoderErrors) as e:
        return fail("encoder errors", e)
    except TornReadError as e:
        return fail("bad argument", f"{e}: frames end faster than the tool reads them; sample "
                    f"triggered (without --free-run) or with a longer --free-run PERIOD_US")
    except BoardError as e:
        return fail("bad argument", e)
    except OSError as e:                # the port failed while in use (unplugged)
        where = f"the port {args.port}" if transport is None else "the transport"
        return fail("port", f"{where} failed while in use (unplugged?): {e}")
    finally:
        if board is not None and transport is None:
            close = getattr(board.link.transport, "close", None)
            if close:
                close()


if __name__ == "__main__":
    sys.exit(main())
