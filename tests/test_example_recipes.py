"""Every recipe in examples/recipes/ validates and trains (a few steps, tiny networks)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from helpers import REPO, TINY_TEACHER

from retarget.cli.main import main

RECIPES = sorted((REPO / "examples" / "recipes").glob("*.yaml"))
SMALL = ["--steps", "16", "--num-envs", "2", "--no-tensorboard",
         "--set", "algorithm.rollout_steps=8", "--set", "algorithm.minibatch_size=16",
         "--set", "algorithm.actor_hidden=[16]"]  # fmt: skip


def test_there_are_example_recipes() -> None:
    assert len(RECIPES) >= 4


@pytest.mark.parametrize("recipe", RECIPES, ids=lambda p: p.stem)
def test_example_recipe_trains(recipe: Path, tmp_path: Path) -> None:
    extra: list[str] = []
    if "dagger" in recipe.read_text():  # a student: train a tiny teacher for it first
        teacher = tmp_path / "teacher.yaml"
        teacher.write_text(TINY_TEACHER)
        assert main(["train", str(teacher), "--steps", "64", "--runs-dir", str(tmp_path),
                     "--no-tensorboard"]) == 0  # fmt: skip
        extra = ["--set", f"algorithm.teacher={tmp_path / 'teacher' / 'latest'}"]
    elif "type: estimator" in recipe.read_text():  # supervised: no rollouts, its own sizes
        assert main(["recipe", "validate", str(recipe)]) == 0
        assert main(["train", str(recipe), "--runs-dir", str(tmp_path), "--steps", "16",
                     "--no-tensorboard", "--set", "algorithm.batch_size=16",
                     "--set", "algorithm.hidden=[16]"]) == 0  # fmt: skip
        return
    else:
        extra = ["--set", "algorithm.critic_hidden=[16]"]
    assert main(["recipe", "validate", str(recipe)]) == 0
    motions = yaml.safe_load(recipe.read_text()).get("motions") or {}
    if not motions.get("path") and (motions.get("include") or motions.get("exclude")):
        # a corpus recipe, run with --motions (retarget train refuses patterns without files)
        from retarget.motion.bvh_write import write_bvh
        from retarget.motion.procedural import default_motions

        clips = tmp_path / "corpus"
        clips.mkdir()
        write_bvh(default_motions()[1], clips / "dataset-2_walk_active_001.bvh")
        extra += ["--motions", str(clips)]
    assert main(["train", str(recipe), "--runs-dir", str(tmp_path), *SMALL, *extra]) == 0
