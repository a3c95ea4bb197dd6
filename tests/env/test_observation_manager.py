"""Observation groups are lists of sources; each step gathers only what the used sources and
the reward and termination terms need."""

from __future__ import annotations

import pytest
import torch

from retarget import PluginError, StepNeeds
from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import idle_clip
from retarget.plugins.characters.human import Human
from retarget.plugins.rewards.scene_contact import SceneContact
from retarget.plugins.sensors.devices import ThreePoint
from retarget.plugins.sensors.full_body import FullBody

CLIP = idle_clip(2.0)


def _env(groups=None, sensors=(), rewards=None) -> RetargetEnv:
    return RetargetEnv(
        Human(), [CLIP], sensors=sensors, rewards=rewards,
        options=EnvOptions(num_envs=2, groups=groups),
    )  # fmt: skip


def test_default_groups_gather_the_critics_future_frames_only() -> None:
    env = _env(sensors=[ThreePoint()])
    assert env.groups == {
        "actor": ["three_point", "proprio"],
        "critic": ["three_point", "proprio", "privileged"],
    }
    assert env.step_needs == StepNeeds(reference_offsets=(1, 3, 6))
    env.reset()
    obs, *_ = env.step(torch.zeros(2, env.action_dim))
    assert sorted(env.last_context.ref.future) == [1, 3, 6]
    assert env.last_context.ref.scene_contacts is None  # nobody asked
    assert obs["critic"].shape == (2, env.obs_dims["critic"])


def test_unused_sources_gather_nothing_and_used_ones_add_their_frames() -> None:
    plain = _env(groups={"actor": ["three_point"]}, sensors=[ThreePoint()])
    assert plain.step_needs == StepNeeds()
    teacher = FullBody(FullBody.Config(offsets=(2,)))
    both = _env(groups={"actor": ["full_body"], "critic": ["privileged"]}, sensors=[teacher])
    assert both.step_needs.reference_offsets == (1, 2, 3, 6)
    assert both.obs_layout["actor"] == [("full_body", both.observation_size("full_body"))]


def test_a_reward_that_needs_scene_contacts_gets_them() -> None:
    env = _env(groups={"actor": ["proprio"]}, rewards={"contact": SceneContact()})
    assert env.step_needs.scene_contacts
    env.reset()
    env.step(torch.zeros(2, env.action_dim))
    labels = env.last_context.ref.scene_contacts
    assert labels is not None and labels.shape == (2, len(env.layout.body_groups))


def test_bad_needs_name_the_plugin_and_unknown_sources_name_the_group() -> None:
    class Backwards(ThreePoint):
        name = "backwards"

        def needs(self) -> StepNeeds:
            return StepNeeds(reference_offsets=(0,))

    with pytest.raises(PluginError, match="sensor backwards"):
        _env(sensors=[Backwards()])
    with pytest.raises(Exception, match=r"env\.groups\.actor"):
        _env(groups={"actor": ["proprio", "nope"]})
