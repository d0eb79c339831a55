"""Let the plugin's tests run from a checkout even before ``pip install -e`` (the
entry-point test alone needs the installed distribution, and says so when it is missing)."""

from __future__ import annotations

import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
if str(SRC) not in sys.path:
    sys.path.insert(0, str(SRC))
