"""Files that parse but cannot be a person are refused, naming the file and the frame: a
skeleton scaled by a million (a 1,750 km subject) and a root 100 km away for one
frame (both were read without a word)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from retarget.errors import MotionError
from retarget.plugins.formats.bvh import Bvh


def _sample(tmp_path: Path) -> tuple[Path, list[str], int]:
    path = Bvh.write_sample(tmp_path)
    lines = path.read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("Frame Time")) + 1
    return path, lines, first


def test_a_scaled_skeleton_is_refused(tmp_path: Path) -> None:
    path, lines, _ = _sample(tmp_path)
    text = re.sub(r"OFFSET ([-\d.e]+) ([-\d.e]+) ([-\d.e]+)",
                  lambda m: "OFFSET " + " ".join(str(float(g) * 1e6) for g in m.groups()),
                  "\n".join(lines))  # fmt: skip
    path.write_text(text)
    with pytest.raises(MotionError, match=r"sample\.bvh.*tall, outside 0\.4-3\.0 m"):
        Bvh().read(path)


def test_a_root_that_teleports_is_refused_at_its_frame(tmp_path: Path) -> None:
    path, lines, first = _sample(tmp_path)
    values = lines[first + 5].split()
    values[0] = "1e7"  # frame 5: the root 100 km away (centimetres)
    lines[first + 5] = " ".join(values)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MotionError, match=r"frame 5: the root"):
        Bvh().read(path)


def test_the_sample_itself_is_plausible(tmp_path: Path) -> None:
    path, _, _ = _sample(tmp_path)
    assert Bvh().read(path).num_frames == 30
