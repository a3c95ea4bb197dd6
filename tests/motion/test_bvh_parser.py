"""Malformed BVH input is always a MotionError naming file and line, and nothing else."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from retarget.errors import MotionError
from retarget.motion.bvh import parse_bvh_text, read_bvh
from retarget.motion.import_bvh import clip_from_bvh
from retarget.plugins.formats.bvh import Bvh

VALID = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.033333
0 90 0 0 0 0 10 0 0
0 90 1 0 0 5 20 0 0
"""


def test_valid_minimal_file_parses():
    data = parse_bvh_text(VALID, "mini.bvh")
    assert data.names == ["Hips", "Spine"]
    assert data.joints[0].rotation_order == "zyx"
    assert data.joints[1].rotation_order == "zxy"
    assert data.values.shape == (2, 9)
    assert data.joints[1].end_site is not None
    assert data.fps == pytest.approx(30.0, rel=1e-4)


CASES = {
    "empty": ("", 1, "empty"),
    "truncated": (VALID.rsplit("\n", 2)[0] + "\n", 19, "truncated"),
    "cut_hierarchy": ("\n".join(VALID.splitlines()[:8]), 8, "end of file"),
    "channel_names": (VALID.replace("CHANNELS 3 Zrotation Xrotation Yrotation",
                                    "CHANNELS 3 Zrotation Xrotation"), 10, "channel name"),
    "row_width": (VALID.replace("0 90 1 0 0 5 20 0 0", "0 90 1 0 0 5 20 0"), 20, "8 values"),
    "bad_number": (VALID.replace("0 90 1 0 0 5 20 0 0", "0 90 1 0 zero 5 20 0 0"), 20,
                   "bad number"),
    "nan": (VALID.replace("0 90 1 0 0 5 20 0 0", "0 90 1 0 nan 5 20 0 0"), 20, "bad number"),
    "duplicate": (VALID.replace("JOINT Spine", "JOINT Hips"), 6, "duplicate"),
    "frames_word": (VALID.replace("Frames: 2", "Frames: two"), 17, "integer"),
    "frame_time": (VALID.replace("Frame Time: 0.033333", "Frame Time: 0"), 18, "out of range"),
    "frame_time_huge": (VALID.replace("Frame Time: 0.033333", "Frame Time: 1e6"), 18,
                        "between 0.0001 s (10 kHz) and 1.0 s"),
    "frame_time_tiny": (VALID.replace("Frame Time: 0.033333", "Frame Time: 1e-9"), 18,
                        "out of range"),
    "too_long": (VALID.replace("Frames: 2", "Frames: 99999999"), 18, "at most 3 h"),
    "no_motion": (VALID.split("MOTION")[0], 15, "MOTION"),
    "offset": (VALID.replace("OFFSET 0 10 0\n    CHANNELS", "OFFSET 0 ten 0\n    CHANNELS"), 8,
               "number"),
    "extra_rows": (VALID + "0 0 0 0 0 0 0 0 0\n", 21, "more data rows"),
    "two_roots": (VALID.replace("MOTION", "ROOT B\n{\nOFFSET 0 0 0\n}\nMOTION"), 16, "ROOT"),
    "brace": (VALID.replace("  JOINT Spine\n  {", "  JOINT Spine\n  ["), 7, "'{'"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_malformed_input_names_file_and_line(case, tmp_path: Path):
    text, line, words = CASES[case]
    path = tmp_path / f"{case}.bvh"
    path.write_text(text)
    with pytest.raises(MotionError) as info:
        read_bvh(path)
    err = info.value
    assert err.file == str(path)
    assert err.line == line, (err.line, str(err))
    assert words.lower() in err.message.lower(), err.message
    assert f"{path}:{line}" in str(err)


def test_missing_file_and_binary(tmp_path: Path):
    with pytest.raises(MotionError, match="cannot read"):
        read_bvh(tmp_path / "absent.bvh")
    (tmp_path / "b.bvh").write_bytes(b"\x00\x01HIERARCHY")
    with pytest.raises(MotionError, match="binary"):
        read_bvh(tmp_path / "b.bvh")


def test_unknown_skeleton_lists_unmapped_joints_and_how_to_map(tmp_path: Path):
    with pytest.raises(MotionError) as info:
        clip_from_bvh(parse_bvh_text(VALID, tmp_path / "x.bvh"))
    text = str(info.value)
    assert "unknown skeleton" in text and "left_knee" in text and "name_map" in text
    assert info.value.file == str(tmp_path / "x.bvh")


_SAMPLE: list[str] = []


def _sample_text(tmp: Path) -> str:
    if not _SAMPLE:
        _SAMPLE.append(Bvh.write_sample(tmp).read_text())
    return _SAMPLE[0]


_GARBAGE = st.sampled_from(["", "{", "}", "JOINT", "End", "Site", "OFFSET", "CHANNELS", "7",
                            "-3", "1e308", "nan", "inf", "x", "ROOT", "MOTION", "Frames:", "\n",
                            "Xrotation", "Zposition", "0.5", "\t", "Frame Time:"])


@st.composite
def mutated(draw) -> tuple[str, int, int, str]:
    kind = draw(st.sampled_from(["cut", "delete", "insert", "replace"]))
    a = draw(st.floats(0, 1))
    b = draw(st.floats(0, 1))
    tok = draw(_GARBAGE) + draw(st.sampled_from(["", " ", "\n"]))
    return kind, a, b, tok


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                     HealthCheck.function_scoped_fixture])
@given(m=mutated())
def test_fuzz_reader_raises_only_motion_error(m, tmp_path: Path):
    """Random cuts, deletions, insertions and token swaps of a valid file: the whole reader
    (parse, detect, map, floor, contacts) either returns a finite clip or a MotionError."""
    text = _sample_text(tmp_path)
    kind, a, b, tok = m
    n = len(text)
    i, j = sorted((int(a * n), int(b * n)))
    if kind == "cut":
        text = text[:i]
    elif kind == "delete":
        text = text[:i] + text[min(n, i + 1 + (j - i) % 40):]
    elif kind == "insert":
        text = text[:i] + tok + text[i:]
    else:
        words = text.split(" ")
        k = int(a * (len(words) - 1))
        words[k] = tok
        text = " ".join(words)
    path = tmp_path / "fuzz.bvh"
    path.write_text(text)
    try:
        clip = Bvh().read(path)
    except MotionError as err:
        assert err.file == str(path)
        return
    assert np.isfinite(clip.global_pos).all()


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=300))
def test_fuzz_arbitrary_text(text):
    try:
        parse_bvh_text(text, "t.bvh")
    except MotionError as err:
        assert err.file == "t.bvh"
