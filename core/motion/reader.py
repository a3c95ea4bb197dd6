"""What the motion layer needs of a file reader: the clip-reader protocol.

The motion-format plugins (:class:`retarget.kinds.MotionFormat`) are readers; the motion
layer reads files through any object of this shape, so it knows nothing of plugins and is
handed the invocation's formats (``Registry.motion_formats()``) by its caller.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip


@runtime_checkable
class ClipReader(Protocol):
    """Reads one kind of motion file into a canonical clip.

    ``suffixes`` pick the reader for a file, ``accepts`` decides among readers sharing a
    suffix, ``config`` (a pydantic model) is part of the clip cache's key, and a reader with
    ``cacheable`` true has clips that depend only on the file's bytes and that config."""

    suffixes: Sequence[str]
    cacheable: bool
    config: Any

    def read(self, path: Path) -> MotionClip: ...

    def accepts(self, path: Path) -> bool: ...
