"""Generate the Verilog module ``biss_master``.

    python -m bissmaster.generate [-o FILE] [--preset NAME] [--max-data-bits 55,40] ...

The default configuration is committed as ``rtl/generated/biss_master.v`` for users who never
run Python; ``make rtl`` regenerates it and the test suite checks it is up to date.
"""

import argparse
import sys
from importlib import metadata

from amaranth.back import verilog

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


# The Renishaw encoders are unidirectional (CDS always 0): their builds leave the
# register-access engine out.
_NO_ACCESS = ["--register-access", "0"]
_BISS_C = ["--max-data-bits", "36", "--word-crcs", "6"] + _NO_ACCESS

#: Named builds: generator options for ``--preset``. Options given besides a preset win.
#: scripts/synth.py measures these, and the test suite simulates each one.
PRESETS = {
    "default": ("the committed rtl/generated/biss_master.v: 2 words of up to 55/40 bits, "
                "both CRCs on each, the register-access engine (BP3 identification, EDS)", []),
    "biss-c": ("BiSS C only: one word of up to 36 bits, CRC-6, no register access", _BISS_C),
    "biss-c-lean": ("BiSS C only, smallest: as biss-c, without error counters and timestamp, "
                    "16-bit time settings",
                    _BISS_C + ["--counter-width", "0", "--timestamp-width", "0",
                               "--timer-width", "16"]),
    "safety": ("BiSS Safety: CPW up to 36 bits with CRC-6, SPW up to 28 bits with CRC-16, "
               "no register access",
               ["--max-data-bits", "36,28", "--word-crcs", "6,16"] + _NO_ACCESS),
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
    ap.add_argument("--name", default="biss_master", help="Verilog module name")
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
    ap.add_argument("--register-access", type=int, choices=(0, 1),
                    default=int(defaults.register_access),
                    help="1: build the register-access engine (ca_* ports, CDM hold); 0: leave it out")
    ap.add_argument("--start-wait-frames", type=int, default=defaults.start_wait_frames,
                    help="register reads: frames to wait for a late slave start bit (1 .. 255)")
    argv = sys.argv[1:] if argv is None else list(argv)
    preset = ap.parse_known_args(argv)[0].preset
    args = ap.parse_args(PRESETS[preset][1] + argv)     # later options win

    bits = tuple(int(b) for b in args.max_data_bits.split(","))
    crcs = args.word_crcs or defaults.word_crcs[:len(bits)]
    try:
        params = MasterParams(sys_clk_hz=args.sys_clk_hz, max_data_bits=bits, word_crcs=crcs,
                              max_line_delay=args.max_line_delay, timer_width=args.timer_width,
                              counter_width=args.counter_width,
                              timestamp_width=args.timestamp_width,
                              register_access=bool(args.register_access),
                              start_wait_frames=args.start_wait_frames)
    except ValueError as e:
        ap.error(str(e))
    text = generate(params, args.name)
    if args.output == "-":
        sys.stdout.write(text)
    else:
        with open(args.output, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
