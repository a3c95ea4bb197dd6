"""Reward terms hear of every new episode: after an episode's end, a placement, a blown-up
simulation and a restored checkpoint (they kept stale per-env state in the last three)."""

from __future__ import annotations

import torch

import retarget
from retarget.env import RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.registry.loader import load_plugins


class Counting(retarget.RewardTerm):
    """Counts, per environment, the resets it was told of."""

    name = "counting"

    def bind(self, layout: retarget.Layout) -> None:
        self.resets: torch.Tensor | None = None

    def compute(self, ctx: retarget.StepContext) -> torch.Tensor:
        if self.resets is None:
            self.resets = torch.zeros(ctx.num_envs, dtype=torch.long)
        return torch.zeros(ctx.num_envs)

    def reset(self, env_ids: torch.Tensor) -> None:
        if self.resets is not None:
            self.resets[env_ids] += 1


def _env() -> tuple[RetargetEnv, Counting]:
    character = load_plugins().get("character", "human").cls()
    term = Counting(Counting.Config(weight=1.0))
    from retarget.env import EnvOptions

    env = RetargetEnv(character, default_motions()[:2], rewards={"counting": term},
                      options=EnvOptions(num_envs=4))  # fmt: skip
    env.reset()
    env.step(torch.zeros(4, env.action_dim))  # the term now holds per-env state
    return env, term


def test_placement_and_restore_reset_every_term() -> None:
    env, term = _env()
    before = term.resets.clone()
    env.place(torch.zeros(4, dtype=torch.long), torch.zeros(4, dtype=torch.long))
    assert torch.equal(term.resets, before + 1)
    env.load_state_dict(env.state_dict())
    assert torch.equal(term.resets, before + 2)


def test_a_blown_up_env_resets_its_terms() -> None:
    env, term = _env()
    before = term.resets.clone()
    action = torch.zeros(4, env.action_dim)
    action[2] = float("nan")  # a broken action ends env 2 as a failure
    env.step(action)
    assert term.resets[2] == before[2] + 1 and torch.equal(term.resets[[0, 1, 3]],
                                                           before[[0, 1, 3]])  # fmt: skip
    before = term.resets.clone()
    env.sim._qvel[1] = 1e9  # env 1's physics explodes in the next step: it is put back
    bad = env.step_physics(torch.zeros(4, env.action_dim))
    assert bool(bad[1]) and term.resets[1] == before[1] + 1


def test_nan_action_counts_survive_a_checkpoint() -> None:
    env, _ = _env()
    action = torch.zeros(4, env.action_dim)
    action[1] = float("nan")
    env.step(action)
    assert env.nan_actions == 1
    state = env.state_dict()
    again, _ = _env()
    again.load_state_dict(state)
    assert again.nan_actions == 1 and again.nan_resets == env.nan_resets
