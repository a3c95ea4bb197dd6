"""Reward and termination managers: weighted sums, failure penalties, per-term episode logs."""

from __future__ import annotations

from collections.abc import Mapping

import torch

from retarget.errors import PluginError
from retarget.kinds import RewardTerm, Termination
from retarget.kinds.state import StepContext


class RewardManager:
    """``sum_i w_i * term_i(ctx)``; zero-weight terms are skipped; sums kept per episode."""

    def __init__(self, terms: Mapping[str, RewardTerm], num_envs: int) -> None:
        self.terms = {k: t for k, t in terms.items() if t.config.weight != 0.0}
        self.names = list(self.terms)
        self.weights = torch.tensor([t.config.weight for t in self.terms.values()])
        self.episode_sums = torch.zeros(num_envs, len(self.terms))
        self._value_sums = torch.zeros(len(self.terms), dtype=torch.float64)
        self._value_count = 0

    def compute(self, ctx: StepContext, valid: torch.Tensor | None = None) -> torch.Tensor:
        """Weighted reward of the step, added into the per-term episode sums.

        Every term must return ``(N,)`` floats, finite wherever ``valid`` (environments whose
        physics did not blow up); anything else is a :class:`PluginError` naming the term.
        """
        if not self.terms:
            return torch.zeros(ctx.num_envs)
        parts = []
        for name, term in self.terms.items():
            value = term.compute(ctx)
            if (
                not isinstance(value, torch.Tensor)
                or tuple(value.shape) != (ctx.num_envs,)
                or not value.is_floating_point()
            ):
                got = (f"{tuple(value.shape)} {value.dtype}" if isinstance(value, torch.Tensor)
                       else type(value).__name__)  # fmt: skip
                raise PluginError(
                    f"compute() returned {got}; expected ({ctx.num_envs},) floats",
                    plugin=f"reward {term.name}", field=f"rewards.{name}",
                )
            parts.append(value.float())
        values = torch.stack(parts, dim=1)
        finite = torch.isfinite(values)
        if not bool(finite.all()):
            rows = finite.all(dim=1) | (~valid if valid is not None else False)
            if not bool(rows.all()):
                i = int((~finite[~rows]).any(dim=0).nonzero()[0])
                raise PluginError(
                    "compute() returned NaN or inf for an environment whose simulation is "
                    "finite",
                    plugin=f"reward {self.terms[self.names[i]].name}",
                    field=f"rewards.{self.names[i]}",
                )
        self._value_sums += torch.where(finite, values, 0.0).sum(dim=0).double()
        self._value_count += values.shape[0]
        weighted = values * self.weights
        self.episode_sums += weighted
        return weighted.sum(dim=1)

    def mean_values(self) -> dict[str, float]:
        """Each term's unweighted value averaged over every environment step computed so far
        (empty before the first step): how far into its kernel a term sits."""
        if not self._value_count:
            return {}
        means = self._value_sums / self._value_count
        return {name: float(v) for name, v in zip(self.names, means, strict=True)}

    def pop_episodes(self, env_ids: torch.Tensor) -> dict[str, float]:
        """Mean per-term episode sums of the finished ``env_ids``, then zero them."""
        if env_ids.numel() == 0:
            return {}
        sums = self.episode_sums[env_ids].mean(dim=0)
        self.episode_sums[env_ids] = 0.0
        return {name: float(v) for name, v in zip(self.names, sums, strict=True)}

    def reset(self, env_ids: torch.Tensor) -> None:
        """A new episode in ``env_ids`` (however it started: after an episode's end, a
        placement, a blown-up simulation, a restored checkpoint): every term forgets them."""
        for term in self.terms.values():
            term.reset(env_ids)


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
            if (
                not isinstance(hit, torch.Tensor)
                or tuple(hit.shape) != (n,)
                or hit.dtype != torch.bool
            ):
                got = (f"{tuple(hit.shape)} {hit.dtype}" if isinstance(hit, torch.Tensor)
                       else type(hit).__name__)  # fmt: skip
                raise PluginError(
                    f"check() returned {got}; expected ({n},) bool",
                    plugin=f"termination {term.name}", field=f"terminations.{name}",
                )
            self.counts[name] += int(hit.sum())
            if term.time_out:
                timed_out |= hit
            else:
                failed |= hit
        return failed, timed_out & ~failed

    def reset(self, env_ids: torch.Tensor) -> None:
        """New episodes in ``env_ids``: every term forgets them."""
        for term in self.terms.values():
            term.reset(env_ids)
