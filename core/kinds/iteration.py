"""What one training iteration reports: a typed result instead of keys with special meaning.

The trainer logs ``stats`` (metrics.csv, TensorBoard, callbacks), counts ``samples`` toward the
run's budget when the algorithm learnt without stepping the environment (a pose estimator
reads rows of the motion library), and shows the ``headline`` figures on the progress bar.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

RL_HEADLINE = ("episode_return", "episode_length")
"""The progress bar's figures for a policy that steps episodes."""


@dataclass(frozen=True)
class IterationResult:
    """One iteration's figures.

    ``stats``: every figure of the iteration, finite floats by name (logged as they are).
    ``samples``: the samples it learnt from when it did not step the environment; ``None``
    when it did (the trainer counts the environment's own steps then).
    ``headline``: names in ``stats`` the progress bar shows, most important first.
    """

    stats: Mapping[str, float]
    samples: int | None = None
    headline: tuple[str, ...] = RL_HEADLINE

    def __post_init__(self) -> None:
        stats: dict[str, float] = {}
        for key, value in self.stats.items():
            try:
                stats[str(key)] = float(value)
            except (TypeError, ValueError):
                raise TypeError(
                    f"iteration statistic {key!r} must be a number, got {type(value).__name__}"
                ) from None
        object.__setattr__(self, "stats", stats)
        if self.samples is not None and (isinstance(self.samples, bool) or self.samples < 0):
            raise ValueError(f"samples must be a count >= 0, got {self.samples!r}")

    def non_finite(self) -> dict[str, float]:
        """The statistics that are NaN or infinite (a diverged update)."""
        return {k: float(v) for k, v in self.stats.items() if not math.isfinite(float(v))}


def as_result(value: IterationResult | Mapping[str, float]) -> IterationResult:
    """An algorithm's return as a result: a plain mapping (the contract before results
    were typed) is its statistics, with nothing counted beyond the environment's steps."""
    if isinstance(value, IterationResult):
        return value
    if isinstance(value, Mapping):
        return IterationResult(stats=dict(value))
    raise TypeError(
        f"train_iteration must return an IterationResult (or a dict of statistics), got "
        f"{type(value).__name__}"
    )
