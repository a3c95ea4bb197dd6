"""``motions.weights``: clips drawn by weight from patterns on their file names."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

import retarget
from retarget.motion.clip_weights import clip_weights
from retarget.motion.procedural import default_motions


def _clips():
    walk, turn, idle = default_motions(names=("walk", "turn_left", "idle"))
    return [walk.with_(source=Path("a_run_fast_001.bvh")), turn, idle]


def test_patterns_multiply_and_unmatched_clips_keep_one() -> None:
    got = clip_weights(_clips(), {"*_RUN_*": 3.0, "*fast*": 2.0, "idle": 0.5})
    assert got == [6.0, 1.0, 0.5]  # the file name, case-insensitive; else the clip's name


def test_a_pattern_that_matches_nothing_is_named() -> None:
    with pytest.raises(ValueError, match="'\\*_jog_\\*' matches none of the 3"):
        clip_weights(_clips(), {"*_jog_*": 2.0})


def test_all_zero_is_refused() -> None:
    with pytest.raises(ValueError, match="every clip has weight 0"):
        clip_weights(_clips(), {"*": 0.0})


def _env(weights: str):
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load

    registry = retarget.load_plugins()
    recipe = load(None, registry, assignments=[f"motions.weights={weights}"])
    return env_from_recipe(recipe, num_envs=2, registry=registry)


def test_the_recipe_weights_the_training_library() -> None:
    env = _env("{'walk': 4, 'turn_*': 0}")
    w = env.library.weights
    assert w.numel() == env.library.num_clips and float(w.max()) == 4.0
    assert int((w == 0).sum()) >= 2  # both turns (and their rest-end variants if any)
    starts, _ = env.library.sample(4000, torch.Generator().manual_seed(0))
    drawn = torch.bincount(starts, minlength=env.library.num_clips).double()
    share = drawn / drawn.sum()
    expected = w / w.sum()
    assert torch.allclose(share, expected, atol=0.03), (share, expected)


def test_a_misspelt_pattern_is_a_recipe_error_naming_the_field() -> None:
    with pytest.raises(retarget.RecipeError, match=r"motions\.weights") as err:
        _env("{'wlak': 2}")
    assert "wlak" in str(err.value)


def test_weights_out_of_range_are_refused_by_the_recipe() -> None:
    with pytest.raises(retarget.RecipeError, match=r"motions\.weights"):
        _env("{'walk': -1}")


def test_a_run_loaded_to_act_ignores_training_weights() -> None:
    """A shipped lock keeps its weights but not its data: loading it on other clips (eval,
    play, serve) must not trip over patterns written for the training corpus."""
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load

    registry = retarget.load_plugins()
    recipe = load(None, registry, assignments=["motions.weights={'*_run_*': 3}"])
    with pytest.raises(retarget.RecipeError, match="_run_"):
        env_from_recipe(recipe, num_envs=2, registry=registry)
    env = env_from_recipe(recipe, num_envs=2, registry=registry, weighted=False)
    assert bool((env.library.weights == 1).all())
