"""The Makefile's SIM check: every target that SIM reaches rejects an unknown simulator in one
line, before anything runs (make -n: nothing is built or simulated), and accepts the known ones.

Fast: make only reads the Makefile (about 0.1 s a call).
"""

import os
import re
import subprocess

import pytest

from sim.shared import runner

from testkit import REPO as ROOT



def make(*args, env_sim=None):
    """make in the repository, without what an outer make (make test) passes down: its
    MAKEFLAGS carry its command line's variables (SIM=...), which would override these."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL", "MAKEOVERRIDES", "SIM")}
    if env_sim is not None:
        env["SIM"] = env_sim
    return subprocess.run(["make", "--no-print-directory", "-C", str(ROOT), *args],
                          capture_output=True, text=True, timeout=60, env=env)


def makefile_var(name):
    run = make("--eval", f"print-var: ; @echo $({name})", "print-var")
    assert run.returncode == 0, run.stderr
    return run.stdout.split()


def sim_targets():
    """The targets whose recipe uses $(SIM) or $(SIM_TESTS) (whose pytest reads SIM from the
    environment), and every target that depends on one of them."""
    rules, target = {}, None
    for line in (ROOT / "Makefile").read_text().splitlines():
        m = re.match(r"^([a-z0-9-]+):(?!=)([^#]*)", line)
        if m:
            target = m.group(1)
            deps = m.group(2).split("##")[0].split()
            rules.setdefault(target, [set(deps), ""])
        elif line.startswith("\t") and target:
            rules[target][1] += line
        elif not line.strip().startswith("#"):
            target = None
    uses = {t for t, (_, recipe) in rules.items()
            if "$(SIM)" in recipe or "$(SIM_TESTS)" in recipe}
    while True:
        more = {t for t, (deps, _) in rules.items() if deps & uses} - uses
        if not more:
            return uses
        uses |= more


def test_the_makefile_knows_the_runners_simulators():
    assert makefile_var("SIMULATORS") == list(runner.SIMULATORS)


def test_every_target_sim_reaches_is_checked():
    targets = sim_targets()
    assert {"sim", "demo", "demo-bp3", "waves", "test"} <= targets     # the parser finds them
    assert targets == set(makefile_var("SIM_GOALS"))


@pytest.mark.parametrize("sim", ["foo", "", "verilator icarus"])
def test_an_unknown_simulator_is_rejected_in_one_line(sim):
    for target in makefile_var("SIM_GOALS"):
        run = make("-n", target, f"SIM={sim}")
        assert run.returncode != 0, target
        assert run.stdout == "", f"{target}: something ran before the check"
        lines = run.stderr.splitlines()
        assert len(lines) == 1 and f"SIM={sim} is not a simulator" in lines[0], run.stderr


def test_an_unknown_simulator_from_the_environment_is_rejected():
    run = make("-n", "sim", env_sim="foo")
    assert run.returncode != 0 and "SIM=foo is not a simulator" in run.stderr


@pytest.mark.parametrize("sim", runner.SIMULATORS)
def test_a_known_simulator_is_accepted(sim):
    for target in makefile_var("SIM_GOALS"):
        run = make("-n", target, f"SIM={sim}")
        assert run.returncode == 0, (target, run.stderr)


def test_targets_without_sim_ignore_it():
    assert make("-n", "help", "SIM=foo").returncode == 0
