"""``retarget motion inspect/show`` through the command plugin's public interface."""

from __future__ import annotations

import argparse
import os
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from retarget.errors import MotionError, RetargetError
from retarget.plugins.commands.motion import MotionCommand
from retarget.plugins.formats.bvh import Bvh
from retarget.registry.loader import load_plugins

os.environ.setdefault("MUJOCO_GL", "osmesa")



def _command() -> MotionCommand:
    """The command as the CLI hands it over: connected to the invocation's registry."""
    cmd = MotionCommand()
    cmd.connect(load_plugins())
    return cmd

def _args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    MotionCommand().add_arguments(parser)
    return parser.parse_args(list(argv))


def _read_png(path: Path) -> np.ndarray:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    w, h = struct.unpack(">II", data[16:24])
    pos, idat = 8, b""
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        if data[pos + 4:pos + 8] == b"IDAT":
            idat += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + 3 * w)
    return raw[:, 1:].reshape(h, w, 3)


def test_inspect_prints_a_row_per_file(tmp_path: Path, capsys, mocap_dir: Path):
    sample = Bvh.write_sample(tmp_path)
    real = mocap_dir / "bandai_d2_walk_normal_020.bvh"
    assert _command().run(_args("inspect", str(sample), str(real))) == 0
    out = capsys.readouterr().out
    assert "sample.bvh" in out and "bandai" in out and "290" in out and "canonical" in out


def test_inspect_missing_file_is_a_user_error(tmp_path: Path):
    with pytest.raises(MotionError, match="no such file"):
        _command().run(_args("inspect", str(tmp_path / "nope.bvh")))


def test_show_writes_a_picture_of_the_body(tmp_path: Path):
    sample = Bvh.write_sample(tmp_path)
    out = tmp_path / "s.png"
    assert _command().run(_args("show", str(sample), "--out", str(out), "--frames", "2",
                                     "--size", "96")) == 0
    img = _read_png(out)
    assert img.shape == (96, 2 * 96 + 4, 3)
    # the skeleton's colours (blue left, red right limbs) are in the picture
    red = (img[..., 0] > 150) & (img[..., 1] < 100) & (img[..., 2] < 100)
    blue = (img[..., 2] > 150) & (img[..., 0] < 100)
    assert red.sum() > 20 and blue.sum() > 20


def test_show_rejects_unknown_output(tmp_path: Path):
    sample = Bvh.write_sample(tmp_path)
    with pytest.raises(RetargetError, match=r"\.png or \.mp4"):
        _command().run(_args("show", str(sample), "--out", str(tmp_path / "x.gif")))


def test_show_cameras_draws_a_row_of_headset_views_per_frame(tmp_path: Path, capsys):
    sample = Bvh.write_sample(tmp_path)
    out = tmp_path / "views.png"
    assert _command().run(_args("show", str(sample), "--out", str(out), "--frames", "2",
                                     "--size", "64", "--cameras", "quest2")) == 0  # fmt: skip
    img = _read_png(out)
    assert img.shape == (2 * 48 + 4, 4 * 64 + 3 * 4, 3)  # 2 frames x 4 cameras of 64x48
    assert np.array_equal(img[..., 0], img[..., 2])  # grayscale views
    assert "2 frames x 4 quest2 cameras" in capsys.readouterr().out
    with pytest.raises(RetargetError, match=r"--cameras draws a \.png"):
        _command().run(_args("show", str(sample), "--out", str(tmp_path / "v.mp4"),
                                  "--cameras", "aria"))  # fmt: skip
