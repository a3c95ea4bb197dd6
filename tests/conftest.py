"""Shared test helpers: throw-away installed distributions with entry points."""

from __future__ import annotations

import sys
import textwrap
import uuid
from collections.abc import Callable
from pathlib import Path

import pytest


@pytest.fixture
def make_dist(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Callable[..., str]:
    """Install a fake distribution on ``sys.path``: ``make_dist(name, {ep: source})``.

    Each entry point gets its own uniquely named module with the given source, registered in
    the ``retarget`` entry-point group, exactly as ``pip install`` of a plugin package would.
    Returns the suffix used for module names.
    """
    root = tmp_path / "site"
    root.mkdir(exist_ok=True)
    monkeypatch.syspath_prepend(str(root))
    suffix = uuid.uuid4().hex[:8]

    def make(dist: str, plugins: dict[str, str], version: str = "1.0") -> str:
        lines = ["[retarget]"]
        for ep_name, source in plugins.items():
            module = f"{ep_name}_{suffix}"
            (root / f"{module}.py").write_text(textwrap.dedent(source))
            lines.append(f"{ep_name} = {module}")
        info = root / f"{dist.replace('-', '_')}-{version}.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
        (info / "entry_points.txt").write_text("\n".join(lines) + "\n")
        return suffix

    yield make
    for name in [m for m in sys.modules if m.endswith(f"_{suffix}")]:
        del sys.modules[name]


@pytest.fixture(autouse=True, scope="session")
def _image_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Camera images rendered by tests go to a session folder, not the user's cache."""
    import os

    os.environ.setdefault("RETARGET_CACHE", str(tmp_path_factory.mktemp("retarget-cache")))
