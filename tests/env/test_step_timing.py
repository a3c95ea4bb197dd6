"""The env's step timers book each kind of work where it belongs: the observation an episode
ended in counts as observations, not resets (it was booked as resets)."""

from __future__ import annotations

import time

import torch

import retarget
from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.registry.loader import load_plugins


class Slow(retarget.Sensor):
    """One number per env, taking 50 ms per call (far more than any real work here)."""

    name = "slow"

    def spec(self, layout: retarget.Layout) -> retarget.ObsSpec:
        return retarget.ObsSpec((1,))

    def observe(self, ctx: retarget.StepContext) -> torch.Tensor:
        time.sleep(0.05)
        return torch.zeros(ctx.num_envs, 1)


def test_final_observations_are_booked_as_observations() -> None:
    registry = load_plugins()
    character = registry.get("character", "human").cls()
    cap = registry.get("termination", "episode_cap").cls
    env = RetargetEnv(character, default_motions()[:1], sensors=[Slow()],
                      terminations={"cap": cap(cap.Config(max_steps=1))},
                      options=EnvOptions(num_envs=2))  # fmt: skip
    env.reset()
    for key in env.seconds:
        env.seconds[key] = 0.0
    for _ in range(10):  # every step ends both episodes by time-out: two observations each
        env.step(torch.zeros(2, env.action_dim))
    sec = env.seconds
    # the Slow sensor is read for the final and the next observation: 2+ calls of 50 ms
    assert sec["observations"] > 0.9, sec
    assert sec["resets"] < 0.5 * sec["observations"], sec
    assert sec["rewards"] < 0.5 * sec["observations"], sec


def test_gather_refuses_a_bool_offset_as_needs_validation_does() -> None:
    import pytest

    from retarget.errors import PluginError
    from retarget.kinds.step import StepNeeds

    registry = load_plugins()
    env = RetargetEnv(registry.get("character", "human").cls(), default_motions()[:1],
                      options=EnvOptions(num_envs=1))  # fmt: skip
    with pytest.raises(PluginError, match=r"offsets \[True\]"):
        env.gather(StepNeeds(reference_offsets=(True,)))  # type: ignore[arg-type]
    env.gather(StepNeeds(reference_offsets=(2,)))
    assert 2 in env.step_needs.reference_offsets
