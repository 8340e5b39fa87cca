import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
for d in ("sim", "tb", "rtl"):
    if str(ROOT / d) not in sys.path:
        sys.path.insert(0, str(ROOT / d))
