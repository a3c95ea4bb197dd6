"""Running mean/variance observation normalisation, one normaliser per observation group.

Observations mix metres, radians, m/s and newtons; without scaling the tanh layers saturate on
the large ones. Statistics are accumulated in float64 (Chan et al.'s parallel merge) so that
millions of samples do not lose precision, and applied in float32. The statistics only change
when :meth:`RunningNormalizer.update` is called: PPO updates them once per rollout, so every
observation of one rollout is scaled the same way.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, cast

import torch
from torch import nn

if TYPE_CHECKING:
    from retarget.kinds.comm import Comm


class RunningNormalizer(nn.Module):
    """``(x - mean) / sqrt(var + eps)``, clipped to ``[-clip, clip]``."""

    mean: torch.Tensor
    var: torch.Tensor
    count: torch.Tensor
    frozen: torch.Tensor

    def __init__(
        self, dim: int, *, clip: float = 10.0, eps: float = 1e-8, max_count: float | None = None
    ) -> None:
        super().__init__()
        self.clip, self.eps, self.max_count = clip, eps, max_count
        self.register_buffer("mean", torch.zeros(dim, dtype=torch.float64))
        self.register_buffer("var", torch.ones(dim, dtype=torch.float64))
        self.register_buffer("count", torch.zeros((), dtype=torch.float64))
        # columns whose statistics no longer change: the inputs a warm-started network was
        # trained on (retarget.learn.widen), so they keep meaning what its weights learned
        self.register_buffer("frozen", torch.zeros(dim, dtype=torch.bool))

    def _load_from_state_dict(self, state_dict: dict[str, Any], prefix: str, *args: Any,
                              **kwargs: Any) -> None:  # fmt: skip
        """States saved before ``frozen`` existed load with no column frozen."""
        state_dict.setdefault(prefix + "frozen", torch.zeros_like(self.frozen))
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    @torch.no_grad()
    def update(self, x: torch.Tensor) -> None:
        """Merge the statistics of a batch ``(..., dim)`` into the running ones."""
        x = x.reshape(-1, x.shape[-1]).double()
        if x.shape[0]:
            self.merge(x.shape[0], x.mean(0), x.var(0, unbiased=False))

    @torch.no_grad()
    def merge(self, n: float | torch.Tensor, mean: torch.Tensor, var: torch.Tensor) -> None:
        """Merge statistics of ``n`` samples (Chan et al.). With ``max_count`` the running
        count saturates, so old samples fade out: statistics that drift during training (the
        returns of an improving policy) are followed instead of averaged over all history.
        Frozen columns keep their mean and variance."""
        total = self.count + n
        delta = mean - self.mean
        m2 = self.var * self.count + var * n + delta.square() * self.count * n / total
        keep = ~self.frozen
        self.mean[keep] += (delta * n / total)[keep]
        self.var[keep] = (m2 / total)[keep]
        self.count.copy_(total if self.max_count is None else total.clamp(max=self.max_count))

    @torch.no_grad()
    def merge_ranks(
        self, comm: Comm, count: torch.Tensor, mean: torch.Tensor, var: torch.Tensor
    ) -> None:
        """Merge this rank's batch statistics and every other rank's, in rank order, so all
        ranks of a distributed run hold identical statistics (one rank: :meth:`merge`)."""
        for n, m, v in comm.all_stats(count, mean, var):
            if float(n) > 0:
                self.merge(n, m, v)

    @torch.no_grad()
    def update_ranks(self, comm: Comm, x: torch.Tensor) -> None:
        """:meth:`update` with the samples of every rank (see :meth:`merge_ranks`)."""
        x = x.reshape(-1, x.shape[-1]).double()
        n = torch.tensor(float(x.shape[0]), dtype=torch.float64)
        if x.shape[0]:
            self.merge_ranks(comm, n, x.mean(0), x.var(0, unbiased=False))
        else:
            self.merge_ranks(comm, n, self.mean.clone(), self.var.clone())

    def raw_stats(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``(count, mean, var)`` for merging into another normaliser."""
        return self.count.clone(), self.mean.clone(), self.var.clone()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        scale = (self.var + self.eps).rsqrt().float()
        return ((x - self.mean.float()) * scale).clamp(-self.clip, self.clip)


class GroupNormalizer(nn.Module):
    """A :class:`RunningNormalizer` per observation group (``actor``, ``critic``, ...)."""

    def __init__(self, dims: Mapping[str, int], *, clip: float = 10.0) -> None:
        super().__init__()
        self.groups = nn.ModuleDict({k: RunningNormalizer(d, clip=clip) for k, d in dims.items()})

    def normalizer(self, key: str) -> RunningNormalizer:
        """The running statistics of one observation group."""
        return cast(RunningNormalizer, self.groups[key])

    def update(self, obs: Mapping[str, torch.Tensor]) -> None:
        for key, norm in self.groups.items():
            norm.update(obs[key])

    def forward(self, obs: Mapping[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        return {key: norm(obs[key]) for key, norm in self.groups.items()}

    def group(self, key: str, x: torch.Tensor) -> torch.Tensor:
        return self.groups[key](x)
