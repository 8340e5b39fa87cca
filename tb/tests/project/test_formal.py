"""The fast slice of the formal checks (tb/formal): Yosys SMT flow + Yices, about two minutes.

Each test builds one Amaranth harness around the real RTL, writes SMT-LIB 2 with YoWASP Yosys
and runs yosys-smtbmc: a k-induction proof, a BMC run, a cover run (the properties are not
vacuous) or a mutation run (a weakened harness must produce a counterexample). The whole set,
with the deeper runs, is ``make formal``; tb/formal/README.md says what each check proves.
"""

import pytest

from formal.run import CHECKS, run_check

FAST = [c for c in CHECKS if c.fast]


@pytest.mark.parametrize("check", FAST, ids=[f"{c.name}-{c.method}" for c in FAST])
def test_formal(check):
    outcome = run_check(check)
    assert outcome.ok, (f"{check.name} ({check.method}, depth {check.depth}): {outcome.result}"
                        f" {outcome.detail}; logs and traces in sim_build/formal/")


def test_access_frame_bound_is_the_documented_one():
    """The harness's bound (written from docs/control.md) and the engine's own
    ``frame_bound`` give the same numbers: the proof is of the contract the RTL states."""
    from bissmaster.control.register_access import frame_bound
    from formal.harnesses import access_frame_bound

    # The docs' table: one and 64 registers, default wait.
    assert [access_frame_bound(n, 16, w) for n in (1, 64) for w in (True, False)] == \
        [60, 65, 942, 1955]
    for wait in (1, 2, 16, 255):
        for count in range(1, 65):
            for write in (False, True):
                assert access_frame_bound(count, wait, write) == frame_bound(count, wait, write)
