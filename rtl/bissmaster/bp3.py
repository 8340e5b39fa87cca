"""Thin re-export, kept so that ``bissmaster.bp3`` stays the public name: the module lives in
:mod:`bissmaster.host.bp3` (host-side software, no hardware). Import from either; new code
inside the package uses the ``host`` path."""

from .host.bp3 import *  # noqa: F401,F403  (the public names, __all__ below)
from .host.bp3 import __all__  # noqa: F401
