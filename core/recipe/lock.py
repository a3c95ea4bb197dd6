"""``recipe.lock.yaml``: the fully resolved recipe plus the plugin versions that ran it.

Resuming a run re-reads this file, so a run continues with exactly the settings it started
with even if the packaged defaults changed in between.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import yaml

import retarget
from retarget.recipe.resolve import ResolvedRecipe


def lock_data(resolved: ResolvedRecipe) -> dict[str, Any]:
    data = resolved.to_dict()
    data["_lock"] = {
        "retarget_version": retarget.__version__,
        "source": resolved.source.path,
        "overrides": dict(resolved.source.overrides),
        "plugins": {
            path: {
                "kind": c.entry.kind,
                "name": c.entry.name,
                "distribution": c.entry.distribution,
                "version": c.entry.version,
            }
            for path, c in resolved.components.items()
        },
    }
    return data


def write_lock(resolved: ResolvedRecipe, directory: str | Path) -> Path:
    """Write ``recipe.lock.yaml`` atomically into ``directory`` and return its path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    target = directory / "recipe.lock.yaml"
    data = lock_data(resolved)
    _keep_provenance(data, target, resolved)
    text = yaml.safe_dump(data, sort_keys=False)
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".recipe.lock.", suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8") as handle:
        handle.write(text)
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(tmp, target)
    return target


def _keep_provenance(data: dict[str, Any], target: Path, resolved: ResolvedRecipe) -> None:
    """A lock written again from itself (``train --resume``) keeps where the run came from:
    its first source and overrides, with the resume's own overrides added, not the lock's path."""
    source = resolved.source.path
    if source is None or not target.is_file() or Path(source).resolve() != target.resolve():
        return
    try:
        before = (yaml.safe_load(target.read_text(encoding="utf-8")) or {}).get("_lock") or {}
    except (OSError, yaml.YAMLError):
        return
    if not isinstance(before, dict) or "source" not in before:
        return
    data["_lock"]["source"] = before["source"]
    overrides = before.get("overrides") if isinstance(before.get("overrides"), dict) else {}
    data["_lock"]["overrides"] = {**overrides, **data["_lock"]["overrides"]}
