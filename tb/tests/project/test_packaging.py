"""`pip install .`: the wheel built from pyproject.toml holds the whole `bissmaster` package
(the RTL source and the host-side modules), the `bissmaster-generate` and `bissmaster` entry
points and the pinned Amaranth, and the package runs from the wheel alone.

Offline: the wheel is built with the venv's setuptools (`--no-build-isolation --no-index`),
from a copy of the files pyproject.toml names, so nothing is written into the checkout.
About 5 s: one wheel build and two small Verilog conversions.
"""

import configparser
import os
import shutil
import subprocess
import sys
import zipfile
from importlib import metadata
from pathlib import Path

import pytest

import bissmaster

from testkit import REPO as ROOT
PACKAGE = ROOT / "rtl" / "bissmaster"


def _requirement(name):
    """The line of requirements.txt that pins ``name``."""
    for line in (ROOT / "requirements.txt").read_text().splitlines():
        if line.split("[")[0].split("==")[0].strip() == name:
            return line.strip()
    raise AssertionError(f"requirements.txt pins no {name}")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    shutil.copytree(PACKAGE, src / "rtl" / "bissmaster",
                    ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path_factory.mktemp("wheel")
    run = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
         "--no-index", "-q", "-w", str(out)],
        capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, (
        "pip wheel failed; the venv needs setuptools >= 70.1 (requirements.txt pins it: "
        "`make setup`)\n" + run.stdout + run.stderr)
    wheels = list(out.glob("bissmaster-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def _dist_info(whl, name):
    with zipfile.ZipFile(whl) as z:
        (path,) = [n for n in z.namelist() if n.endswith(f".dist-info/{name}")]
        return z.read(path).decode()


def test_setuptools_builds_wheels_by_itself():
    # setuptools < 70.1 has no bdist_wheel of its own: `pip wheel --no-build-isolation` then
    # fails with "invalid command 'bdist_wheel'" (the Python 3.11 venv default is 65.5).
    assert _requirement("setuptools") == f"setuptools=={metadata.version('setuptools')}"
    major, minor = (int(x) for x in metadata.version("setuptools").split(".")[:2])
    assert (major, minor) >= (70, 1)


def test_wheel_holds_every_module_of_the_package_and_nothing_else(wheel):
    with zipfile.ZipFile(wheel) as z:
        names = [n for n in z.namelist() if ".dist-info/" not in n]
    expected = {p.relative_to(PACKAGE.parent).as_posix()
                for p in [*PACKAGE.rglob("*.py"), *PACKAGE.rglob("*.rdl")]}
    assert set(names) == expected
    assert {"bissmaster/generate.py", "bissmaster/master.py", "bissmaster/bp3.py",
            "bissmaster/control_crc.py", "bissmaster/__init__.py", "bissmaster/core/ma_clock.py",
            "bissmaster/control/crc4.py", "bissmaster/bus/bus_top.py",
            "bissmaster/bus/biss_master.rdl", "bissmaster/host/bp3.py"} <= expected


def test_wheel_metadata_version_and_pinned_amaranth(wheel):
    meta = _dist_info(wheel, "METADATA")
    assert f"\nVersion: {bissmaster.__version__}\n" in meta
    assert wheel.name.startswith(f"bissmaster-{bissmaster.__version__}-py3-none-any")
    requires = [line.split(":", 1)[1].strip() for line in meta.splitlines()
                if line.startswith("Requires-Dist:")]
    assert requires == [_requirement("amaranth"),      # the same pins as the venv
                        f"{_requirement('systemrdl-compiler')}; extra == \"bus\"",
                        f"{_requirement('amaranth-boards')}; extra == \"boards\"",
                        f"{_requirement('systemrdl-compiler')}; extra == \"boards\"",
                        f"{_requirement('pyserial')}; extra == \"host\"",
                        f"{_requirement('matplotlib')}; extra == \"host\""]


def test_wheel_declares_the_console_script(wheel):
    entry = configparser.ConfigParser()
    entry.read_string(_dist_info(wheel, "entry_points.txt"))
    assert dict(entry["console_scripts"]) == {"bissmaster-generate": "bissmaster.generate:main",
                                              "bissmaster": "bissmaster.host.cli:main"}


def test_console_script_function_matches_python_m(wheel, tmp_path):
    entry = configparser.ConfigParser()
    entry.read_string(_dist_info(wheel, "entry_points.txt"))
    script = metadata.EntryPoint("bissmaster-generate",
                                 entry["console_scripts"]["bissmaster-generate"],
                                 "console_scripts").load()
    in_process = tmp_path / "entry.v"
    script(["--preset", "biss-c-lean", "-o", str(in_process)])

    # `python -m bissmaster.generate` with the package taken from the wheel (a pure wheel is a
    # zip that Python imports from): the wheel runs without the checkout.
    env = dict(os.environ, PYTHONPATH=str(wheel))
    where = subprocess.run([sys.executable, "-c", "import bissmaster; print(bissmaster.__file__)"],
                           env=env, capture_output=True, text=True, check=True).stdout
    assert where.strip().startswith(str(wheel))
    from_wheel = tmp_path / "wheel.v"
    subprocess.run([sys.executable, "-m", "bissmaster.generate", "--preset", "biss-c-lean",
                    "-o", str(from_wheel)], env=env, check=True, timeout=120)
    text = in_process.read_text()
    assert text == from_wheel.read_text()
    assert "module biss_master(" in text and "counter_width   = 0 (no counters)" in text


def test_host_side_modules_import_from_the_wheel(wheel):
    env = dict(os.environ, PYTHONPATH=str(wheel))
    code = ("import bissmaster.bp3, bissmaster.control_crc, bissmaster.protocol, sys; "
            "print(bissmaster.bp3.__file__)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout
    assert out.strip().startswith(str(wheel))


def test_bus_top_from_the_wheel_is_the_committed_one(wheel, tmp_path):
    """The register map ships in the wheel: with the ``bus`` extra's systemrdl-compiler (the
    venv has it), ``--top axil`` from the wheel alone gives the committed Verilog."""
    env = dict(os.environ, PYTHONPATH=str(wheel))
    out = tmp_path / "axil.v"
    subprocess.run([sys.executable, "-m", "bissmaster.generate", "--top", "axil", "-o", str(out)],
                   env=env, check=True, timeout=300, cwd=tmp_path)
    assert out.read_text() == (ROOT / "rtl" / "generated" / "biss_master_axil.v").read_text()


def test_bus_top_without_systemrdl_is_one_clear_line(wheel, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(wheel))
    code = ("import sys; sys.modules['systemrdl'] = None; "     # as if it were not installed
            "from bissmaster.generate import main; main(['--top', 'wb', '-o', 'x.v'])")
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         cwd=tmp_path, timeout=120)
    assert run.returncode == 2 and run.stdout == ""
    last = run.stderr.strip().splitlines()[-1]
    assert "Traceback" not in run.stderr and not (tmp_path / "x.v").exists()
    assert last == ("bissmaster-generate: error: --top wb reads the register map with "
                    "systemrdl-compiler, which is not installed: pip install 'bissmaster[bus]'")


def test_help_says_what_the_bus_tops_need():
    from bissmaster.generate import _parser
    text = " ".join(_parser()[0].format_help().split())
    assert "need pip install 'bissmaster[bus]'" in text
