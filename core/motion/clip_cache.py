"""Parsed clips cached on disk by content, so a corpus of thousands of files reads in seconds.

Parsing and mapping a BVH file onto the canonical skeleton costs milliseconds per second of
motion; a 2.5-hour corpus costs most of a minute every run. A clip depends only on the file's
bytes, the reader and its settings, so the parsed clip is stored under the hash of exactly
those (a changed file or setting is a new entry, never a stale one), as an ``.npz`` of plain
arrays and a JSON header: reading one back runs no code (``allow_pickle=False``). Only formats
that declare ``cacheable = True`` (their output depends on nothing but the file and their
config) are cached.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from retarget.motion.clip import MotionClip
from retarget.motion.reader import ClipReader

VERSION = 2
"""Bumped when readers map files differently, so old entries are not reused."""


def clip_cache_dir() -> Path | None:
    """``$RETARGET_CACHE/clips`` (default ``~/.cache/retarget/clips``); ``RETARGET_CACHE=off``
    turns caching off."""
    root = os.environ.get("RETARGET_CACHE", "").strip()
    if root.lower() in ("off", "0", "none"):
        return None
    return (Path(root) if root else Path.home() / ".cache" / "retarget") / "clips"


def clip_key(fmt: ClipReader, data: bytes) -> str:
    """Hash of everything a parsed clip depends on."""
    from retarget import __version__

    kind = type(fmt)
    h = hashlib.sha256()
    h.update(f"v{VERSION} {__version__} {kind.__module__}.{kind.__qualname__} ".encode())
    h.update(fmt.config.model_dump_json().encode())
    h.update(hashlib.sha256(data).digest())
    return h.hexdigest()[:40]


def read_cached(fmt: ClipReader, path: Path, folder: Path | None) -> MotionClip:
    """``fmt.read(path)``, through the cache when ``folder`` is set and ``fmt`` is cacheable."""
    if folder is None or not getattr(fmt, "cacheable", False):
        return fmt.read(path)
    try:
        key = clip_key(fmt, path.read_bytes())
    except OSError:
        return fmt.read(path)  # the reader names the file in its error
    entry = folder / key[:2] / f"{key}.npz"
    if entry.exists():
        clip = _load(entry, path)
        if clip is not None:
            return clip
    clip = fmt.read(path)
    _store(entry, clip)
    return clip


class _Arrays(json.JSONEncoder):
    def default(self, o: Any) -> Any:
        if isinstance(o, np.ndarray):
            return {"__array__": o.tolist(), "dtype": str(o.dtype)}
        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, Path):
            return str(o)
        return super().default(o)


def _arrays_back(obj: dict) -> Any:
    if set(obj) == {"__array__", "dtype"}:
        return np.asarray(obj["__array__"], dtype=obj["dtype"])
    return obj


def _store(entry: Path, clip: MotionClip) -> None:
    """Write the entry atomically; a full disk or an unserialisable ``meta`` skips caching."""
    try:
        header = json.dumps(
            {"fps": clip.fps, "name": clip.name, "skeleton": clip.skeleton, "meta": clip.meta,
             "name_is_stem": clip.source is not None and clip.name == clip.source.stem},
            cls=_Arrays,
        )
    except (TypeError, ValueError):
        return
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=entry.parent, prefix=".clip.", suffix=".npz")
        with os.fdopen(fd, "wb") as handle:
            np.savez(handle, root_pos=clip.root_pos, local_rot=clip.local_rot,
                     offsets=clip.offsets, contacts=clip.contacts,
                     header=np.frombuffer(header.encode(), dtype=np.uint8))  # fmt: skip
        os.replace(tmp, entry)
    except OSError:
        Path(locals().get("tmp", entry.with_suffix(".none"))).unlink(missing_ok=True)


def _load(entry: Path, source: Path) -> MotionClip | None:
    """The cached clip, or None when the entry is unreadable (it is then written anew)."""
    try:
        with np.load(entry, allow_pickle=False) as z:
            header = json.loads(z["header"].tobytes().decode(), object_hook=_arrays_back)
            return MotionClip(
                float(header["fps"]), z["root_pos"], z["local_rot"], z["offsets"],
                contacts=z["contacts"], source=source,
                name=source.stem if header.get("name_is_stem") else str(header["name"]),
                skeleton=str(header["skeleton"]), meta=dict(header["meta"]),
            )  # fmt: skip
    except (OSError, ValueError, KeyError, TypeError, json.JSONDecodeError):
        return None
