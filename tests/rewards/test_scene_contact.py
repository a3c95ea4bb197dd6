"""``contact`` (QuestEnvSim Eq. 3): contract, hand-computed values, real contact forces."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch

from retarget import PluginError
from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.rewards.scene_contact import LINKS, SceneContact
from retarget.sim.world import build_world
from retarget.testing import fake_context, parametrize_with_checks

HUMAN = build_world(Human()).layout


@parametrize_with_checks([SceneContact])
def test_contact_reward_contract(plugin, check) -> None:
    check(plugin)


def _ctx(up: dict[str, float], total: dict[str, float], labels: list[str], n: int = 1):
    """One human step: the given bodies carry the given forces; ``labels`` groups are True."""
    ctx = fake_context(HUMAN, n, seed=0)
    f_up = torch.zeros(n, HUMAN.num_bodies)
    f_all = torch.zeros(n, HUMAN.num_bodies)
    for name, value in up.items():
        f_up[:, HUMAN.body_names.index(name)] = value
    for name, value in total.items():
        f_all[:, HUMAN.body_names.index(name)] = value
    groups = list(HUMAN.body_groups)
    lab = torch.zeros(n, len(groups), dtype=torch.bool)
    for g in labels:
        lab[:, groups.index(g)] = True
    sim = replace(ctx.sim, contact_force_up=f_up, contact_force=f_all)
    return replace(ctx, sim=sim, ref=replace(ctx.ref, scene_contacts=lab))


def _value(term: SceneContact, ctx) -> float:
    term.bind(ctx.layout)
    out = term.compute(ctx)
    assert out.dtype == torch.float32 and out.shape == (ctx.num_envs,)
    return float(out[0])


def test_contact_reward_hand_computed() -> None:
    term = SceneContact(SceneContact.Config(k=0.5))
    # standing: both feet carry weight and are labelled, nothing else -> exp(0) = 1
    stand = {"l_foot": 300.0, "r_foot": 300.0}
    assert _value(term, _ctx(stand, stand, ["left_foot", "right_foot"])) == pytest.approx(1.0)
    # seated by the labels, but the pelvis carries only 49 N up: one mismatch -> exp(-0.5 * 1)
    seat = {**stand, "pelvis": 49.0}
    ctx = _ctx(seat, seat, ["left_foot", "right_foot", "pelvis"])
    assert _value(term, ctx) == pytest.approx(math.exp(-0.5))
    # heel and toes are one link: 30 N + 30 N = 60 N > 50 N up on the left foot; the right
    # foot unloaded and the left hand pressing (not labelled): two mismatches -> exp(-0.5 sqrt 2)
    split = {"l_foot": 30.0, "l_toes": 30.0, "l_hand": 80.0}
    ctx = _ctx(split, split, ["left_foot", "right_foot"])
    assert _value(term, ctx) == pytest.approx(math.exp(-0.5 * math.sqrt(2.0)))
    # a back leaning on a backrest: 200 N sideways, 10 N up. The paper's rule (up) ignores it;
    # measuring the magnitude counts it.
    lean_up, lean_all = {**stand, "chest": 10.0}, {**stand, "chest": 200.0}
    ctx = _ctx(lean_up, lean_all, ["left_foot", "right_foot", "spine"])
    assert _value(term, ctx) == pytest.approx(math.exp(-0.5))
    total = SceneContact(SceneContact.Config(k=0.5, measure="total"))
    assert _value(total, ctx) == pytest.approx(1.0)


def test_contact_reward_errors_name_the_plugin() -> None:
    with pytest.raises(PluginError, match=r"contact.*'nose'"):
        SceneContact(SceneContact.Config(groups=("pelvis", "nose"))).bind(HUMAN)
    term = SceneContact()
    term.bind(HUMAN)
    ctx = fake_context(HUMAN, 2, seed=0)
    with pytest.raises(PluginError, match="scene contact labels"):
        term.compute(replace(ctx, ref=replace(ctx.ref, scene_contacts=None)))
    assert set(LINKS) <= set(HUMAN.body_groups)


def test_contact_reward_on_real_contact_forces() -> None:
    """A simulated human standing on the floor: its feet carry its weight upward (> 50 N each)
    and nothing else touches, as the idle clip's floor labels say; the reward is 1."""
    idle = default_motions(names=("idle",))
    term = SceneContact()
    env = RetargetEnv(
        Human(), idle, rewards={"contact": term}, options=EnvOptions(num_envs=2), seed=0
    )
    env.place(torch.zeros(2, dtype=torch.long), torch.tensor([0, 30]))
    for _ in range(3):
        env.step(torch.zeros(2, env.action_dim))
    ctx = env.last_context
    weight = float(env.world.model.body_subtreemass[1]) * 9.81
    assert ctx.sim.contact_force_up.sum(-1).min() > 0.5 * weight
    state = term.sim_contacts(ctx)
    feet = [term.config.groups.index(g) for g in ("left_foot", "right_foot")]
    assert state[:, feet].all() and not state[:, 2:].any()
    labels = ctx.ref.scene_contacts
    groups = list(env.layout.body_groups)
    assert labels[:, groups.index("left_foot")].all()
    assert not labels[:, groups.index("pelvis")].any()
    assert torch.allclose(term.compute(ctx), torch.ones(2))
