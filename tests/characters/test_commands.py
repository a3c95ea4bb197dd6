"""``retarget character show|retarget`` render real pictures (offscreen MuJoCo)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pytest

from retarget.plugins.characters.commands import CharacterCommand
from retarget.registry.loader import load_plugins

MOCAP = Path("/work/shared/data/mocap/bandai_d2_wave-right-hand_normal_018.bvh")


def _run(argv: list[str]) -> int:
    cmd = CharacterCommand()
    cmd.connect(load_plugins())  # as the CLI does before run()
    parser = argparse.ArgumentParser()
    cmd.add_arguments(parser)
    return cmd.run(parser.parse_args(argv))


def _image(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


@pytest.fixture(autouse=True)
def _needs_rendering() -> None:
    pytest.importorskip("PIL")
    if os.environ.get("MUJOCO_GL", "osmesa") == "osmesa":
        try:
            import ctypes.util

            if ctypes.util.find_library("OSMesa") is None:
                pytest.skip("offscreen rendering needs libosmesa6")
        except Exception:  # pragma: no cover - platform probing only
            pytest.skip("cannot probe for OSMesa")


def test_show_renders_a_labelled_rest_pose(tmp_path: Path) -> None:
    out = tmp_path / "oppy.png"
    assert _run(["show", "oppy", "--out", str(out), "--size", "240x180"]) == 0
    img = _image(out)
    assert img.shape == (180, 240, 3)
    assert img.std() > 10  # not a blank frame


def test_retarget_renders_human_beside_character(tmp_path: Path) -> None:
    if not MOCAP.exists():
        pytest.skip("shared mocap clips not available")
    out = tmp_path / "wave.gif"
    assert _run(["retarget", str(MOCAP), "--character", "dino", "--out", str(out),
                 "--seconds", "0.4", "--fps", "5", "--size", "160x120"]) == 0
    from PIL import Image

    with Image.open(out) as gif:
        assert gif.n_frames == 2
