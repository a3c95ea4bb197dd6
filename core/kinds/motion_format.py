"""Motion formats: readers that turn a file into a clip on the canonical human skeleton."""

from __future__ import annotations

from abc import abstractmethod
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.base import ConfigT, Plugin

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip


class MotionFormat(Plugin[ConfigT]):
    """Base class of motion readers.

    ``suffixes`` picks the reader for a file (``.bvh``); ``read`` must raise
    :class:`retarget.errors.MotionError` naming the file (and line where it applies) for any
    malformed input, and nothing else. ``write_sample`` writes a small valid file so that the
    contract suite can exercise the reader without shipping data.
    """

    kind: ClassVar[str] = "motion_format"
    suffixes: ClassVar[tuple[str, ...]] = ()
    cacheable: ClassVar[bool] = False
    """True when a read clip depends only on the file's bytes and this reader's config (no
    file beside it, no body model): parsed clips are then cached on disk by content."""

    @abstractmethod
    def read(self, path: Path) -> MotionClip: ...

    def accepts(self, path: Path) -> bool:
        """Whether this reader is the one for ``path`` among the formats sharing its suffix
        (AMASS and position arrays are both ``.npz``): a cheap look inside, never a full
        read. The default takes every file with a matching suffix."""
        return True

    @classmethod
    @abstractmethod
    def write_sample(cls, directory: Path) -> Path:
        """Write a small valid file into ``directory`` and return its path."""
        ...
