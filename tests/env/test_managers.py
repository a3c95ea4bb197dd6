"""Reward and termination managers name the plugin that returned the wrong thing."""

from __future__ import annotations

import pytest
import torch

import retarget
from retarget.env.managers import RewardManager, TerminationManager
from retarget.errors import PluginError
from retarget.testing import fake_context


class Returns(retarget.RewardTerm):
    """Returns whatever the test sets."""

    name = "returns"
    value: object = None

    def compute(self, ctx):
        return self.value(ctx)  # type: ignore[operator]


class Ends(retarget.Termination):
    """Ends whatever the test sets."""

    name = "ends"
    value: object = None

    def check(self, ctx):
        return self.value(ctx)  # type: ignore[operator]


@pytest.mark.parametrize(
    ("value", "needle"),
    [
        (lambda ctx: torch.zeros(ctx.num_envs, 2), r"expected \(5,\) floats"),
        (lambda ctx: torch.zeros(ctx.num_envs, dtype=torch.long), r"expected \(5,\) floats"),
        (lambda ctx: 1.0, "returned float"),
        (lambda ctx: torch.full((ctx.num_envs,), float("nan")), "NaN"),
    ],
)
def test_reward_that_breaks_its_contract_is_named(value, needle) -> None:
    term = Returns()
    term.value = value
    manager = RewardManager({"mine": term}, 5)
    with pytest.raises(PluginError, match=needle) as err:
        manager.compute(fake_context(num_envs=5))
    assert "reward returns" in str(err.value) and err.value.field == "rewards.mine"


def test_nan_where_the_physics_blew_up_is_not_the_rewards_fault() -> None:
    term = Returns()
    term.value = lambda ctx: torch.tensor([1.0, float("nan"), 1.0])
    manager = RewardManager({"mine": term}, 3)
    valid = torch.tensor([True, False, True])
    out = manager.compute(fake_context(num_envs=3), valid=valid)
    assert out[0] == 1.0 and out[2] == 1.0


def test_termination_must_return_bools() -> None:
    term = Ends()
    term.value = lambda ctx: torch.zeros(ctx.num_envs)
    with pytest.raises(PluginError, match=r"expected \(4,\) bool") as err:
        TerminationManager({"stop": term}).check(fake_context(num_envs=4))
    assert "termination ends" in str(err.value)
