"""Reward and termination managers: weighted sums, failure penalties, per-term episode logs."""

from __future__ import annotations

from collections.abc import Mapping

import torch

from retarget.kinds import RewardTerm, Termination
from retarget.state import StepContext


class RewardManager:
    """``sum_i w_i * term_i(ctx)``; zero-weight terms are skipped; sums kept per episode.

    Terms marked ``on_failure`` (the fail penalty) are applied through their ``penalty(failed)``
    once the step's failures are known.
    """

    def __init__(self, terms: Mapping[str, RewardTerm], num_envs: int) -> None:
        self.terms = {k: t for k, t in terms.items() if t.config.weight != 0.0}
        self.names = list(self.terms)
        self.weights = torch.tensor([t.config.weight for t in self.terms.values()])
        self.episode_sums = torch.zeros(num_envs, len(self.terms))
        self._step_values = torch.zeros(num_envs, len(self.terms))

    def compute(self, ctx: StepContext) -> torch.Tensor:
        """Weighted reward of the step without failure penalties (added by :meth:`penalize`)."""
        if not self.terms:
            return torch.zeros(ctx.num_envs)
        values = torch.stack([t.compute(ctx) for t in self.terms.values()], dim=1)
        self._step_values = values * self.weights
        return self._step_values.sum(dim=1)

    def penalize(self, failed: torch.Tensor) -> torch.Tensor:
        """Failure penalties of the step (N,), added into the per-term sums too."""
        extra = torch.zeros(failed.shape[0])
        for i, term in enumerate(self.terms.values()):
            if getattr(term, "on_failure", False):
                value = term.config.weight * term.penalty(failed)
                self._step_values[:, i] += value
                extra += value
        self.episode_sums += self._step_values
        return extra

    def pop_episodes(self, env_ids: torch.Tensor) -> dict[str, float]:
        """Mean per-term episode sums of the finished ``env_ids``, then zero them."""
        if env_ids.numel() == 0:
            return {}
        sums = self.episode_sums[env_ids].mean(dim=0)
        self.episode_sums[env_ids] = 0.0
        for term in self.terms.values():
            term.reset(env_ids)
        return {name: float(v) for name, v in zip(self.names, sums, strict=True)}


class TerminationManager:
    """Splits terminations into failures (terminated) and time-outs (truncated)."""

    def __init__(self, terms: Mapping[str, Termination]) -> None:
        self.terms = dict(terms)
        self.counts = dict.fromkeys(self.terms, 0)

    def check(self, ctx: StepContext) -> tuple[torch.Tensor, torch.Tensor]:
        n = ctx.num_envs
        failed = torch.zeros(n, dtype=torch.bool)
        timed_out = torch.zeros(n, dtype=torch.bool)
        for name, term in self.terms.items():
            hit = term.check(ctx)
            self.counts[name] += int(hit.sum())
            if term.time_out:
                timed_out |= hit
            else:
                failed |= hit
        return failed, timed_out & ~failed

    def reset(self, env_ids: torch.Tensor) -> None:
        for term in self.terms.values():
            term.reset(env_ids)
