"""Citations of the protocol point inside the repository (issue 25).

Code, tests and docs cite ``docs/protocol.md, section N`` (the protocol facts in our words, with
their sources). A citation of a file outside the repository, or of a section that page does not
have, fails here.
"""

import re
import subprocess

from testkit import REPO

PROTOCOL = REPO / "docs" / "protocol.md"
#: "docs/protocol.md, section 6", "... sections 2, 4 and 9", "... section 5.2".
CITE = re.compile(r"docs/protocol\.md`{0,2},? sections? "
                  r"(\d+(?:\.\d)?\b(?:(?:, | and )\d+(?:\.\d)?\b)*)")


def _tracked_text_files():
    names = subprocess.run(["git", "ls-files", "*.py", "*.md", "*.c", "*.h", "Makefile", "*.core",
                            "*.toml", "*.txt", "*.rdl", "*.sh"], cwd=REPO, capture_output=True,
                           text=True, check=True).stdout.split()
    return [REPO / n for n in names if (REPO / n).is_file()]


def _sections():
    return set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", PROTOCOL.read_text(), re.M))


def test_nothing_cites_a_file_outside_the_repository():
    outside = re.compile(r"shared/spec|\.\./shared/|biss-protocol\.md")
    offenders = [f.relative_to(REPO).as_posix() for f in _tracked_text_files()
                 if f.name != "test_citations.py" and outside.search(f.read_text())]
    assert offenders == []


def test_every_cited_section_exists():
    sections = _sections()
    assert {str(n) for n in range(1, 11)} | {"5.1", "5.2"} <= sections
    missing = {}
    for f in _tracked_text_files():
        if f.name == "test_citations.py":       # its own examples
            continue
        for m in CITE.finditer(f.read_text()):
            for n in re.split(r", | and ", m.group(1)):
                if n.rstrip(".") not in sections:
                    missing.setdefault(f.relative_to(REPO).as_posix(), []).append(n)
    assert missing == {}


def test_the_checks_see_a_bad_citation(tmp_path):
    found = CITE.search("see docs/protocol.md, sections 2, 4 and 12 for it").group(1)
    assert re.split(r", | and ", found) == ["2", "4", "12"]
    assert "12" not in _sections()
