"""Contract checks for a whole environment, whatever engine runs its physics.

A simulator backend (``sim.backend``), or a change to the env itself, is right when an
environment built on it keeps the promises algorithms rely on; these checks state them. Each
takes a factory that builds a fresh environment, so one check cannot leave state for the next:

    from retarget.testing.env_checks import check_env
    check_env(lambda: env_from_recipe(resolved, num_envs=4))

Every failure is an ``AssertionError`` naming the check and what it saw.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch

from retarget.kinds import VecEnv

EnvFactory = Callable[[], Any]


def _actions(env: Any, seed: int, scale: float = 0.3) -> torch.Tensor:
    gen = torch.Generator().manual_seed(seed)
    return (torch.rand(env.num_envs, env.action_dim, generator=gen) * 2 - 1) * scale


def check_env_shapes(make: EnvFactory) -> None:
    """reset and step return every group as ``(N, D)`` float32 and per-env ``(N,)`` reward,
    terminated and truncated."""
    env = make()
    assert isinstance(env, VecEnv), "the env implements the VecEnv protocol"
    n = env.num_envs
    obs = env.reset()
    for group, dim in env.obs_dims.items():
        assert obs[group].shape == (n, dim), f"reset: group {group} is {tuple(obs[group].shape)}"
        assert obs[group].dtype == torch.float32, f"reset: group {group} is {obs[group].dtype}"
    obs, reward, terminated, truncated, info = env.step(_actions(env, 0))
    for group, dim in env.obs_dims.items():
        assert obs[group].shape == (n, dim), f"step: group {group} is {tuple(obs[group].shape)}"
    assert reward.shape == (n,) and terminated.shape == (n,) and truncated.shape == (n,)
    assert terminated.dtype == torch.bool and truncated.dtype == torch.bool
    assert isinstance(info, dict)


def check_env_finite(make: EnvFactory, steps: int = 12) -> None:
    """Random actions for ``steps`` control steps: every observation and reward is finite."""
    env = make()
    env.reset()
    for k in range(steps):
        obs, reward, *_ = env.step(_actions(env, k))
        assert torch.isfinite(reward).all(), f"step {k}: non-finite reward"
        for group, x in obs.items():
            assert torch.isfinite(x).all(), f"step {k}: non-finite observation in {group}"


def check_env_place(make: EnvFactory) -> None:
    """``place`` at the same (clip, frame) twice gives the same observation, and the
    character stands where the reference is (the root within 5 cm, the lift aside)."""
    env = make()
    clip = torch.zeros(env.num_envs, dtype=torch.long)
    frame = torch.arange(env.num_envs) * 3 + 2
    first = env.place(clip, frame)
    env.step(_actions(env, 1))
    again = env.place(clip, frame)
    for group in first:
        assert torch.equal(first[group], again[group]), f"place is not repeatable ({group})"
    ref = env.reference.pose(env.library.rows(clip, frame)[:, 0])
    root = env.sim.state.body_pos[:, 0]
    gap = (root[:, :2] - ref.body_pos[:, 0, :2]).norm(dim=-1)
    assert float(gap.max()) < 0.05, f"placed root {float(gap.max()):.3f} m from the reference"


def check_env_nan_action(make: EnvFactory) -> None:
    """A non-finite action ends only that environment, as a failure, with finite outputs."""
    env = make()
    env.reset()
    action = _actions(env, 2)
    action[0, 0] = float("nan")
    obs, reward, terminated, _, info = env.step(action)
    assert bool(terminated[0]) and info["nan_actions"] == 1, "the NaN action's env failed"
    assert not terminated[1:].any() or env.num_envs == 1, "other envs are not touched"
    assert torch.isfinite(reward).all() and all(torch.isfinite(x).all() for x in obs.values())


def check_env_resume(make: EnvFactory, steps: int = 3, atol: float = 0.0) -> None:
    """``load_state_dict(state_dict())`` continues like the uninterrupted env (bit for bit
    with ``atol=0``; an engine that is not deterministic across a state reload states its
    tolerance)."""
    env = make()
    env.reset()
    env.step(_actions(env, 3))
    saved = env.state_dict()
    first = [env.step(_actions(env, 10 + k))[0] for k in range(steps)]
    env.load_state_dict(saved)
    second = [env.step(_actions(env, 10 + k))[0] for k in range(steps)]
    for k, (a, b) in enumerate(zip(first, second, strict=True)):
        for group in a:
            err = float((a[group] - b[group]).abs().max())
            assert err <= atol, f"resumed step {k}: {group} differs by {err:g} (> {atol:g})"


ENV_CHECKS = (check_env_shapes, check_env_finite, check_env_place, check_env_nan_action,
              check_env_resume)  # fmt: skip


def check_env(make: EnvFactory, *, resume_atol: float = 0.0) -> None:
    """Run every environment check on fresh environments from ``make``."""
    for check in ENV_CHECKS:
        if check is check_env_resume:
            check_env_resume(make, atol=resume_atol)
        else:
            check(make)
