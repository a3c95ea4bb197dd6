"""Where motion data comes from: a path the user gives, ``RETARGET_DATA``, or the default set.

Real datasets are never shipped with the project (licences, size): users point at them with
``--motions DIR``, a recipe field, or the ``RETARGET_DATA`` environment variable (a directory
holding motion files, searched recursively, or an archive of them; archives inside the
directory are read too, see :mod:`retarget.motion.archives`). With none of these, the
generated default set (:mod:`retarget.motion.procedural`) is used. ``include``/``exclude``
name patterns pick files (hold out a whole style: ``exclude: ["*_normal_*"]``), and parsed
clips are cached by content (:mod:`retarget.motion.clip_cache`).
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

from retarget.errors import MotionError
from retarget.motion.archives import is_archive, unpacked
from retarget.motion.clip import MotionClip
from retarget.motion.clip_cache import clip_cache_dir, read_cached
from retarget.motion.reader import ClipReader

ENV_VAR = "RETARGET_DATA"


def resolve_motion_source(
    path: str | Path | None, suffixes: Iterable[str] = (".bvh",)
) -> list[Path] | None:
    """Motion files to read, or ``None`` for the generated default set.

    ``path`` (a file or a directory) wins; else ``$RETARGET_DATA``; else ``None``. A path that
    does not exist, or a directory without any motion file, is a :class:`MotionError`.
    """
    origin = "argument"
    if path is None or str(path) == "":
        env = os.environ.get(ENV_VAR, "").strip()
        if not env:
            return None
        path, origin = env, f"${ENV_VAR}"
    p = Path(path).expanduser()
    wanted = tuple(s.lower() for s in suffixes)
    if p.is_file() and not is_archive(p):
        return [p]
    if not p.exists():
        raise MotionError(f"motion path does not exist ({origin})", file=p)
    found = [p] if p.is_file() else _walk(p)
    files: list[Path] = []
    for f in found:
        if f.suffix.lower() in wanted:
            files.append(f)
        elif is_archive(f):
            inside = unpacked(f, wanted)
            files.extend(g for g in _walk(inside) if g.suffix.lower() in wanted)
    files = sorted(files)
    if not files:
        raise MotionError(
            f"no motion files ({', '.join(wanted)}) under this directory ({origin})", file=p
        )
    return files


def _walk(root: Path) -> list[Path]:
    """Every file under ``root``, following linked folders (a dataset is often a folder of
    links to another disk) but visiting each real folder once, so a link loop ends."""
    seen: set[str] = set()
    out: list[Path] = []
    for folder, dirs, names in os.walk(root, followlinks=True):
        real = os.path.realpath(folder)
        if real in seen:
            dirs[:] = []
            continue
        seen.add(real)
        out.extend(Path(folder) / n for n in names if (Path(folder) / n).is_file())
    return out


def read_file(path: Path, formats: Mapping[str, ClipReader]) -> MotionClip:
    """One motion file read by the format for it, through the clip cache."""
    return read_cached(reader_for(path, formats), path, clip_cache_dir())


def expand(paths: Sequence[str | Path], suffixes: Iterable[str]) -> list[Path]:
    """Files, folders and archives as the motion files they stand for (files as given)."""
    out: list[Path] = []
    for given in paths:
        p = Path(given)
        many = p.is_dir() or is_archive(p)
        out.extend((resolve_motion_source(p, suffixes) or []) if many else [p])
    return out


def reader_for(path: Path, formats: Mapping[str, ClipReader]) -> ClipReader:
    """The motion format whose suffixes match ``path`` (and that accepts it, when several
    share the suffix); the error lists the known suffixes."""
    suffix = path.suffix.lower()
    matching = [f for f in formats.values() if suffix in (s.lower() for s in f.suffixes)]
    for fmt in matching:
        if fmt.accepts(path):
            return fmt
    if matching:  # none recognises the content: the first reads it and says what is wrong
        return matching[0]
    known = sorted({s for f in formats.values() for s in f.suffixes})
    raise MotionError(
        f"no motion format reads '{suffix}' files; known: {', '.join(known)}", file=path
    )


def name_matches(name: str, patterns: Sequence[str]) -> bool:
    """Whether a file name matches one of ``patterns`` (shell patterns, case-insensitive): the
    one rule for picking motion files and for weighting their clips."""
    return any(fnmatch.fnmatch(name.lower(), p.lower()) for p in patterns)


def select(files: Sequence[Path], include: Sequence[str] = (),
           exclude: Sequence[str] = ()) -> list[Path]:  # fmt: skip
    """``files`` whose name matches one of ``include`` (all when empty) and none of
    ``exclude`` (:func:`name_matches`)."""
    picked = [f for f in files if not include or name_matches(f.name, include)]
    return [f for f in picked if not name_matches(f.name, exclude)]


def load_motions(
    path: str | Path | None = None,
    formats: Mapping[str, ClipReader] | None = None,
    *,
    height: float | None = None,
    include: Sequence[str] = (),
    exclude: Sequence[str] = (),
    progress: bool = True,
) -> list[MotionClip]:
    """Clips from ``path`` / ``$RETARGET_DATA`` (only the files ``include``/``exclude``
    select), or the generated default set; a progress bar while many files are parsed.

    ``formats`` are the readers (``Registry.motion_formats()``, or one configured format):
    this layer does not load plugins, the caller hands it the invocation's."""
    named = not (path is None or str(path) == "") or os.environ.get(ENV_VAR, "").strip()
    if named and not formats:
        raise ValueError("load_motions: reading files needs the motion formats: pass "
                         "registry.motion_formats() (registry = retarget.load_plugins())")
    suffixes = [s for f in (formats or {}).values() for s in f.suffixes]
    files = resolve_motion_source(path, suffixes) if named else None
    if files is None:
        from retarget.motion.procedural import default_motions

        return default_motions() if height is None else default_motions(height)
    chosen = select(files, include, exclude)
    if not chosen:
        raise MotionError(
            f"none of {len(files)} motion files matches include={list(include)} "
            f"exclude={list(exclude)}", file=Path(str(path or os.environ.get(ENV_VAR, ""))),
        )  # fmt: skip
    folder = clip_cache_dir()
    if len(chosen) < 50 or not progress:
        return [read_cached(reader_for(f, formats), f, folder) for f in chosen]
    from rich.progress import track

    steps = track(chosen, description="motion files", transient=True)
    return [read_cached(reader_for(f, formats), f, folder) for f in steps]


def read_clip(path: str | Path, *, joints: str | None = None, fps: float | None = None,
              formats: Mapping[str, ClipReader] | None = None) -> MotionClip:  # fmt: skip
    """One motion file read by the format its suffix and content say; ``joints`` (a names
    file) and ``fps`` configure the position-only format for a capture that needs them."""
    path = Path(path)
    if not path.is_file():
        raise MotionError("no such motion file", file=path)
    if not formats:
        raise ValueError("read_clip needs the motion formats (Registry.motion_formats())")
    formats = dict(formats)
    if (joints or fps) and "positions" in formats:
        cls = type(formats["positions"])
        settings = {k: v for k, v in (("joints", joints), ("fps", fps)) if v}
        try:
            formats["positions"] = cls(cls.Config.model_validate(settings))
        except ValueError as exc:
            raise MotionError(f"--joints/--fps: {exc}", file=path) from None
    return reader_for(path, formats).read(path)
