"""Failure-weighted starts and the annealed root assist, on real physics and clips."""

from __future__ import annotations

import torch

from retarget.env.build import env_from_recipe
from retarget.env.curriculum import CurriculumOptions, FailureCurriculum
from retarget.env.root_assist import RootAssistOptions
from retarget.motion.library import MotionLibrary
from retarget.motion.procedural import default_motions
from retarget.recipe import load
from retarget.registry.loader import load_plugins

REGISTRY = load_plugins(strict=True)


def _env(num_envs: int = 16, *sets: str):
    resolved = load("teacher", REGISTRY, shorthands={}, assignments=list(sets))
    return env_from_recipe(resolved, num_envs=num_envs, threads=1)


def test_starts_follow_failures_with_a_uniform_share() -> None:
    library = MotionLibrary(default_motions())
    options = CurriculumOptions(uniform=0.25, bin_seconds=1.0)
    cur = FailureCurriculum(library, options, num_envs=64)
    gen = torch.Generator().manual_seed(0)
    before, _ = cur.sample(4000, gen)
    hard_clip, hard_frame = 2, 40  # failures at one place of clip 2
    for _ in range(20):
        cur.record(torch.full((8,), hard_clip), torch.full((8,), hard_frame),
                   torch.ones(8, dtype=torch.bool))  # fmt: skip
    clip, frame = cur.sample(4000, gen)
    seg = cur.segment(torch.tensor([hard_clip]), torch.tensor([hard_frame]))
    in_hard = (cur.segment(clip, frame) == seg).double().mean()
    in_before = (cur.segment(clip, frame) == seg - 1).double().mean()
    # 3/4 of starts from failures: 2/3 of that mass on the failing segment, 1/3 one before
    assert 0.45 < in_hard < 0.6 and 0.2 < in_before < 0.32
    assert (before == hard_clip).double().mean() < 0.5
    assert (frame < library.length[clip]).all() and (frame >= 0).all()
    assert set(clip.tolist()) == set(range(library.num_clips))  # the uniform share visits all


def test_failure_counts_decay_and_survive_a_checkpoint() -> None:
    library = MotionLibrary(default_motions())
    options = CurriculumOptions(half_life_steps=1000)
    cur = FailureCurriculum(library, options, num_envs=100)
    cur.record(torch.tensor([0]), torch.tensor([0]), torch.tensor([True]))
    for _ in range(10):
        cur.record(torch.tensor([0]), torch.tensor([0]), torch.tensor([False]))
    assert abs(float(cur.failures.sum()) - 0.5) < 1e-9  # 10 x 100 steps: one half-life
    again = FailureCurriculum(library, options, num_envs=100)
    again.load_state_dict(cur.state_dict())
    assert torch.equal(again.failures, cur.failures)


def test_env_with_a_curriculum_resumes_its_counts() -> None:
    env = _env(16, "env.curriculum={uniform: 0.5}")
    env.reset()
    for _ in range(60):
        env.step(torch.zeros(16, env.action_dim))  # a T-pose falls: failures are counted
    assert env.curriculum is not None and float(env.curriculum.failures.sum()) > 0
    state = env.state_dict()
    other = _env(16, "env.curriculum={uniform: 0.5}")
    other.load_state_dict(state)
    assert torch.equal(other.curriculum.failures, env.curriculum.failures)


def _root_error(env, steps: int) -> float:
    env.reset()
    gen = torch.Generator().manual_seed(3)
    err = 0.0
    for _ in range(steps):
        env.step(0.1 * torch.randn(env.num_envs, env.action_dim, generator=gen))
        rows = env.library.rows(env.clip, env.frame)[:, 0]
        ref = env.reference.arrays["body_pos"][rows, 0]
        err += float((env.sim.state.body_pos[:, 0] - ref).norm(dim=-1).mean())
    return err / steps


def test_root_assist_pulls_toward_the_reference_only_when_a_trainer_sets_it() -> None:
    sets = ("env.root_assist={strength: 1.0}", "terminations={}")
    plain = _root_error(_env(8, "terminations={}"), 40)
    idle = _env(8, *sets)
    assert idle.root_assist is not None and idle.root_assist.scale == 0.0
    assert abs(_root_error(idle, 40) - plain) < 1e-6  # no trainer, no assist: bit for bit
    held = _env(8, *sets)
    held.root_assist.scale = 1.0
    assisted = _root_error(held, 40)
    assert assisted < 0.6 * plain, (assisted, plain)


def test_the_assist_anneals_to_zero() -> None:
    options = RootAssistOptions(strength=2.0, anneal_steps=1000)
    assert options.scale_at(0) == 2.0 and options.scale_at(500) == 1.0
    assert options.scale_at(1000) == 0.0 and options.scale_at(10**9) == 0.0
