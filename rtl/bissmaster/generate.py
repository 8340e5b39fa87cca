"""Generate the Verilog of the BiSS master.

    bissmaster-generate [-o FILE] [--preset NAME] [--max-data-bits 55,40] ...
    python -m bissmaster.generate ...           (the same command, from a source checkout)

The default configuration is committed as ``rtl/generated/biss_master.v`` for users who never
run Python; ``make rtl`` regenerates it and the test suite checks it is up to date.

What is built is a *top* (``--top``) made of cores of one configuration (``--preset`` and the
core options): ``core`` is the module ``biss_master`` with every setting and result a port;
``axil``, ``wb`` and ``uart`` put ``--channels`` cores behind AXI4-Lite, Wishbone or the UART
bridge (``--baud``, docs/uart_bridge.md) and one register bank (:data:`TOPS`, each with its own
options). The bus tops read their register map with
systemrdl-compiler, the package's one optional dependency (``pip install 'bissmaster[bus]'``);
without it they are refused in one line, and the core needs nothing more.
"""

import argparse
import importlib.util
import re
import sys
from dataclasses import dataclass, field, replace
from importlib import metadata

from amaranth.back import verilog

from . import __version__
from .bus.bus_top import BUSES, BusTop
from .master import BissMaster
from .params import Crc, MasterParams


def header(params, top_lines=()):
    """The comment block on top of a generated file: generator, parameters (``top_lines``: a
    top's own parameters, after the core's), where the ports and constraints are described."""
    lines = [
        "BiSS C / BiSS Safety master: generated Verilog. DO NOT EDIT; edit the Amaranth source.",
        f"Generator: bissmaster.generate, amaranth {metadata.version('amaranth')}",
        "Parameters:",
        *("  " + line for line in params.describe()),
        *("  " + line for line in top_lines),
        "Ports: docs/ports.md. Constraints: constraints/.",
    ]
    return "".join(f"// {line}\n" for line in lines)


@dataclass(frozen=True)
class Top:
    """A top-level module the generator can build from cores of one :class:`MasterParams`.

    ``build(params, **options)`` returns the Elaboratable; ``options`` are the top's own
    command-line options as ``(flags, argparse keywords)`` pairs, passed to ``build`` by their
    ``dest`` (give each ``default=None`` on the command line and its real default in ``build``:
    an option left out is not passed); ``describe(**options)`` gives the header lines of those
    options. Several tops may share an option (same flags, same keywords).
    """
    summary: str
    module: str
    build: object
    options: tuple = ()
    describe: object = field(default=lambda **options: ())


#: How a user gets what the bus tops need beyond the core (pyproject.toml's optional ``bus``).
BUS_EXTRA = "pip install 'bissmaster[bus]'"

#: Channels of the committed bus tops.
BUS_CHANNELS = 2


#: The command-line options of the buses' own parameters (:attr:`~bissmaster.bus.bus_top.Bus.options`),
#: by parameter: flags and argparse keywords (``default=None``: the bus's default applies).
BUS_OPTIONS = {
    "baud": (("--baud",), dict(type=int, default=None, metavar="BAUD",
                               help="the UART's baud rate, 8N1; the divider round(sys_clk_hz / "
                                    "BAUD) must be at least 4 and within 2 %% of it "
                                    "(default 115200)")),
    "timeout_bits": (("--uart-timeout-bits",),
                     dict(type=int, default=None, metavar="BITS", dest="timeout_bits",
                          help="the UART bridge's inter-byte timeout in bit times: a partial "
                               "request is dropped after this long a quiet line (default "
                               "1000)")),
}


def _bus_top(bus):
    """A :class:`Top` for ``bus`` (a :data:`~bissmaster.bus.bus_top.BUSES` name): ``channels`` cores
    behind the register bank of bissmaster/bus/biss_master.rdl. The cores are the preset's, the
    register-access engine included unless ``--register-access 0`` (the map's ``ca`` block then
    reads 0, ``caps.register_access`` says so). The bus's own parameters (the UART's baud rate
    and timeout) are options of their own (:data:`BUS_OPTIONS`)."""
    spec = BUSES[bus]

    def build(params, channels=BUS_CHANNELS, **options):
        return BusTop(bus, channels, params, **options)

    def describe(channels=BUS_CHANNELS, **options):
        lines = [f"bus             = {spec.title}", f"channels        = {channels}"]
        if bus == "uart":
            options = {**spec.options, **options}
            lines += [f"baud            = {options['baud']} (docs/uart_bridge.md)",
                      f"uart timeout    = {options['timeout_bits']} bit times"]
        return lines + ["register map    = rtl/bissmaster/bus/biss_master.rdl (docs/registers.md)"]

    what = {"uart": "the UART bridge (docs/uart_bridge.md)"}.get(bus, spec.title)
    return Top(f"CHANNELS cores behind {what} "
               f"(module biss_master_{bus}; register map docs/registers.md)",
               f"biss_master_{bus}", build,
               options=((("--channels",), dict(type=int, default=None, metavar="N",
                                               help=f"channels, 1..8 (default {BUS_CHANNELS})")),
                        *(BUS_OPTIONS[name] for name in spec.options)),
               describe=describe)


#: The tops ``--top`` chooses from; the first is the default.
TOPS = {
    "core": Top("one master core (module biss_master): every cfg_* setting and result is a port",
                "biss_master", BissMaster),
    **{bus: _bus_top(bus) for bus in sorted(BUSES)},
}


def generate_bus(bus="axil", channels=BUS_CHANNELS, params=None, name=None, **options):
    """The Verilog text of a bus top (``--top axil|wb|uart --channels N``; ``options``: the
    bus's own, e.g. ``baud`` for ``uart``)."""
    return generate(params, name, bus, channels=channels, **options)


class Family:
    """What the design is elaborated for when it is generated for one FPGA family
    (``--family``): the blocks read ``platform.family`` as they do on a board's platform."""

    def __init__(self, family):
        self.family = family


#: ``--family`` choices -> the platform family the blocks see (None: any family).
FAMILIES = {"any": None, "ice40": "iCE40"}


#: A memory's ``initial`` block as Yosys writes it for Amaranth 0.5, whose RTLIL backend gives
#: every memory an initial value (zeros when it is given none: ``Memory(init=[])``): every row
#: set to zero, nothing else. A row of another value (a ROM's) does not match and stays.
_ZERO_MEMORY_INIT = re.compile(
    r"^  initial begin\n(?:    (?:\\\S+ |\w+)\[\d+\] = \d+'[dhb]0+;\n)+  end\n", re.M)


def drop_zero_memory_inits(text):
    """``text`` without its memories' all-zero ``initial`` blocks.

    No block of the design reads a memory word it has not written since the last reset: each
    memory is either cleared after reset by its block (the counter memory, the CRC table, the
    access engine's read buffer) or read behind a flag that is reset (the configuration
    read-back's written flags, the chain memory's published count), or read only where the
    host wrote it (the access engine's write buffer; docs/ports.md, "Clock and reset"). A memory keeps its contents through a reset anyway, so
    an initial value would hold only after power-up. What the initial value does do is keep
    Yosys's ``synth_intel_alm`` from mapping the memory to Cyclone V MLABs (it cannot
    initialize them): with it, every memory of the bus tops became flip-flops there
    (``axil-chain-8``: 4,840 FF, 2,494 without it; docs/performance.md, "Other families")."""
    return _ZERO_MEMORY_INIT.sub("", text)


def generate(params=None, name=None, top="core", family="any", **options):
    """The Verilog text of ``top`` (a :data:`TOPS` name) built from cores of ``params`` (default:
    :class:`MasterParams`), module ``name`` (default: the top's), with the top's ``options``,
    for ``family`` (a :data:`FAMILIES` name)."""
    params = params or MasterParams()
    spec = TOPS[top]
    platform = Family(FAMILIES[family]) if FAMILIES[family] else None
    body = drop_zero_memory_inits(verilog.convert(spec.build(params, **options),
                                                  name=name or spec.module,
                                                  platform=platform, emit_src=False))
    lines = spec.describe(**options)
    if platform:
        lines = [*lines, f"family          = {FAMILIES[family]} (--family {family})"]
    return header(params, lines) + body


# The Renishaw encoders are unidirectional (CDS always 0): their builds leave the
# register-access engine out.
_NO_ACCESS = ["--register-access", "0"]
# The named BiSS builds leave SSI out (the default build has it).
_NO_SSI = ["--ssi", "0"]
# The BiSS-C-only builds read one CRC-6 word: custom CRCs and signed words (issue 26's
# per-word options, about 160 LUT4 on ECP5) are left out too, so that these presets stay the
# size they were before those options came (docs/performance.md); ``--custom-crc 1
# --signed-words 1`` adds them back.
_BISS_C = (["--max-data-bits", "36", "--word-crcs", "6", "--custom-crc", "0",
            "--signed-words", "0"] + _NO_ACCESS + _NO_SSI)

#: Named builds: core options for ``--preset``. Options given besides a preset win.
#: scripts/synth.py measures these, and the test suite simulates each one.
PRESETS = {
    "default": ("the committed rtl/generated/biss_master.v: 2 words of up to 55/40 bits, "
                "both CRCs on each, the register-access engine (BP3 identification, EDS), "
                "SSI mode", []),
    "biss-c": ("BiSS C only: one word of up to 36 bits, CRC-6, no register access, no custom "
               "CRCs or signed words", _BISS_C),
    "biss-c-lean": ("BiSS C only, smallest: as biss-c, without error counters and timestamp, "
                    "16-bit time settings",
                    _BISS_C + ["--counter-width", "0", "--timestamp-width", "0",
                               "--timer-width", "16"]),
    "bp3": ("BiSS C / BP3 Standard Encoder Profile: one word of up to 55 bits (the profile's "
            "longest position), CRC-6, the register-access engine (identification, EDS, "
            "encoder registers)",
            ["--max-data-bits", "55", "--word-crcs", "6", "--register-access", "1"] + _NO_SSI),
    "safety": ("BiSS Safety: CPW up to 36 bits with CRC-6, SPW up to 28 bits with CRC-16, "
               "no register access",
               ["--max-data-bits", "36,28", "--word-crcs", "6,16"] + _NO_ACCESS + _NO_SSI),
    "chain": ("a chain of three slaves on one cable: words of up to 64, 32 and 24 bits, each "
              "with CRC-6 or its own CRC, no register access",
              ["--max-data-bits", "64,32,24", "--word-crcs", "6,6,6"] + _NO_ACCESS + _NO_SSI),
}


def _parse_crcs(text):
    # "6+16,16" -> ((CRC6, CRC16), (CRC16,))
    kinds = {"6": Crc.CRC6, "16": Crc.CRC16}
    try:
        return tuple(tuple(kinds[k] for k in word.split("+")) for word in text.split(","))
    except KeyError as e:
        raise argparse.ArgumentTypeError(f"CRC must be 6 or 16, not {e.args[0]!r}")


_EXAMPLES = """\
examples:
  %(prog)s -o biss_master.v                      the committed default build
  %(prog)s --preset biss-c-lean -o lean.v        the smallest BiSS C core
  %(prog)s --preset safety --sys-clk-hz 50000000 -o fs.v
  %(prog)s --preset biss-c --max-data-bits 26    a preset with one option changed
  %(prog)s --list-presets                        what each preset builds

Ports: docs/ports.md; constraints: constraints/README.md.
"""


def _parser():
    defaults = MasterParams()
    ap = argparse.ArgumentParser(
        prog="bissmaster-generate",
        description="Generate the Verilog of the BiSS C / BiSS Safety master "
                    "(Amaranth HDL -> Verilog, through Yosys).",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version",
                    version=f"%(prog)s {__version__} (amaranth {metadata.version('amaranth')})")

    what = ap.add_argument_group("what to build")
    what.add_argument("--top", choices=TOPS, default=next(iter(TOPS)),
                      help="the top-level module: " + "; ".join(
                          f"{k}: {v.summary}" for k, v in TOPS.items())
                      + f" (default: %(default)s; {', '.join(BUSES)} need {BUS_EXTRA})")
    what.add_argument("--preset", choices=PRESETS, default="default",
                      help="a named core configuration (--list-presets); core options given "
                           "besides it override it (default: %(default)s)")
    what.add_argument("--list-presets", action="store_true",
                      help="list the presets with their options and parameters, and exit")

    what.add_argument("--family", choices=FAMILIES, default="any",
                      help="the FPGA family the Verilog is for: any (default: memories left to "
                           "the tool's inference) or ice40 (as the iCE40 board designs are "
                           "built: the counter memory marked for block RAM, a bus top's "
                           "configuration read back from flip-flops, since iCE40 has no "
                           "distributed RAM)")

    out = ap.add_argument_group("output")
    out.add_argument("-o", "--output", default="-", metavar="FILE",
                     help="output file (default: stdout)")
    out.add_argument("--name", default=None,
                     help="Verilog module name (default: the top's, e.g. biss_master)")

    core = ap.add_argument_group("core options (override the preset)")
    core.add_argument("--sys-clk-hz", type=int, default=defaults.sys_clk_hz, metavar="HZ",
                      help="system clock; turns the protocol's default times into clocks "
                           "(default: %(default)s)")
    core.add_argument("--max-data-bits", default=",".join(map(str, defaults.max_data_bits)),
                      metavar="N[,N...]",
                      help="longest data field per word, 1 to 8 words, 1..64 each: 36 (BiSS C "
                           "only), 36,28 (CPW, SPW), 64,32,24 (a chain of three) "
                           "(default: %(default)s)")
    core.add_argument("--word-crcs", type=_parse_crcs, default=None, metavar="C[+C][,...]",
                      help="CRC checkers built per word, 6 and/or 16: 6, 6,16, 6+16,6+16 "
                           "(default: both on each word)")
    core.add_argument("--max-line-delay", type=int, default=defaults.max_line_delay,
                      metavar="CLOCKS",
                      help="longest measurable round trip, in system clocks "
                           "(default: %(default)s)")
    core.add_argument("--timer-width", type=int, default=defaults.timer_width, metavar="BITS",
                      help="width of the time settings in system clocks, 16..32 "
                           "(default: %(default)s)")
    core.add_argument("--half-period-width", type=int, default=defaults.half_period_width,
                      metavar="BITS",
                      help="width of the MA half-period setting in system clocks, 4..16: the "
                           "slowest MA is the system clock / (2 * (2**BITS - 1)); 10 bits reach "
                           "the protocol's 80 kHz at 100 MHz, 8 bits at 24 MHz "
                           "(default: %(default)s)")
    core.add_argument("--counter-width", type=int, default=defaults.counter_width,
                      metavar="BITS",
                      help="width of the error counters, 0: no counters (default: %(default)s)")
    core.add_argument("--counter-ram", type=int, choices=(0, 1),
                      default=int(defaults.counter_ram),
                      help="1: the data channel's counters in one memory behind a read port "
                           "(count_addr, count_en, count_data) instead of a count_* port each; "
                           "the bus tops always build them so (default: %(default)s)")
    core.add_argument("--chain-memory", type=int, choices=(0, 1),
                      default=int(defaults.chain_memory),
                      help="1: the data of words 2.. in one memory behind a read port "
                           "(chain_addr, chain_en, chain_data) instead of a word<N>_position "
                           "port each; no change with one or two words; the bus tops always "
                           "build them so (default: %(default)s)")
    core.add_argument("--timestamp-width", type=int, default=defaults.timestamp_width,
                      metavar="BITS",
                      help="width of the time base behind `timestamp`, 0: no timestamp "
                           "(default: %(default)s)")
    core.add_argument("--time-input", type=int, choices=(0, 1),
                      default=int(defaults.time_input),
                      help="1: the timestamp captures the input time_now (a time base shared "
                           "by several cores) instead of the core's own counter; the bus tops "
                           "always build them so (default: %(default)s)")
    core.add_argument("--custom-crc", type=int, choices=(0, 1),
                      default=int(defaults.custom_crc),
                      help="1: each word may have its own CRC (cfg_wN_crc = 3: width 1..16, "
                           "polynomial, start value, inversion on the cfg_wN_crc_* ports); "
                           "0: the named CRCs only (default: %(default)s)")
    core.add_argument("--signed-words", type=int, choices=(0, 1),
                      default=int(defaults.signed_words),
                      help="1: a word may be two's complement (cfg_wN_signed: sign-extended to "
                           "its port's width); 0: unsigned words only, no cfg_wN_signed ports "
                           "(default: %(default)s)")
    core.add_argument("--ssi", type=int, choices=(0, 1), default=int(defaults.ssi),
                      help="1: the channel may run SSI encoders (cfg_ssi, cfg_ssi_delay, "
                           "cfg_ssi_error, cfg_ssi_error_low, cfg_ssi_double); 0: BiSS only, "
                           "no cfg_ssi* ports (default: %(default)s)")
    core.add_argument("--register-access", type=int, choices=(0, 1),
                      default=int(defaults.register_access),
                      help="1: build the register-access engine (ca_* ports, CDM hold); "
                           "0: leave it out (default: %(default)s)")
    core.add_argument("--start-wait-frames", type=int, default=defaults.start_wait_frames,
                      metavar="FRAMES",
                      help="register reads: frames to wait for a late slave start bit, 1..255 "
                           "(default: %(default)s)")

    # The tops' own options, once each even when several tops share one.
    shared = {}
    for top_name, spec in TOPS.items():
        for flags, kwargs in spec.options:
            shared.setdefault(tuple(flags), (kwargs, []))[1].append(top_name)
    top_options = {}      # dest -> the tops that take it
    if shared:
        group = ap.add_argument_group("options of the bus tops")
        for flags, (kwargs, tops) in shared.items():
            kwargs = dict(kwargs, help=f"{kwargs.get('help', '')} (--top {', '.join(tops)})")
            top_options[group.add_argument(*flags, **kwargs).dest] = tops
    return ap, top_options


def _params(ap, args):
    defaults = MasterParams()
    try:
        bits = tuple(int(b) for b in args.max_data_bits.split(","))
    except ValueError:
        ap.error(f"--max-data-bits takes 1 to 8 integers, e.g. 36 or 36,28, "
                 f"not {args.max_data_bits!r}")
    crcs = args.word_crcs or (defaults.word_crcs[0],) * len(bits)
    try:
        return MasterParams(sys_clk_hz=args.sys_clk_hz, max_data_bits=bits, word_crcs=crcs,
                            max_line_delay=args.max_line_delay, timer_width=args.timer_width,
                            half_period_width=args.half_period_width,
                            counter_width=args.counter_width,
                            counter_ram=bool(args.counter_ram),
                            chain_memory=bool(args.chain_memory),
                            timestamp_width=args.timestamp_width,
                            time_input=bool(args.time_input),
                            custom_crc=bool(args.custom_crc),
                            signed_words=bool(args.signed_words),
                            ssi=bool(args.ssi),
                            register_access=bool(args.register_access),
                            start_wait_frames=args.start_wait_frames)
    except ValueError as e:
        ap.error(str(e))


def preset_params(preset="default", **overrides):
    """The :class:`MasterParams` of ``--preset preset`` (a :data:`PRESETS` name), with
    ``overrides`` (MasterParams fields, e.g. ``sys_clk_hz``) on top: what the command line
    builds for ``--preset preset`` and those options (the board designs use it)."""
    if preset not in PRESETS:
        raise ValueError(f"preset must be one of {', '.join(PRESETS)}, not {preset!r}")
    ap = _parser()[0]
    params = _params(ap, ap.parse_args(PRESETS[preset][1]))
    return replace(params, **overrides)


def list_presets(ap=None):
    """The text of ``--list-presets``: each preset's summary, options and parameters."""
    ap = ap or _parser()[0]
    out = ["Presets (--preset NAME); core options given besides a preset override it.", ""]
    for name, (summary, options) in PRESETS.items():
        params = _params(ap, ap.parse_args(options))
        out += [f"{name}", f"    {summary}",
                f"    options: {' '.join(options) or '(none: the defaults)'}",
                *(f"    {line}" for line in params.describe()), ""]
    return "\n".join(out)


def main(argv=None):
    """The command line (``bissmaster-generate``, ``python -m bissmaster.generate``)."""
    ap, top_options = _parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    preset = ap.parse_known_args(argv)[0].preset
    args = ap.parse_args(PRESETS[preset][1] + argv)     # later options win
    if args.list_presets:
        sys.stdout.write(list_presets(ap))
        return
    options = {}
    for dest, tops in top_options.items():
        value = getattr(args, dest)
        if args.top in tops:
            if value is not None:
                options[dest] = value
        elif value is not None:
            ap.error(f"--{dest.replace('_', '-')} applies to --top {', '.join(tops)}, "
                     f"not --top {args.top}")
    if args.top in BUSES and importlib.util.find_spec("systemrdl") is None:
        ap.error(f"--top {args.top} reads the register map with systemrdl-compiler, which is "
                 f"not installed: {BUS_EXTRA}")
    params = _params(ap, args)
    try:
        text = generate(params, args.name, args.top, args.family, **options)
    except ValueError as e:     # a top's parameters (channels, baud rate, ...) refused
        ap.error(str(e))
    if args.output == "-":
        sys.stdout.write(text)
    else:
        with open(args.output, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
