"""``retarget average``: a run directory whose policy is the mean of a real run's last
checkpoints; it loads and acts like any run, and bad requests are refused by name."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import torch
from helpers import TINY

from retarget.errors import RetargetError
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.average import average_run, average_state
from retarget.train.checkpoint import load_checkpoint
from retarget.train.run_dir import new_run_dir, run_checkpoints
from retarget.train.runner import Budget, Trainer

SAMPLES = 4 * 8  # num_envs x rollout_steps of the tiny recipe


def _train(tmp_path: Path, name: str, text: str, iterations: int) -> Path:
    recipe = tmp_path / f"{name}.yaml"
    recipe.write_text(text)
    registry = load_plugins()
    resolved = load(str(recipe), registry, shorthands={}, assignments=[])
    run = new_run_dir(tmp_path / "runs", name)
    Trainer(resolved, run, checkpoint_every=1, tensorboard=False,
            registry=registry).train(Budget(steps=iterations * SAMPLES))  # fmt: skip
    return run


def test_the_mean_of_the_last_checkpoints_loads_and_acts(tmp_path: Path) -> None:
    run = _train(tmp_path, "tiny", TINY, 4)
    files = run_checkpoints(run)
    assert [f.name for f in files][-3:] == ["ckpt-0000002.pt", "ckpt-0000003.pt",
                                             "ckpt-0000004.pt"]  # fmt: skip
    out = tmp_path / "averaged"
    cli = subprocess.run([sys.executable, "-m", "retarget", "average", str(run), "--last", "3",
                          "--out", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert cli.returncode == 0, cli.stderr
    record = json.loads((out / "averaged_from.json").read_text())
    assert record["checkpoints"] == [f.name for f in files[-3:]]
    mean = load_checkpoint(out / "checkpoints" / "ckpt-0000004.pt")["algorithm"]
    states = [load_checkpoint(f)["algorithm"] for f in files[-3:]]
    for key, value in mean["actor"].items():
        expected = torch.stack([s["actor"][key].double() for s in states]).mean(0)
        assert torch.allclose(value.double(), expected, atol=1e-6), key
    assert not torch.equal(mean["actor"]["net.0.weight"], states[-1]["actor"]["net.0.weight"])
    assert "optimizer" not in mean and mean["iteration"] == states[-1]["iteration"]
    # a run like any other: evaluated from the averaged weights
    ev = subprocess.run([sys.executable, "-m", "retarget", "eval", str(out), "--max-seconds", "1",
                         "--num-envs", "2", "--json", str(tmp_path / "e.json")],
                        capture_output=True, text=True, cwd=tmp_path)  # fmt: skip
    assert ev.returncode == 0, ev.stderr + ev.stdout
    with pytest.raises(RetargetError, match="not empty"):
        average_run(run, out, 2)
    with pytest.raises(RetargetError, match="fewer than --last 9"):
        average_run(run, tmp_path / "more", 9)
    # the checkpoints up to one chosen earlier in the run, not the run's newest
    early = tmp_path / "early"
    cli = subprocess.run([sys.executable, "-m", "retarget", "average", str(run), "--last", "2",
                          "--upto", "3", "--out", str(early)], capture_output=True, text=True,
                         cwd=tmp_path)  # fmt: skip
    assert cli.returncode == 0, cli.stderr
    assert json.loads((early / "averaged_from.json").read_text())["checkpoints"] == [
        "ckpt-0000002.pt", "ckpt-0000003.pt"]  # fmt: skip
    upto3 = load_checkpoint(early / "checkpoints" / "ckpt-0000003.pt")["algorithm"]["actor"]
    for key, value in upto3.items():
        expected = (states[0]["actor"][key].double() + states[1]["actor"][key].double()) / 2
        assert torch.allclose(value.double(), expected, atol=1e-6), key
    with pytest.raises(RetargetError, match="no checkpoint of iteration 7"):
        average_run(run, tmp_path / "none", 2, upto=7)
    with pytest.raises(RetargetError, match="up to iteration 2, fewer than --last 4"):
        average_run(run, tmp_path / "short", 4, upto=2)


def test_checkpoints_of_other_networks_are_refused_naming_the_file(tmp_path: Path) -> None:
    small = _train(tmp_path, "small", TINY, 1)
    wide = _train(tmp_path, "wide", TINY.replace("actor_hidden: [32]", "actor_hidden: [48]"), 1)
    other = run_checkpoints(wide)[-1]
    with pytest.raises(RetargetError, match="another shape") as err:
        average_state([run_checkpoints(small)[-1], other])
    assert str(other) in str(err.value)
