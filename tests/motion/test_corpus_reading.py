"""Reading a corpus at scale: archives as folders, name picks, clips and references cached by
content (a second read gives the same arrays; a changed file is read anew)."""

from __future__ import annotations

import io
import tarfile
import zipfile
from pathlib import Path

import numpy as np
import pytest

from retarget import load_plugins
from retarget.errors import MotionError
from retarget.motion import procedural
from retarget.motion.bvh_write import write_bvh
from retarget.motion.clip_cache import clip_cache_dir, read_cached
from retarget.motion.sources import load_motions as _load_motions
from retarget.motion.sources import reader_for

FORMATS = load_plugins().motion_formats()


def load_motions(path, **kwargs):
    """The motion layer's reader with every installed format."""
    return _load_motions(path, FORMATS, **kwargs)


def _clips_dir(tmp_path: Path) -> Path:
    folder = tmp_path / "clips"
    folder.mkdir()
    for i, clip in enumerate(procedural.default_motions()[:3]):
        for style in ("normal", "active"):
            write_bvh(clip, folder / f"dataset-2_{clip.name}_{style}_{i:03d}.bvh")
    return folder


def _first_clip(tmp_path: Path):
    """One written clip, the reader for it, and an empty cache folder."""
    path = sorted(_clips_dir(tmp_path).iterdir())[0]
    return path, reader_for(path, FORMATS), tmp_path / "cache"


def test_a_tar_gz_and_a_zip_read_as_their_clips(tmp_path: Path) -> None:
    folder = _clips_dir(tmp_path)
    tar_path = tmp_path / "corpus.tar.gz"
    with tarfile.open(tar_path, "w:gz") as tar:
        tar.add(folder, arcname="data")
    zip_path = tmp_path / "corpus.zip"
    with zipfile.ZipFile(zip_path, "w") as z:
        for f in sorted(folder.iterdir()):
            z.write(f, f"data/{f.name}")
    plain = load_motions(folder)
    for archive in (tar_path, zip_path):
        clips = load_motions(archive)
        assert [c.name for c in clips] == [c.name for c in plain]
        np.testing.assert_allclose(clips[0].root_pos, plain[0].root_pos)
    both = tmp_path / "both"
    both.mkdir()
    tar_path.rename(both / tar_path.name)
    assert len(load_motions(both)) == len(plain)  # archives inside a folder are read too


def test_include_and_exclude_pick_by_name(tmp_path: Path) -> None:
    folder = _clips_dir(tmp_path)
    held_out = load_motions(folder, include=["*_normal_*"])
    train = load_motions(folder, exclude=["*_NORMAL_*"])
    assert held_out and train and len(held_out) + len(train) == 6
    assert all("_normal_" in c.name for c in held_out)
    assert not any("_normal_" in c.name for c in train)
    with pytest.raises(MotionError, match="none of 6 motion files matches"):
        load_motions(folder, include=["*_sneaky_*"])


def test_an_archive_member_cannot_leave_its_folder(tmp_path: Path) -> None:
    bad = tmp_path / "evil.tar"
    with tarfile.open(bad, "w") as tar:
        info = tarfile.TarInfo("../../outside.bvh")
        data = b"HIERARCHY\n"
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))
    with pytest.raises(MotionError, match="outside its folder"):
        load_motions(bad)
    assert not (tmp_path.parent / "outside.bvh").exists()


def test_a_broken_archive_names_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "broken.tar.gz"
    bad.write_bytes(b"\x1f\x8b not really gzip")
    with pytest.raises(MotionError, match=r"broken\.tar\.gz"):
        load_motions(bad)


def test_parsed_clips_come_back_from_the_cache_equal(tmp_path: Path) -> None:
    path, fmt, cache = _first_clip(tmp_path)
    first = read_cached(fmt, path, cache)
    assert len(list(cache.rglob("*.npz"))) == 1
    again = read_cached(fmt, path, cache)
    for field in ("root_pos", "local_rot", "offsets", "contacts"):
        np.testing.assert_array_equal(getattr(first, field), getattr(again, field))
    assert again.name == first.name and again.meta["units"] == first.meta["units"]
    np.testing.assert_array_equal(again.meta["foot_clearance"], first.meta["foot_clearance"])
    copy = tmp_path / "renamed.bvh"  # same bytes, another name: named after its own file
    copy.write_bytes(path.read_bytes())
    assert read_cached(fmt, copy, cache).name == "renamed"
    path.write_text(path.read_text().replace("Frame Time", "Frame Time", 1) + "\n")
    read_cached(fmt, path, cache)  # changed bytes: a second entry, never the stale one
    assert len(list(cache.rglob("*.npz"))) == 2


def test_a_corrupt_cache_entry_is_read_anew(tmp_path: Path) -> None:
    path, fmt, cache = _first_clip(tmp_path)
    first = read_cached(fmt, path, cache)
    (entry,) = cache.rglob("*.npz")
    entry.write_bytes(b"garbage")
    again = read_cached(fmt, path, cache)
    np.testing.assert_array_equal(first.root_pos, again.root_pos)


def test_the_cache_can_be_turned_off(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RETARGET_CACHE", "off")
    assert clip_cache_dir() is None


def test_a_large_reference_is_cached_and_equal(monkeypatch: pytest.MonkeyPatch) -> None:
    import retarget.env.reference_cache as rc
    from retarget.env.env import RetargetEnv
    from retarget.registry.loader import load_plugins

    monkeypatch.setattr(rc, "MIN_FRAMES", 10)
    character = load_plugins().get("character", "human").cls()
    clips = procedural.default_motions()[:2]
    first = RetargetEnv(character, clips).reference
    files = list((clip_cache_dir().parent / "reference").glob("*.npz"))
    assert files
    again = RetargetEnv(character, clips).reference
    np.testing.assert_array_equal(first.qpos64, again.qpos64)
    for name, value in first.arrays.items():
        assert torch_equal(value, again.arrays[name]), name


def torch_equal(a, b) -> bool:
    import torch

    return bool(torch.equal(a, b))


def test_motion_commands_use_the_invocations_registry(tmp_path: Path, monkeypatch) -> None:
    """`retarget motion inspect` of many files loads the plugins once (it reloaded every entry
    point per file, ignoring --strict-plugins and warning twice)."""
    import retarget.registry.loader as loader
    from retarget.cli.main import main

    folder = _clips_dir(tmp_path)
    calls = []
    original = loader.load_plugins

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(loader, "load_plugins", counting)
    import retarget.cli.main as cli_main

    monkeypatch.setattr(cli_main, "load_plugins", counting)
    assert main(["motion", "inspect", str(folder)]) == 0
    assert len(calls) == 1
