"""Motion archives (``.tar.gz``, ``.tgz``, ``.tar``, ``.zip``) read as the folders they hold.

Datasets ship as archives of thousands of clips. Rather than asking every reader to read from
inside a tar stream, an archive is unpacked once into the cache folder under the hash of its
bytes (a changed archive is a new folder, never a stale one) and its motion files are then
ordinary paths. Unpacking trusts nothing in the archive: only regular files with a motion
suffix are written, a member whose path would leave the folder is refused, and the member count
and the bytes written are bounded.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tarfile
import tempfile
import zipfile
from collections.abc import Iterable
from pathlib import Path, PurePosixPath

from retarget.errors import MotionError

SUFFIXES = (".tar.gz", ".tgz", ".tar", ".zip")
MAX_MEMBERS = 200_000
"""Most files unpacked from one archive."""
MAX_BYTES = 16 * 2**30
"""Most bytes unpacked from one archive (16 GiB): more is a mistake, not a motion dataset."""
DONE = ".complete"


def is_archive(path: Path) -> bool:
    name = path.name.lower()
    return path.is_file() and any(name.endswith(s) for s in SUFFIXES)


def archive_dir() -> Path:
    """``$RETARGET_CACHE/archives`` (default ``~/.cache/retarget/archives``)."""
    root = os.environ.get("RETARGET_CACHE", "").strip()
    return (Path(root) if root else Path.home() / ".cache" / "retarget") / "archives"


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(2**20), b""):
            h.update(block)
    return h.hexdigest()


def unpacked(path: Path, suffixes: Iterable[str], *, folder: Path | None = None) -> Path:
    """The folder holding ``path``'s motion files (those ending in ``suffixes``), unpacking
    the archive there on first use; later calls return at once."""
    wanted = tuple(s.lower() for s in suffixes)
    key = hashlib.sha256((file_digest(path) + " " + " ".join(sorted(wanted))).encode())
    target = (folder or archive_dir()) / key.hexdigest()[:32]
    if (target / DONE).exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=".unpack."))
    try:
        if path.name.lower().endswith(".zip"):
            _unzip(path, tmp, wanted)
        else:
            _untar(path, tmp, wanted)
        (tmp / DONE).write_text(str(path.resolve()), encoding="utf-8")
        if target.exists():  # a half-written folder from an interrupted run
            shutil.rmtree(target)
        os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return target


def _safe_name(name: str, archive: Path) -> PurePosixPath:
    p = PurePosixPath(name.replace("\\", "/"))
    if p.is_absolute() or ".." in p.parts or not p.parts:
        raise MotionError(f"archive member '{name}' would be written outside its folder",
                          file=archive)  # fmt: skip
    return p


class _Budget:
    def __init__(self, archive: Path) -> None:
        self.archive, self.members, self.bytes = archive, 0, 0

    def take(self, size: int) -> None:
        self.members += 1
        self.bytes += max(int(size), 0)
        if self.members > MAX_MEMBERS or self.bytes > MAX_BYTES:
            raise MotionError(
                f"archive holds more than {MAX_MEMBERS} motion files or "
                f"{MAX_BYTES / 2**30:.0f} GiB; unpack it yourself and pass the folder",
                file=self.archive,
            )


def _untar(path: Path, out: Path, wanted: tuple[str, ...]) -> None:
    budget = _Budget(path)
    try:
        with tarfile.open(path, "r:*") as tar:
            for member in tar:
                if not member.isfile() or not member.name.lower().endswith(wanted):
                    continue
                name = _safe_name(member.name, path)
                budget.take(member.size)
                source = tar.extractfile(member)
                if source is None:
                    continue
                dest = out.joinpath(*name.parts)
                dest.parent.mkdir(parents=True, exist_ok=True)
                with source, dest.open("wb") as handle:
                    shutil.copyfileobj(source, handle, 2**20)
    except (tarfile.TarError, EOFError, OSError) as exc:
        raise MotionError(f"cannot read archive: {exc}", file=path) from None


def _unzip(path: Path, out: Path, wanted: tuple[str, ...]) -> None:
    budget = _Budget(path)
    try:
        with zipfile.ZipFile(path) as archive:
            for info in archive.infolist():
                if info.is_dir() or not info.filename.lower().endswith(wanted):
                    continue
                name = _safe_name(info.filename, path)
                budget.take(info.file_size)
                dest = out.joinpath(*name.parts)
                dest.parent.mkdir(parents=True, exist_ok=True)
                with archive.open(info) as source, dest.open("wb") as handle:
                    shutil.copyfileobj(source, handle, 2**20)
    except (zipfile.BadZipFile, EOFError, OSError) as exc:
        raise MotionError(f"cannot read archive: {exc}", file=path) from None
