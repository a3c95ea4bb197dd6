"""The browser viewer in a real headless browser: the page of a run's rollout shows the
character (the screenshot differs from the same page with the character hidden)."""

from __future__ import annotations

import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import TINY

pytest.importorskip("viser")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium (apt install chromium)")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _screenshot(url: str, out: Path) -> np.ndarray:
    """A wide window, so the control panel on the right never covers the character in the
    middle of the view (the panel's height changes while the page lays itself out)."""
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--hide-scrollbars", "--window-size=1280,720",
           "--virtual-time-budget=10000", f"--screenshot={out}", url]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True, timeout=120)
    import imageio.v3 as iio

    return np.asarray(iio.imread(out))[..., :3].astype(int)


def test_the_viewer_page_shows_the_character(tmp_path) -> None:
    from retarget.cli.main import main
    from retarget.registry.loader import load_plugins
    from retarget.render.browser_view import Viewer, run_track
    from retarget.train.load import load_run

    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    assert main(["train", str(recipe), "--steps", "16", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    run = tmp_path / "tiny" / "latest"
    track = run_track(str(run), load_run(run, load_plugins(), num_envs=1), seconds=1.0)
    port = _free_port()
    viewer = Viewer([track], "127.0.0.1", port)
    viewer.playing = False
    thread = threading.Thread(target=viewer.play, args=(120.0,), daemon=True)
    thread.start()
    try:
        url = f"http://127.0.0.1:{port}"
        shown = _screenshot(url, tmp_path / "shown.png")
        assert viewer.scene is not None
        viewer.scene.set_visible(False)
        time.sleep(0.5)
        hidden = _screenshot(url, tmp_path / "hidden.png")
    finally:
        viewer.server.stop()
    assert shown.shape == hidden.shape == (720, 1280, 3)
    # the middle of the view, where the camera looks at the character: the panels at the
    # corners lay themselves out at their own pace and are not what this test is about
    middle = (slice(180, 620), slice(320, 960))
    changed = (np.abs(shown[middle] - hidden[middle]).sum(-1) > 60).mean()
    assert changed > 0.01, f"only {changed:.4f} of the pixels show the character"
    assert hidden.std() > 5, "the page rendered (grid and panel), not a blank image"
