"""What tests share: the repository, the shared motion-capture clips, state comparison."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SHARED_MOCAP = Path(
    os.environ.get("RETARGET_SHARED_DATA", str(REPO.parent / "shared" / "data" / "mocap"))
)


def assert_state_equal(a: Any, b: Any, where: str = "state") -> None:
    """Bit-for-bit equality of nested checkpoint states (tensors, arrays, dicts, lists),
    naming the first differing entry."""
    import torch

    if isinstance(a, torch.Tensor):
        assert torch.equal(a, b), where
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            assert_state_equal(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_state_equal(x, y, f"{where}[{i}]")
    elif hasattr(a, "shape"):  # numpy arrays inside env state
        assert (a == b).all(), where
    else:
        assert a == b, where
