"""``retarget blend``: a real fine-tune (one input source added) blended with the run it started
from: weights in between, the new input's columns scaled, a run that loads and acts; runs
trained apart, bad weights and a used directory are refused by name."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import torch
from helpers import TINY

from retarget.cli.main import main
from retarget.errors import RetargetError
from retarget.registry.loader import load_plugins
from retarget.train.blend import BLENDED_FROM, blend_runs
from retarget.train.checkpoint import load_checkpoint
from retarget.train.load import load_run
from retarget.train.run_dir import latest_checkpoint
from retarget.train.warm_start import input_maps


def _train(root: Path, name: str, *extra: str) -> Path:
    recipe = root / f"{name}.yaml"
    recipe.write_text(TINY.replace("name: tiny", f"name: {name}"))
    assert main(["train", str(recipe), "--steps", "64", "--runs-dir", str(root),
                 "--no-tensorboard", *extra]) == 0  # fmt: skip
    return root / name / "latest"


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("blend")
    start = _train(root, "start")
    tuned = _train(root, "tuned", "--init-from", str(start),
                   "--sensors", "three_point,controller_tracking")  # fmt: skip
    return start, tuned


def _actor(run: Path) -> dict[str, torch.Tensor]:
    return load_checkpoint(latest_checkpoint(run))["algorithm"]["actor"]


def test_a_blend_lies_between_the_fine_tune_and_its_start(runs, tmp_path: Path) -> None:
    start, tuned = runs
    out = tmp_path / "blend"
    cli = subprocess.run([sys.executable, "-m", "retarget", "blend", str(tuned), "--start",
                          str(start), "--weight", "0.25", "--out", str(out)],
                         capture_output=True, text=True, cwd=tmp_path)  # fmt: skip
    assert cli.returncode == 0, cli.stderr
    assert json.loads((out / BLENDED_FROM).read_text())["weight"] == 0.25
    a, b, mixed = _actor(start), _actor(tuned), _actor(out)
    registry = load_plugins()
    layouts = [load_run(r, registry, num_envs=1).env.obs_layout for r in (tuned, start)]
    index = input_maps(*layouts)[0]["actor"]
    new = index < 0
    assert new.sum() == 4, "the tuned run reads each controller's flag, now and a frame ago"
    w = mixed["net.0.weight"]
    expected = 0.75 * a["net.0.weight"][:, index[~new]] + 0.25 * b["net.0.weight"][:, ~new]
    assert torch.allclose(w[:, ~new], expected, atol=1e-6)
    assert torch.allclose(w[:, new], 0.25 * b["net.0.weight"][:, new], atol=1e-6)
    assert not torch.allclose(w, b["net.0.weight"])
    for key in ("net.0.bias", "net.2.weight", "log_std"):
        assert torch.allclose(mixed[key], 0.75 * a[key] + 0.25 * b[key], atol=1e-6), key
    # the input statistics are the fine-tune's
    stats = load_checkpoint(latest_checkpoint(out))["algorithm"]["obs_norm"]
    theirs = load_checkpoint(latest_checkpoint(tuned))["algorithm"]["obs_norm"]
    assert all(torch.equal(stats[k], theirs[k]) for k in theirs)
    ev = subprocess.run([sys.executable, "-m", "retarget", "eval", str(out), "--max-seconds", "1",
                         "--num-envs", "2", "--json", str(tmp_path / "e.json")],
                        capture_output=True, text=True, cwd=tmp_path)  # fmt: skip
    assert ev.returncode == 0, ev.stderr + ev.stdout


def test_runs_trained_apart_and_bad_requests_are_refused(runs, tmp_path: Path) -> None:
    start, tuned = runs
    registry = load_plugins()
    apart = _train(tmp_path, "apart", "--seed", "11")
    with pytest.raises(RetargetError, match="normalise their shared 'actor' inputs differently"):
        blend_runs(tuned, apart, 0.5, tmp_path / "x", registry)
    with pytest.raises(RetargetError, match=r"within 0 and 1, got 1\.5"):
        blend_runs(tuned, start, 1.5, tmp_path / "y", registry)
    used = tmp_path / "used"
    used.mkdir()
    (used / "file").write_text("x")
    with pytest.raises(RetargetError, match="not empty"):
        blend_runs(tuned, start, 0.5, used, registry)
