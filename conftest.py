"""Test order for pytest-xdist (``make test`` runs everything in one session on ``JOBS``
workers): the long items first (the formal checks, then the cocotb simulations and campaigns),
the many short unit tests last, so that they fill the workers' gaps and no worker is left
alone with a long item at the end. It changes the order only, never what runs."""

LONG_FIRST = ("tb/tests/project/test_formal.py", "tb/tests/core/test_limits.py", "sim/")


def pytest_collection_modifyitems(items):
    def rank(item):
        return next((i for i, p in enumerate(LONG_FIRST) if item.nodeid.startswith(p)),
                    len(LONG_FIRST))
    items.sort(key=rank)    # stable: within a rank, the collection order
