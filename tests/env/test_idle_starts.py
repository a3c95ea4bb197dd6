"""Idle starts: training episodes that begin standing idle where a clip sets off from rest."""

from __future__ import annotations

import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.geometry import rotations as rot
from retarget.motion.procedural import default_motions
from retarget.motion.rest_ends import rest_ends
from retarget.recipe import load
from retarget.registry.loader import load_plugins

REGISTRY = load_plugins(strict=True)


def _clips():
    walk = next(c for c in default_motions() if c.name == "walk")
    moving = walk.slice(120, walk.num_frames).with_(name="walk_mid")  # cut mid-stride
    return [moving, *rest_ends(moving)]


def _env(share: float, num_envs: int = 64):
    resolved = load("teacher", REGISTRY, shorthands={},
                    assignments=[f"env.idle_starts={share}"])  # fmt: skip
    return env_from_recipe(resolved, num_envs=num_envs, threads=1, clips=_clips())


def test_a_share_of_starts_stands_idle_at_a_set_off() -> None:
    env = _env(0.5)
    lib = env.library
    (from_rest,) = lib.from_rest.tolist()
    assert lib.names[from_rest].endswith("_from_rest")
    env.reset()
    idle = env.idle_starts.idle_qpos
    q = env.sim.state.qpos.double().numpy()
    at_idle = np.abs(q[:, 7:] - idle[7:]).max(axis=1) < 1e-6
    assert 16 < at_idle.sum() < 48  # about half of 64
    assert (env.clip[torch.as_tensor(at_idle)] == from_rest).all()
    assert (env.frame[torch.as_tensor(at_idle)] == 0).all()
    rows = lib.rows(env.clip, env.frame)[:, 0].numpy()
    ref = env.reference.qpos64[rows]
    # under the reference's root, turned to its heading, at rest, at the idle pose's height
    np.testing.assert_allclose(q[at_idle, :2], ref[at_idle, :2], atol=1e-5)
    np.testing.assert_allclose(rot.yaw(q[at_idle, 3:7]), rot.yaw(ref[at_idle, 3:7]), atol=1e-5)
    np.testing.assert_allclose(q[at_idle, 2], idle[2] + env.options.reset_lift, atol=1e-5)
    assert float(env.sim.state.qvel[torch.as_tensor(at_idle)].abs().max()) < 1e-6
    # the others start in their reference pose, as without the option
    np.testing.assert_allclose(q[~at_idle, 7:], ref[~at_idle, 7:], atol=1e-5)


def test_off_by_default_and_places_are_never_redirected() -> None:
    env = _env(0.0, num_envs=8)
    assert env.idle_starts is None
    env = _env(1.0, num_envs=4)
    clip, frame = torch.tensor([0, 0, 1, 1]), torch.tensor([5, 9, 3, 7])
    env.place(clip, frame)  # evaluation places its own starts
    assert torch.equal(env.clip, clip) and torch.equal(env.frame, frame)
    rows = env.library.rows(clip, frame)[:, 0].numpy()
    np.testing.assert_allclose(env.sim.state.qpos.double().numpy()[:, 7:],
                               env.reference.qpos64[rows, 7:], atol=1e-5)  # fmt: skip


def test_without_set_off_clips_every_start_is_the_reference() -> None:
    resolved = load("teacher", REGISTRY, shorthands={}, assignments=["env.idle_starts=1"])
    env = env_from_recipe(resolved, num_envs=8, threads=1, clips=_clips()[:1])
    assert env.library.from_rest.numel() == 0
    env.reset()
    rows = env.library.rows(env.clip, env.frame)[:, 0].numpy()
    np.testing.assert_allclose(env.sim.state.qpos.double().numpy()[:, 7:],
                               env.reference.qpos64[rows, 7:], atol=1e-5)  # fmt: skip


def test_the_set_off_benchmark_runs_both_starts(tmp_path) -> None:
    """``benchmarks/idle_set_off.py`` on a set-off made from a generated walk: each start
    runs every clip to its end or its failure."""
    import sys
    from pathlib import Path

    from retarget.motion.bvh_write import write_bvh

    sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
    from idle_set_off import run_starts

    write_bvh(_clips()[1], tmp_path / "walk_mid_from_rest.bvh")
    for idle in (False, True):
        r = run_starts("pretrained:human-teacher", tmp_path, idle, None)
        assert r["clips"] == 1 and 0.0 <= r["success"] <= 1.0
        assert 0.0 < r["time_to_failure_s"] <= r["seconds"] + 1e-9
        assert list(r["per_clip"]) == ["walk_mid_from_rest"]
