"""The package's imports run one way (rtl/bissmaster/*/README.md; issue 25).

The shared definitions (``protocol``, ``params``, ``layouts``) import only each other; the data
channel (``core``) and the control channel (``control``) import the shared definitions and
themselves; ``master`` connects the two; the bus side (``bus``) builds on ``master``; host
software (``host``) imports no hardware at all. Every import of every module is checked,
function-level imports included, by reading the source (nothing is imported here). The board
designs (``boards``) build on the bus top and the generator's presets.
"""

import ast
from pathlib import Path

import pytest

from testkit import REPO

PACKAGE = REPO / "rtl" / "bissmaster"

#: Which layer each module of the package belongs to, by its dotted name below ``bissmaster``.
SHARED = {"protocol", "params", "layouts"}

#: What each layer may import from the package (its own layer always included).
ALLOWED = {
    "shared": {"shared"},
    "core": {"shared", "core"},
    "control": {"shared", "control"},
    "master": {"shared", "core", "control"},
    "bus": {"shared", "master", "bus"},
    "host": {"shared", "host"},
    "generate": {"api", "shared", "master", "bus"},
    # The board designs: the bus top and a preset's parameters, on a board's platform.
    "boards": {"shared", "bus", "generate"},
    # The thin re-exports of the old public names: each may import its new home only.
    "reexport:bp3": {"host"},
    "reexport:control_crc": {"control"},
    "api": set(),       # __init__ imports lazily, by name, and nothing at import time
}


def layer(module):
    """The layer of ``bissmaster[.x[.y]]``."""
    parts = module.split(".")
    assert parts[0] == "bissmaster", module
    if len(parts) == 1 or parts[1] == "__version__":
        return "api"
    head = parts[1]
    if head in SHARED:
        return "shared"
    if head in ("core", "control", "bus", "host", "master", "generate", "boards"):
        return head
    if head in ("bp3", "control_crc"):
        return f"reexport:{head}"
    raise AssertionError(f"module {module} belongs to no layer: add it to test_layering.py")


def module_name(path, root):
    rel = path.relative_to(root.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(path, root):
    """The package modules ``path`` imports, as dotted names (relative imports resolved)."""
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(base + ([node.module] if node.module else []))
            else:
                base = node.module
            for alias in node.names:
                # ``from . import protocol`` names a module; ``from .x import y`` a name in x.
                candidate = f"{base}.{alias.name}"
                as_module = root.parent.joinpath(*candidate.split("."))
                if as_module.with_suffix(".py").exists() or (as_module / "__init__.py").exists():
                    found.add(candidate)
                else:
                    found.add(base)
    return {m for m in found if m.split(".")[0] == root.name}


def violations(root):
    """Every import of the package under ``root`` that runs against :data:`ALLOWED`."""
    bad = []
    for path in sorted(root.rglob("*.py")):
        own = layer(module_name(path, root))
        for target in sorted(imports(path, root)):
            if layer(target) != own and layer(target) not in ALLOWED[own]:
                bad.append(f"{path.relative_to(root.parent)} ({own}) imports {target} "
                           f"({layer(target)})")
    return bad


def test_imports_run_one_way():
    assert violations(PACKAGE) == []


def test_every_module_has_a_layer():
    modules = [module_name(p, PACKAGE) for p in PACKAGE.rglob("*.py")]
    assert len(modules) > 30
    assert {layer(m) for m in modules} >= {"shared", "core", "control", "bus", "host", "master",
                                           "boards"}


def test_each_subpackage_says_what_it_owns_and_may_import():
    for sub in ("core", "control", "bus", "host", "boards"):
        text = (PACKAGE / sub / "README.md").read_text()
        assert "May import" in text and "Never" in text, sub


def _fake_package(tmp_path, files):
    root = tmp_path / "bissmaster"
    for rel, text in {"__init__.py": "", "params.py": "", "protocol.py": "",
                      "core/__init__.py": "", "core/a.py": "", "control/__init__.py": "",
                      "control/b.py": "", "host/__init__.py": "", **files}.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


@pytest.mark.parametrize("rel, source", [
    ("core/a.py", "from ..control.b import X\n"),
    ("core/a.py", "from ..control import b\n"),
    ("core/a.py", "import bissmaster.control.b\n"),
    ("core/a.py", "def f():\n    from ..control.b import X\n"),
    ("host/h.py", "from ..core.a import A\n"),
    ("boards/b.py", "from ..core.a import A\n"),
    ("bus/x.py", "from ..boards import b\n"),
    ("params.py", "from .core import a\n"),
])
def test_a_wrong_way_import_is_found(tmp_path, rel, source):
    assert len(violations(_fake_package(tmp_path, {rel: source}))) == 1


def test_a_right_way_import_passes(tmp_path):
    root = _fake_package(tmp_path, {"core/a.py": "from .. import protocol\nfrom ..params import P\n",
                                    "host/h.py": "from .. import params\n"})
    assert violations(root) == []
