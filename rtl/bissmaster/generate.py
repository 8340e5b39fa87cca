"""Generate the Verilog module ``biss_master``, or a bus top of several channels.

    python -m bissmaster.generate [-o FILE] [--preset NAME] [--max-data-bits 55,40] ...
    python -m bissmaster.generate --bus axil|wb [--channels N] [--preset NAME] ...

The default configurations are committed (``rtl/generated/biss_master.v``,
``biss_master_axil.v``, ``biss_master_wb.v``) for users who never run Python; ``make rtl``
regenerates them and the test suite checks they are up to date.
"""

import argparse
import sys
from importlib import metadata

from amaranth.back import verilog

from .bus_top import BUSES, BusTop
from .master import BissMaster
from .params import Crc, MasterParams


def header(params):
    lines = [
        "BiSS C / BiSS Safety master: generated Verilog. DO NOT EDIT; edit the Amaranth source.",
        f"Generator: bissmaster.generate, amaranth {metadata.version('amaranth')}",
        "Parameters:",
        *("  " + line for line in params.describe()),
        "Ports: docs/ports.md. Constraints: constraints/.",
    ]
    return "".join(f"// {line}\n" for line in lines)


def generate(params=None, name="biss_master"):
    params = params or MasterParams()
    body = verilog.convert(BissMaster(params), name=name, emit_src=False)
    return header(params) + body


def header_bus(bus, channels, params):
    lines = [
        f"BiSS master bus top ({'AXI4-Lite' if bus == 'axil' else 'Wishbone B4'}, "
        f"{channels} channel{'s' * (channels > 1)}): generated Verilog. DO NOT EDIT; edit the "
        "Amaranth source or the register map.",
        f"Generator: bissmaster.generate --bus {bus}, amaranth {metadata.version('amaranth')}",
        "Register map: rtl/regmap/biss_master.rdl (docs/registers.md, docs/bus.md).",
        "Parameters of each channel's core:",
        *("  " + line for line in params.describe()),
        "Ports: docs/bus.md. Constraints: constraints/.",
    ]
    return "".join(f"// {line}\n" for line in lines)


#: Channels of the committed bus tops.
BUS_CHANNELS = 2


def generate_bus(bus="axil", channels=BUS_CHANNELS, params=None, name=None):
    """Verilog of a bus top (every channel with the same ``params``)."""
    params = params or MasterParams()
    top = BusTop(bus, channels, params)
    body = verilog.convert(top, name=name or f"biss_master_{bus}", emit_src=False)
    return header_bus(bus, channels, params) + body


_BISS_C = ["--max-data-bits", "36", "--word-crcs", "6"]

#: Named builds: generator options for ``--preset``. Options given besides a preset win.
#: scripts/synth.py measures these, and the test suite simulates each one.
PRESETS = {
    "default": ("the committed rtl/generated/biss_master.v: 2 words of up to 55/40 bits, "
                "both CRCs on each", []),
    "biss-c": ("BiSS C only: one word of up to 36 bits, CRC-6", _BISS_C),
    "biss-c-lean": ("BiSS C only, smallest: as biss-c, without error counters and timestamp, "
                    "16-bit time settings",
                    _BISS_C + ["--counter-width", "0", "--timestamp-width", "0",
                               "--timer-width", "16"]),
    "safety": ("BiSS Safety: CPW up to 36 bits with CRC-6, SPW up to 28 bits with CRC-16",
               ["--max-data-bits", "36,28", "--word-crcs", "6,16"]),
}


def _parse_crcs(text):
    # "6+16,16" -> ((CRC6, CRC16), (CRC16,))
    kinds = {"6": Crc.CRC6, "16": Crc.CRC16}
    try:
        return tuple(tuple(kinds[k] for k in word.split("+")) for word in text.split(","))
    except KeyError as e:
        raise argparse.ArgumentTypeError(f"CRC must be 6 or 16, not {e.args[0]!r}")


def main(argv=None):
    defaults = MasterParams()
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="presets: " + "; ".join(f"{k}: {v[0]}" for k, v in PRESETS.items()))
    ap.add_argument("--preset", choices=PRESETS, default="default",
                    help="a named build (below); other options given override it")
    ap.add_argument("-o", "--output", default="-", help="output file (default: stdout)")
    ap.add_argument("--name", default=None,
                    help="Verilog module name (default: biss_master, or biss_master_<bus>)")
    ap.add_argument("--bus", choices=sorted(BUSES), default=None,
                    help="generate a bus top: AXI4-Lite (axil) or Wishbone B4 (wb)")
    ap.add_argument("--channels", type=int, default=BUS_CHANNELS,
                    help=f"channels of a bus top, 1..8 (default {BUS_CHANNELS})")
    ap.add_argument("--sys-clk-hz", type=int, default=defaults.sys_clk_hz)
    ap.add_argument("--max-data-bits", default=",".join(map(str, defaults.max_data_bits)),
                    help="per word, e.g. 36 (BiSS C only) or 36,28")
    ap.add_argument("--word-crcs", type=_parse_crcs, default=None,
                    help="CRC checkers per word, e.g. 6 or 6+16,6+16 (default: both on each word)")
    ap.add_argument("--max-line-delay", type=int, default=defaults.max_line_delay)
    ap.add_argument("--timer-width", type=int, default=defaults.timer_width,
                    help="width of the time settings in system clocks (16 .. 32)")
    ap.add_argument("--counter-width", type=int, default=defaults.counter_width,
                    help="width of the error counters; 0: no counters")
    ap.add_argument("--timestamp-width", type=int, default=defaults.timestamp_width,
                    help="width of the time base behind `timestamp`; 0: no timestamp")
    argv = sys.argv[1:] if argv is None else list(argv)
    preset = ap.parse_known_args(argv)[0].preset
    args = ap.parse_args(PRESETS[preset][1] + argv)     # later options win

    bits = tuple(int(b) for b in args.max_data_bits.split(","))
    crcs = args.word_crcs or defaults.word_crcs[:len(bits)]
    try:
        params = MasterParams(sys_clk_hz=args.sys_clk_hz, max_data_bits=bits, word_crcs=crcs,
                              max_line_delay=args.max_line_delay, timer_width=args.timer_width,
                              counter_width=args.counter_width,
                              timestamp_width=args.timestamp_width)
    except ValueError as e:
        ap.error(str(e))
    if args.bus:
        try:
            text = generate_bus(args.bus, args.channels, params, args.name)
        except ValueError as e:
            ap.error(str(e))
    else:
        text = generate(params, args.name or "biss_master")
    if args.output == "-":
        sys.stdout.write(text)
    else:
        with open(args.output, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
