"""Paths tests share: the repository and the shared motion-capture clips."""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED_MOCAP = Path(
    os.environ.get("RETARGET_SHARED_DATA", str(REPO.parent / "shared" / "data" / "mocap"))
)
