"""Rollout storage ``(T, N, ...)`` and generalised advantage estimation.

Failures and time-outs end an episode differently. A *terminated* environment (the character
fell) has no future: its next value is zero. A *truncated* one (time limit, end of the clip)
would have gone on, so its next value is the critic's estimate for the observation it ended
in (``bootstrap``, computed from ``info["final_obs"]`` because the environment has already
reset by the time ``step`` returns). In both cases the advantage trace is cut, since the next
stored step belongs to a new episode.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import torch


class RolloutStorage:
    """Preallocated buffers for ``T`` steps of ``N`` environments (no per-step allocation)."""

    def __init__(self, steps: int, num_envs: int, obs_dims: Mapping[str, int], action_dim: int):
        self.steps, self.num_envs = steps, num_envs
        t, n = steps, num_envs
        self.obs = {k: torch.zeros(t, n, d) for k, d in obs_dims.items()}
        self.actions = torch.zeros(t, n, action_dim)
        self.log_probs = torch.zeros(t, n)
        self.values = torch.zeros(t, n)
        self.rewards = torch.zeros(t, n)
        self.terminated = torch.zeros(t, n, dtype=torch.bool)
        self.truncated = torch.zeros(t, n, dtype=torch.bool)
        self.bootstrap = torch.zeros(t, n)  # V(final obs) where truncated, else 0
        self.advantages = torch.zeros(t, n)
        self.returns = torch.zeros(t, n)
        self.step = 0

    def add(
        self,
        obs: Mapping[str, torch.Tensor],
        actions: torch.Tensor,
        log_probs: torch.Tensor,
        values: torch.Tensor,
        rewards: torch.Tensor,
        terminated: torch.Tensor,
        truncated: torch.Tensor,
        bootstrap: torch.Tensor | None,
    ) -> None:
        t = self.step
        for key, buf in self.obs.items():
            buf[t] = obs[key]
        self.actions[t] = actions
        self.log_probs[t] = log_probs
        self.values[t] = values
        self.rewards[t] = rewards
        self.terminated[t] = terminated
        self.truncated[t] = truncated
        if bootstrap is None:
            self.bootstrap[t].zero_()
        else:
            self.bootstrap[t] = bootstrap
        self.step += 1

    def clear(self) -> None:
        self.step = 0

    def compute_returns(self, last_values: torch.Tensor, gamma: float, lam: float) -> None:
        """Fill ``advantages`` and ``returns`` (= advantages + values) with GAE."""
        self.advantages.copy_(
            gae(
                self.rewards,
                self.values,
                last_values,
                self.terminated,
                self.truncated,
                self.bootstrap,
                gamma,
                lam,
            )
        )
        torch.add(self.advantages, self.values, out=self.returns)

    def minibatches(
        self,
        count: int,
        generator: torch.Generator | None,
        extra: Mapping[str, torch.Tensor] | None = None,
    ) -> Iterator[dict[str, torch.Tensor]]:
        """``count`` random disjoint minibatches covering every sample once (one epoch);
        ``extra``: more per-sample tensors ``(T * N, ...)`` sliced the same way."""
        total = self.steps * self.num_envs
        perm = torch.randperm(total, generator=generator)
        flat = {
            "actions": self.actions.reshape(total, -1),
            "log_probs": self.log_probs.reshape(total),
            "values": self.values.reshape(total),
            "advantages": self.advantages.reshape(total),
            "returns": self.returns.reshape(total),
            **{f"obs/{k}": v.reshape(total, -1) for k, v in self.obs.items()},
            **(extra or {}),
        }
        for idx in perm.tensor_split(count):
            yield {k: v[idx] for k, v in flat.items()}


def gae(
    rewards: torch.Tensor,
    values: torch.Tensor,
    last_values: torch.Tensor,
    terminated: torch.Tensor,
    truncated: torch.Tensor,
    bootstrap: torch.Tensor,
    gamma: float,
    lam: float,
) -> torch.Tensor:
    """Advantages ``(T, N)`` by the backward GAE recursion.

    ``values[t]`` is V(o_t); ``last_values`` is V(o_T) of the observation after the last step;
    ``bootstrap[t]`` is V(final obs) for environments truncated at step ``t``.
    """
    steps = rewards.shape[0]
    advantages = torch.zeros_like(rewards)
    running = torch.zeros_like(last_values)
    next_values = last_values
    for t in reversed(range(steps)):
        done = terminated[t] | truncated[t]
        alive = (~done).float()
        # the value the step leads to: the next stored state, V(final obs) on time-outs,
        # nothing on failures
        target = (
            alive * next_values + truncated[t].float() * (~terminated[t]).float() * (bootstrap[t])
        )
        delta = rewards[t] + gamma * target - values[t]
        running = delta + gamma * lam * alive * running
        advantages[t] = running
        next_values = values[t]
    return advantages
