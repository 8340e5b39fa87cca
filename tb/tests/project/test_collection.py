"""Every test file is collected: pytest skips some folder names by default (``build``, ``dist``,
``venv``, ...), and a folder of tests under such a name would silently never run. It did once:
``tb/tests/build/`` held 90 tests that ``make test`` did not see, hence ``project/``."""

import subprocess
import sys

from testkit import REPO


def test_every_test_file_under_tb_tests_is_collected():
    files = {p.relative_to(REPO).as_posix() for p in (REPO / "tb" / "tests").rglob("test_*.py")}
    run = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                          "-p", "no:cacheprovider", "tb/tests"],
                         cwd=REPO, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    collected = {line.split("::", 1)[0] for line in run.stdout.splitlines() if "::" in line}
    assert files - collected == set()
    assert len(files) > 40
