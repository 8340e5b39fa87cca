"""biss_master.core, the FuseSoC CAPI2 core of the committed Verilog: FuseSoC finds it under its
VLNV, its version is the package's, every file it names exists, its targets take the core and
the three bus tops (biss_master_axil, biss_master_wb, biss_master_uart), and its lint targets
(`lint`, `lint_axil`, `lint_wb`, `lint_uart`) run Verilator (-Wall, rtl/lint.vlt) clean,
offline, in a temporary build root.

FuseSoC's config, cache and data folders are pointed into the test's temporary folder, so
nothing is written to the user's home or the checkout. About 10 s.
"""

import re
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml
from fusesoc.capi2.coreparser import Core2Parser
from fusesoc.core import Core

import bissmaster
import venvtools

from testkit import REPO as ROOT
CORE_FILE = ROOT / "biss_master.core"
VLNV = f"bissmaster:ip:biss_master:{bissmaster.__version__}"
#: target: (its Verilog, its top-level module); each has a lint target (lint, lint_<target>).
TOPS = {
    "default": ("rtl/generated/biss_master.v", "biss_master"),
    "axil": ("rtl/generated/biss_master_axil.v", "biss_master_axil"),
    "wb": ("rtl/generated/biss_master_wb.v", "biss_master_wb"),
    "uart": ("rtl/generated/biss_master_uart.v", "biss_master_uart"),
}
LINT = {"default": "lint", "axil": "lint_axil", "wb": "lint_wb", "uart": "lint_uart"}


def _fusesoc(tmp_path, *args, cores_root=ROOT):
    env = venvtools.env_with_venv()             # verilator from the venv, first on PATH
    for var in ("XDG_CONFIG_HOME", "XDG_CACHE_HOME", "XDG_DATA_HOME"):
        env[var] = str(tmp_path / var.lower())
    return subprocess.run([venvtools.tool("fusesoc"), "--cores-root", str(cores_root), *args],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)


def _core():
    return Core(Core2Parser(), str(CORE_FILE))


def test_core_list_finds_the_core_by_vlnv(tmp_path):
    run = _fusesoc(tmp_path, "core", "list")
    assert run.returncode == 0, run.stdout + run.stderr
    assert re.search(rf"^{re.escape(VLNV)}\s*:", run.stdout, re.M), run.stdout


def test_core_version_is_the_package_version():
    # The VLNV's version is the second copy of bissmaster.__version__ (CAPI2 has no way to
    # read it from elsewhere): bump both together.
    assert str(_core().name) == VLNV


def test_every_fileset_names_existing_files():
    data = yaml.safe_load(CORE_FILE.read_text().split("\n", 1)[1])
    for name, fileset in data["filesets"].items():
        for entry in fileset["files"]:
            path = entry if isinstance(entry, str) else next(iter(entry))
            assert (ROOT / path).is_file(), f"fileset {name} names {path}, which does not exist"


def test_targets_take_the_committed_verilog():
    core = _core()
    files = {t: [f["name"] for f in core.get_files({"target": t, "is_toplevel": True})]
             for t in ("default", "lint")}
    assert files["default"] == ["rtl/generated/biss_master.v"]
    assert files["lint"] == ["rtl/generated/biss_master.v", "rtl/lint.vlt"]
    for target in files:
        assert core.get_toplevel({"target": target, "is_toplevel": True}) == "biss_master"
    # A design that depends on this core gets the default target's files, whatever its target.
    as_dependency = core.get_files({"target": "lint", "is_toplevel": False})
    assert [f["name"] for f in as_dependency] == files["default"]


@pytest.mark.parametrize("top", ["axil", "wb", "uart"])
def test_bus_top_targets_take_the_committed_bus_top(top):
    core = _core()
    verilog, module = TOPS[top]
    for target, files in ((top, [verilog]), (LINT[top], [verilog, "rtl/lint.vlt"])):
        flags = {"target": target, "is_toplevel": True}
        assert [f["name"] for f in core.get_files(flags)] == files
        assert core.get_toplevel(flags) == module


def test_every_committed_top_has_targets():
    """Each top in rtl/generated/ (the core and every bus top) is some target's top level."""
    tops = {p.stem for p in (ROOT / "rtl" / "generated").glob("biss_master*.v")}
    assert tops == {module for _, module in TOPS.values()}
    targets = set(yaml.safe_load(CORE_FILE.read_text().split("\n", 1)[1])["targets"])
    assert targets == set(TOPS) | set(LINT.values())


@pytest.mark.parametrize("top", TOPS)
def test_lint_target_runs_verilator_clean(tmp_path, top):
    run = _fusesoc(tmp_path, "run", "--build-root", str(tmp_path / "build"),
                   f"--target={LINT[top]}", VLNV)
    assert run.returncode == 0, run.stdout + run.stderr
    (vc,) = (tmp_path / "build").rglob("*.vc")
    options = vc.read_text().split()
    assert "--lint-only" in options and "-Wall" in options
    assert TOPS[top][0].split("/")[-1] in " ".join(options)
    assert f"--top-module {TOPS[top][1]}" in " ".join(options)
    assert "VerilationReport" in run.stdout.replace(" ", "")      # Verilator did run


def test_lint_target_fails_without_the_waivers(tmp_path):
    # The same core with an empty waiver file: -Wall reports Yosys's spelling of the netlist.
    # This shows that the lint target runs with -Wall and that the waivers are what keep it
    # clean, so the clean run above means something.
    root = tmp_path / "root"
    for path in ("biss_master.core", "rtl/generated/biss_master.v", "constraints"):
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        copy = shutil.copytree if (ROOT / path).is_dir() else shutil.copy
        copy(ROOT / path, root / path)
    (root / "rtl" / "lint.vlt").write_text("`verilator_config\n")
    run = _fusesoc(tmp_path, "run", "--build-root", str(tmp_path / "build"), "--target=lint",
                   VLNV, cores_root=root)
    assert run.returncode != 0
    assert "%Warning-" in run.stdout + run.stderr
