"""Overlapped PPO (``algorithm.overlap: true``): the update on one rollout runs beside the
collection of the next, learns from the rollout before, repeats and resumes bit for bit."""

from __future__ import annotations

from pathlib import Path

import torch
from helpers import TINY, assert_state_equal

from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.run_dir import new_run_dir
from retarget.train.runner import Budget, Trainer

SAMPLES = 4 * 8  # TINY: env steps per iteration
OVERLAP = TINY.replace("  type: ppo\n", "  type: ppo\n  overlap: true\n")


def _trainer(tmp_path: Path, name: str) -> Trainer:
    recipe = tmp_path / "overlap.yaml"
    recipe.write_text(OVERLAP)
    resolved = load(str(recipe), load_plugins())
    return Trainer(resolved, new_run_dir(tmp_path, name), checkpoint_every=100,
                   tensorboard=False)  # fmt: skip


def test_the_update_learns_from_the_rollout_before(tmp_path: Path) -> None:
    t = _trainer(tmp_path, "a")
    ppo = t.algorithm.learner
    assert ppo.overlap is not None
    t.algorithm.train_iteration(t.env)
    # the first iteration collects two rollouts: one learned from, one waiting
    assert t.env.total_steps == 2 * SAMPLES
    waiting = ppo.overlap.ready
    assert waiting is not None
    before = {k: v.clone() for k, v in ppo.actor.state_dict().items()}
    acted = waiting.actions.clone()
    stats = t.algorithm.train_iteration(t.env).stats
    assert t.env.total_steps == 3 * SAMPLES
    changed = any(not torch.equal(before[k], v) for k, v in ppo.actor.state_dict().items())
    assert changed, "the update ran"
    assert stats["gradient_steps"] > 0 and stats["update_seconds"] > 0
    # the rollout collected during that update came from the acting copy of the weights
    # before it: the copy now takes the updated weights for the next iteration
    assert not torch.equal(ppo.overlap.ready.actions, acted)
    for name, tensor in ppo.overlap.nets.actor.state_dict().items():
        assert torch.equal(tensor, before[name]), "acted with the weights before the update"


def test_overlapped_runs_repeat_and_resume_bit_for_bit(tmp_path: Path) -> None:
    straight = _trainer(tmp_path, "straight")
    straight.train(Budget(steps=5 * SAMPLES))
    first = _trainer(tmp_path, "first")
    ckpt = first.train(Budget(steps=3 * SAMPLES))
    resumed = _trainer(tmp_path, "second")
    resumed.restore(ckpt)
    assert resumed.algorithm.learner.overlap.ready is not None, "the waiting rollout resumes"
    resumed.train(Budget(steps=5 * SAMPLES))
    assert resumed.progress.iteration == straight.progress.iteration
    assert_state_equal(resumed.algorithm.state_dict(), straight.algorithm.state_dict(), "algorithm")
    assert_state_equal(resumed.env.state_dict(), straight.env.state_dict(), "env")


def test_the_decoupled_objective_is_ppo_when_the_rollout_is_fresh(tmp_path: Path) -> None:
    """Collected by the very weights being updated, the proximal and behaviour policies are
    one: the decoupled update must then move the weights as the plain one does."""
    import copy

    t = _trainer(tmp_path, "fresh")
    ppo = t.algorithm.learner
    ppo.collect(t.env)
    twin = copy.deepcopy(ppo)
    before = copy.deepcopy(ppo.actor.state_dict())
    st, twin_st = copy.deepcopy(ppo.storage), copy.deepcopy(ppo.storage)
    ppo.update(st, torch.Generator().manual_seed(1), proximal=True)
    twin.update(twin_st, torch.Generator().manual_seed(1))
    after = ppo.actor.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in after), "the update moved"
    for name, tensor in after.items():
        torch.testing.assert_close(tensor, twin.actor.state_dict()[name], atol=1e-5, rtol=1e-4)
