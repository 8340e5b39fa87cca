"""`make waves`: a GTKWave save file for a dump of biss_master, and a PNG of one frame.

The signals to show are described below (VIEW) by name, not by hierarchical path: each is looked
up in the dump's own scope tree, so the save file follows the core's hierarchy as it changes.
Every FSM of the design is shown with its state names and ``status`` with the ``Status`` names
(translate filter files from scripts/wavenames.py). The view opens on one frame: from the
first MA fall of frame N to its ``done`` strobe, found in the dump, with room after it for the
results' values; the marker is on ``done``, so the signal pane (as wide as its longest
name=value) shows the frame's results.

    python scripts/waves.py DUMP [--frame N] [--png out.png]

writes sim_build/waves/biss_master.gtkw (open it: ``gtkwave DUMP sim_build/waves/biss_master.gtkw``)
and, with --png, renders it headless (xvfb-run + GTKWave + scripts/grab.tcl).
"""

import argparse
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from vcd.gtkw import GTKWSave       # pyvcd, installed with Amaranth

import wavenames                    # scripts/, this file's folder (on the path when run or tested)

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "sim_build" / "waves"


@dataclass(frozen=True)
class Show:
    """A trace: ``name`` is a signal name, or its tail with scopes (``"decoder.done"``)."""
    name: str
    fmt: str = "hex"


#: Placeholder in VIEW for every FSM state register of the design.
FSMS = "every FSM of the design"
#: Signals (by name) whose values are Status codes.
STATUS_SIGNALS = ("status",)

#: What the save file shows, top to bottom: (group label, traces).
VIEW = (
    ("Line (MA out, SLO in)", (Show("clk"), Show("ma"), Show("slo"))),
    ("Cycle controller", (Show("start"), Show("busy"), Show("rises", "dec"))),
    ("State machines (state names from the design)", FSMS),
    ("Receiver: line delay and mid-eye sampling",
     (Show("locked"), Show("sampler.sample"), Show("delay", "dec"), Show("slots", "dec"),
      Show("start_slot", "dec"))),
    ("Results", (Show("done"), Show("valid"), Show("status"), Show("word0_position"),
                 Show("word1_position"), Show("word0_crc_ok"), Show("word1_crc_ok"),
                 Show("lc", "dec"), Show("line_delay", "dec"))),
)

#: The window and layout (the save file's [size]); GTKWave's zoom z shows ZOOM_UNIT * 2**-z
#: time units per pixel of the wave pane, which is what the signal tree (SST), the signal names
#: and the scroll bar leave of the width (both measured with GTKWave 3.3.118). Only the view of
#: an interactive session depends on them: the PNG's window is set in grab.tcl.
SIZE = (1600, 950)
SST_AND_MARGINS = 400
ZOOM_UNIT = 0.005
#: The signal pane (the save file's [signals_width]) is made as wide as its longest line: the
#: name column (names and group labels, right-aligned), then "=" and the value at the marker,
#: in GTKWave's fixed-width font of CHAR_PX pixels a character, after LEFT_PX and with SLACK_PX
#: to spare; never narrower than MIN_SIGNALS_WIDTH. Measured on the PNG (GTKWave 3.3.118, xvfb).
CHAR_PX = 8
LEFT_PX = 4
SLACK_PX = 16
MIN_SIGNALS_WIDTH = 300
#: The wave pane's font: CHAR_PX of a value drawn on its trace.
WAVE_CHAR_PX = 6
#: What the PNG's window leaves of its width besides the signal pane (pane border, scroll bar).
WAVE_MARGINS_PX = 50
#: The time window: PAD_BEFORE of the frame before its first MA fall; after its done strobe,
#: room for the longest value (in the wave pane's font) and SLACK_CHARS characters more, so the
#: frame's results are drawn in full, not cut by the window's right edge.
PAD_BEFORE = 1 / 50
SLACK_CHARS = 3


# -- The dump ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Var:
    scope: tuple
    name: str
    width: int
    code: str
    range: str

    @property
    def gtkwave_name(self):
        """How GTKWave names it in a save file: scopes, name, then the bit range if any."""
        return ".".join((*self.scope, self.name)) + self.range


def _vcd_lines(dump):
    """The dump as VCD text lines (FST through GTKWave's fst2vcd), and the process to stop."""
    if str(dump).endswith(".vcd"):
        return open(dump), None
    proc = subprocess.Popen(["fst2vcd", str(dump)], stdout=subprocess.PIPE, text=True,
                            errors="replace")
    return proc.stdout, proc


def read_header(dump):
    """Every variable of the dump, and its timescale."""
    lines, proc = _vcd_lines(dump)
    scope, found, timescale, in_ts = [], [], "", False
    try:
        for line in lines:
            tok = line.split()
            if not tok:
                continue
            if tok[0] == "$scope":
                scope.append(tok[2])
            elif tok[0] == "$upscope":
                scope.pop()
            elif tok[0] == "$var":
                rng = tok[5] if len(tok) > 6 and tok[5] != "$end" else ""
                found.append(Var(tuple(scope), tok[4], int(tok[2]), tok[3], rng))
            elif tok[0] == "$timescale":
                in_ts = True
                timescale += " ".join(t for t in tok[1:] if t != "$end")
                in_ts = "$end" not in tok
            elif in_ts:
                timescale += " ".join(t for t in tok if t != "$end")
                in_ts = "$end" not in tok
            elif tok[0] == "$enddefinitions":
                break
    finally:
        _close(lines, proc)
    return found, timescale.strip()


def _close(lines, proc):
    if proc is not None:
        proc.kill()
        proc.wait()
    lines.close()


def find(variables, name):
    """The variable ``name`` (a name, or its tail with scopes): outside the simulator's own
    ``$`` scopes, the shallowest first. None when the dump has none."""
    want = tuple(name.split("."))
    hits = [v for v in variables if (*v.scope, v.name)[-len(want):] == want]
    hits.sort(key=lambda v: (any(s.startswith("$") for s in v.scope), len(v.scope)))
    return hits[0] if hits else None


def frame_window(dump, variables, frame=1):
    """(start, end) dump times of frame ``frame`` (1 = first): from the first MA fall after the
    previous ``done`` strobe (MA idles high; a cycle starts by pulling it low) to its ``done``.
    Neither ``start`` nor ``busy`` would do: periodic cycles need no start pulse, and ``busy``
    is already high in the break after reset."""
    ma, done = find(variables, "ma"), find(variables, "done")
    if ma is None or done is None:
        raise SystemExit(f"waves: {dump} has no ma/done signal")
    lines, proc = _vcd_lines(dump)
    now, dones, start, level = 0, 0, None, {}
    try:
        for line in lines:
            if line.startswith("#"):
                now = int(line[1:])
                continue
            if line[:1] not in "01xzXZ":
                continue
            code, value = line[1:].strip(), line[0]
            if code not in (ma.code, done.code) or level.get(code) == value:
                continue
            edge = level.get(code) == "1" and value == "0", level.get(code) == "0" and value == "1"
            level[code] = value
            if code == ma.code and edge[0] and start is None:
                start = now
            elif code == done.code and edge[1]:
                dones += 1
                if dones == frame and start is not None:
                    return start, now
                start = None
    finally:
        _close(lines, proc)
    raise SystemExit(f"waves: {dump} has fewer than {frame} complete frames")


# -- The save file ----------------------------------------------------------------------------

def traces(variables, fsms, warn):
    """[(group label, [(Var, fmt, filter Names or None)])] for VIEW, found in the dump."""
    status = wavenames.status_names()
    groups = []
    for label, shows in VIEW:
        rows = []
        if shows is FSMS:
            for n in fsms:
                var = find(variables, n.dotted)
                if var is None:
                    warn(f"FSM {n.dotted} is not in the dump (is the Verilog up to date?)")
                else:
                    rows.append((var, "hex", n))
        else:
            for show in shows:
                var = find(variables, show.name)
                if var is None:
                    warn(f"{show.name} is not in the dump")
                    continue
                names = status if show.name.split(".")[-1] in STATUS_SIGNALS else None
                rows.append((var, "hex" if names else show.fmt, names))
        groups.append((label, rows))
    return groups


def alias(var, names):
    """The name a trace is saved under: a filtered FSM by its place in the design."""
    return ".".join(names.path + (var.name,)) if names is not None and names.path else None


def shown_name(var, names):
    """The name GTKWave shows in the signal pane: the last part of the alias or full name."""
    return (alias(var, names) or var.gtkwave_name).split(".")[-1]


def value_chars(var, fmt, names):
    """The most characters a value of the trace takes: its longest state name, or the digits
    of its widest value in the trace's radix."""
    if names is not None:
        return max([len(n) for n in names.states.values()] + [-(-var.width // 4)])
    if fmt == "dec":
        return len(str(2 ** var.width - 1))
    return max(1, -(-var.width // 4))


def signals_width(groups):
    """[signals_width] for ``groups``: the longest name or label, "=" and the longest value."""
    rows = [row for _, rows in groups for row in rows]
    names = [len(label) for label, _ in groups] + [len(shown_name(v, n)) for v, _, n in rows]
    values = [value_chars(*row) for row in rows] or [1]
    width = LEFT_PX + CHAR_PX * (max(names) + 1 + max(values)) + SLACK_PX
    return max(MIN_SIGNALS_WIDTH, width)


def view(frame, groups):
    """The time window (start, end) shown for ``frame`` (its first MA fall, its done strobe):
    PAD_BEFORE of the frame before it; after it, the wave pane's pixels for the longest value
    (plus SLACK_CHARS), converted to time at the scale the window itself sets."""
    start, end = frame
    before = int((end - start) * PAD_BEFORE)
    rows = [row for _, rows in groups for row in rows]
    text_px = WAVE_CHAR_PX * (max([value_chars(*row) for row in rows] or [1]) + SLACK_CHARS)
    wave_px = SIZE[0] - signals_width(groups) - WAVE_MARGINS_PX
    # The span s holds the frame, the pad and the text: s = core + s * text_px / wave_px.
    core = end - start + before
    span = core / (1 - text_px / wave_px)
    return max(0, start - before), end + math.ceil(span - core)


def write_savefile(path, dump, groups, filters, window, marker=None):
    """The GTKWave save file: the traces, each FSM and status through its filter, opened on
    ``window`` (start, end); the primary marker at ``marker`` (the values the signal pane
    shows), if given."""
    start, end = window
    width = signals_width(groups)
    wave_px = SIZE[0] - width - SST_AND_MARGINS
    zoom = -math.log2((end - start) / (wave_px * ZOOM_UNIT))
    with open(path, "w") as f:
        save = GTKWSave(f)
        save.comment("Written by scripts/waves.py (make waves): signals found by name in the dump,",
                     "FSM states and status named through translate filter files from the design.")
        save.dumpfile(str(dump))
        save.savefile(str(path))
        save.timestart(start)
        save.size(*SIZE)
        save.pos(-1, -1)
        save.zoom_markers(zoom, start if marker is None else marker)
        save.signals_width(width)
        save.sst_expanded(True)
        for label, rows in groups:
            save.blank(label)
            for var, fmt, names in rows:
                save.trace(var.gtkwave_name, alias=alias(var, names), datafmt=fmt,
                           translate_filter_file=str(filters[names.dotted]) if names else None)


def render(dump, savefile, png, window, marker=None):
    """Headless GTKWave: the save file's view of ``window``, the marker at ``marker``, grabbed
    to ``png``."""
    env = dict(os.environ, BISS_WAVES_PNG=str(Path(png).resolve()),
               BISS_WAVES_FROM=str(window[0]), BISS_WAVES_TO=str(window[1]))
    if marker is not None:
        env["BISS_WAVES_MARKER"] = str(marker)
    log = OUT / "gtkwave.log"
    with open(log, "w") as f:
        r = subprocess.run(
            ["xvfb-run", "-a", "-s", f"-screen 0 {SIZE[0] + 10}x{SIZE[1] + 60}x24",
             "gtkwave", "--rcvar", "hide_sst on", "--rcvar", "splash_disable on",
             "-S", str(Path(__file__).resolve().parent / "grab.tcl"), str(dump), str(savefile)],
            env=env, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0 or not Path(png).exists():
        raise SystemExit(f"waves: GTKWave failed (exit {r.returncode}); see {log}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dump", help="the simulation's dump.fst (or .vcd)")
    ap.add_argument("--frame", type=int, default=1, help="the frame to open on (1 = first)")
    ap.add_argument("--png", help="also render the view to this PNG (headless GTKWave)")
    ap.add_argument("-o", "--out", default=str(OUT / "biss_master.gtkw"))
    args = ap.parse_args(argv)
    dump = Path(args.dump).resolve()

    variables, timescale = read_header(dump)
    fsms = wavenames.fsm_names()
    names = [*fsms, wavenames.status_names()]
    filters = {n.dotted: path for n, path in wavenames.write_filters(OUT / "filters", names)}
    groups = traces(variables, fsms, lambda msg: print(f"waves: warning: {msg}", file=sys.stderr))
    frame = frame_window(dump, variables, args.frame)
    window = view(frame, groups)
    marker = frame[1]           # the frame's done strobe: the signal pane shows its results
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_savefile(out, dump, groups, filters, window, marker)
    print(f"waves: {out.relative_to(ROOT) if out.is_relative_to(ROOT) else out}: "
          f"{sum(len(r) for _, r in groups)} traces, {len(fsms)} FSMs named, "
          f"frame {args.frame} at {frame[0]}..{frame[1]}, shown {window[0]}..{window[1]}, "
          f"marker at its done ({timescale})")
    if args.png:
        render(dump, out, args.png, window, marker)
        print(f"waves: {args.png}")
    print(f"open it:  gtkwave {dump} {out}")


if __name__ == "__main__":
    main()
