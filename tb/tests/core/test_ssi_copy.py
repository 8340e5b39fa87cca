"""SsiCopyCompare on Amaranth's simulator: an SSI double transmission's copies compared.

Cycle conventions and where expected values come from: ``block_sim.py``. docs/ports.md ("SSI
mode"): the word, one separator bit that must be 0, the word again; any difference, or a
separator of 1, is a mismatch.
"""

import random

import pytest

from bissmaster.core.ssi_copy import SsiCopyCompare

from testkit.block_sim import run_clocks

WIDTH = 55 + 2 + 16     # the default build's longest SSI word


def _run(word, separator, copy, *, gaps=1):
    """The first copy, the separator, the second copy, each bit ``gaps`` clocks apart (no
    strobe between); returns ``mismatch`` after the last bit."""
    n = len(word)
    steps = []
    for kind, bits in (("first", word), ("separator", [separator]), ("second", copy)):
        for b in bits:
            steps.append({"first": 0, "separator": 0, "second": 0, kind: 1, "bit": b,
                          "index": n - 1})
            steps += [{"first": 0, "separator": 0, "second": 0, "bit": 1 - b}] * (gaps - 1)
    steps.append({"first": 0, "separator": 0, "second": 0})
    trace = run_clocks(SsiCopyCompare(WIDTH), steps, ["mismatch"])
    return trace[-1]["mismatch"]


@pytest.mark.parametrize("n", (1, 13, 25, WIDTH))
def test_ssi_copy_equal_copies_match(n):
    rng = random.Random(n)
    word = [rng.randrange(2) for _ in range(n)]
    assert _run(word, 0, word, gaps=1 + n % 3) == 0


@pytest.mark.parametrize("n", (1, 13, 26, WIDTH))
def test_ssi_copy_every_flipped_bit_and_the_separator_mismatch(n):
    rng = random.Random(100 + n)
    word = [rng.randrange(2) for _ in range(n)]
    assert _run(word, 1, word) == 1
    for k in sorted(rng.sample(range(n), min(n, 8))) + [0, n - 1]:
        copy = list(word)
        copy[k] ^= 1
        assert _run(word, 0, copy) == 1, k
