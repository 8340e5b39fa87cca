"""Names for numbers in the waveform: every FSM's states and the ``Status`` codes, from the design.

GTKWave shows a state register as a number. A *translate filter file* (lines ``VALUE NAME``, the
value written as GTKWave prints it in the trace's radix) makes it show names instead. The names
are taken from the elaborated design, never typed in: each ``m.FSM`` of ``BissMaster`` gives its
state signal (``<name>_state``, with a decoder that Amaranth attaches: ``decoder(n)`` is
``"STATE/n"``), wherever it sits in the hierarchy, and ``bissmaster.params.Status`` gives the
status codes (an ``IntEnum`` or an ``amaranth.lib.enum.Enum``: both iterate as members with
``.name`` and ``.value``).

    python scripts/wavenames.py [-o sim_build/waves/filters]   # writes one .txt per filter
"""

import argparse
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: GTKWave's default radix; the filter values are written in it (traces are saved as hex).
RADIX = "hex"


@dataclass(frozen=True)
class Names:
    """One translate filter: the signal it is for and ``{value: name}``.

    ``path`` is the signal's place in the design (submodule names from the top, as in the
    generated Verilog's instance names), ``signal`` its name; ``path`` is empty for filters that
    are not tied to one signal (an enum)."""
    kind: str                   # "fsm" or "enum"
    path: tuple
    signal: str
    width: int
    states: dict

    @property
    def dotted(self):
        return ".".join((*self.path, self.signal))

    def filter_text(self):
        """The translate filter file: one ``VALUE NAME`` line per state, VALUE in RADIX."""
        digits = max(1, -(-self.width // 4))
        lines = [f"# {self.kind} {self.dotted}: written by scripts/wavenames.py from the design"]
        lines += [f"{value:0{digits}x} {name}" for value, name in sorted(self.states.items())]
        return "\n".join(lines) + "\n"


def _signals_in(statements):
    """Every signal a statement list assigns to or switches on (FSM state registers are both)."""
    for stmt in statements:
        if hasattr(stmt, "cases"):             # Switch: the test, then every case's body
            yield stmt.test
            for case in stmt.cases:
                yield from _signals_in(case[1])
        elif hasattr(stmt, "lhs"):              # Assign
            yield stmt.lhs


def _fragments(fragment, path=()):
    """(path, fragment) for the fragment and every subfragment below it."""
    yield path, fragment
    for index, (sub, name, *_) in enumerate(fragment.subfragments):
        yield from _fragments(sub, (*path, name if name is not None else f"U${index}"))


def fsm_names(dut=None):
    """A Names for every FSM of the elaborated design (default: ``BissMaster(MasterParams())``).

    An FSM's state signal is recognised by the decoder Amaranth gives it: a callable (an enum
    shape's decoder is the enum class), whose result for a state's code is ``"NAME/code"``."""
    from amaranth.hdl import Fragment, Signal
    if dut is None:
        from bissmaster.master import BissMaster
        from bissmaster.params import MasterParams
        dut = BissMaster(MasterParams())
    found = {}
    for path, fragment in _fragments(Fragment.get(dut, None)):
        for statements in getattr(fragment, "statements", {}).values():
            for sig in _signals_in(statements):
                decoder = sig.decoder if isinstance(sig, Signal) else None
                if decoder is None or isinstance(decoder, type) or (path, sig.name) in found:
                    continue
                states = {}
                for code in range(1 << len(sig)):
                    try:
                        states[code] = decoder(code).rsplit("/", 1)[0]
                    except (KeyError, IndexError):  # a code no state has
                        pass
                found[(path, sig.name)] = Names("fsm", path, sig.name, len(sig), states)
    return list(found.values())


def enum_names(enum, width=None):
    """A Names for an enum: ``for member in enum`` works for IntEnum and Amaranth enums."""
    if width is None:
        try:                                    # amaranth.lib.enum.Enum: the shape's width
            from amaranth.hdl import Shape
            width = Shape.cast(enum).width
        except TypeError:
            width = max(m.value for m in enum).bit_length()
    return Names("enum", (), enum.__name__, width, {int(m.value): m.name for m in enum})


def status_names():
    """The ``Status`` codes, at the width of the core's status port."""
    from bissmaster import params
    return enum_names(params.Status, getattr(params, "STATUS_WIDTH", None))


def write_filters(folder, names):
    """Write one ``<kind>.<dotted name>.txt`` per Names into folder; returns [(Names, path)]."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for n in names:
        path = folder / f"{n.kind}.{n.dotted}.txt"
        path.write_text(n.filter_text())
        written.append((n, path.resolve()))
    return written


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default=str(ROOT / "sim_build" / "waves" / "filters"))
    args = ap.parse_args(argv)
    for n, path in write_filters(args.out, [*fsm_names(), status_names()]):
        print(f"{path}: {n.dotted}, {len(n.states)} names")


if __name__ == "__main__":
    main()
