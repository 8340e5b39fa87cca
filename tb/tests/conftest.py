"""Make ``rtl/`` (for ``bissmaster.protocol``) and ``tb/`` (for ``encoder_model``) importable."""

import sys
from pathlib import Path

_REPO = Path(__file__).resolve().parents[2]
for _path in (_REPO / "rtl", _REPO / "tb"):
    if str(_path) not in sys.path:
        sys.path.insert(0, str(_path))
