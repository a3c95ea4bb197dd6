"""Video files written by `character retarget`, `motion show` and `play`: GIF and MP4 decode
back to the frames' size and count."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from retarget.render.character_view import save_video


def frames(count: int = 12) -> list[np.ndarray]:
    """A moving white square on black (H.264 needs even sizes: 64x48)."""
    out = []
    for k in range(count):
        f = np.zeros((48, 64, 3), np.uint8)
        f[10:26, 4 * k : 4 * k + 16] = 255
        out.append(f)
    return out


def test_mp4_round_trip(tmp_path: Path) -> None:
    iio = pytest.importorskip("imageio.v3")
    pytest.importorskip("imageio_ffmpeg")
    path = tmp_path / "clip.mp4"
    save_video(frames(), path, fps=36.0)
    back = iio.imread(path)
    assert back.shape == (12, 48, 64, 3)
    # lossy, but the square is where it was drawn
    assert back[5, 12:24, 22:34].mean() > 200 and back[5, 30:, :].mean() < 30


def test_gif_plays_in_real_time(tmp_path: Path) -> None:
    from PIL import Image, ImageSequence

    path = tmp_path / "clip.gif"
    written = save_video(frames(72), path, fps=36.0)  # two seconds at the control rate
    with Image.open(path) as im:
        assert im.size == (64, 48)
        delays = [f.info["duration"] for f in ImageSequence.Iterator(im)]
    assert all(d % 10 == 0 for d in delays)  # whole centiseconds, as GIF stores them
    assert abs(sum(delays) / 1000 - 2.0) < 0.05, sum(delays)  # plays for the clip's 2 s
    assert written == "66 frames at 33.3 fps, real time"  # (identical frames merge in the file)


def test_png_is_a_sheet_of_evenly_spaced_frames(tmp_path: Path) -> None:
    from PIL import Image

    path = tmp_path / "rollout.png"
    assert save_video(frames(), path, fps=36.0) == "8-frame sheet of 12 frames"
    sheet = np.asarray(Image.open(path).convert("RGB"))
    assert sheet.shape == (2 * 48 + 4, 4 * 64 + 3 * 4, 3)  # 8 frames, 4 columns, 4 px gaps
    first, last = sheet[:48, :64], sheet[52:, 3 * 68 :]
    np.testing.assert_array_equal(first, frames()[0])  # the first and the last frame
    np.testing.assert_array_equal(last, frames()[11])
