"""Evaluation metrics as terms: each one small class that sees every step and reports per run.

The runner (:mod:`retarget.eval.runner`) steps a batch of runs and hands each term an
:class:`EvalStep`; at the batch's end a term returns its per-run values. How those aggregate
over runs (a mean, the worst run, or a rate pooled over seconds or steps) and in which unit
they are reported is declared in the term's :class:`Column` s, so a new metric (for example a
kinematic estimator's) is one class and appears in ``retarget eval``'s table without touching
the runner.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

if TYPE_CHECKING:
    import torch

    from retarget.eval.metrics import StepMetrics
    from retarget.kinds.state import StepContext


@dataclass(frozen=True)
class Column:
    """One reported figure: the per-run values under ``key``, summarised as ``label``.

    ``reduce``: ``mean`` over runs (NaN runs ignored), ``max`` over runs, or ``rate``: the sum
    over runs divided by the sum of the per-run column ``per`` (``seconds`` or ``steps``, which
    the runner always records), times ``factor``. Values are multiplied by ``scale`` (metres
    to millimetres, radians to degrees).
    """

    key: str
    label: str
    scale: float = 1.0
    reduce: Literal["mean", "max", "rate"] = "mean"
    per: str = "seconds"
    factor: float = 1.0


@dataclass
class EvalStep:
    """What a term sees at one step of a batch of runs, all ``(N,)`` unless said otherwise."""

    ctx: StepContext
    metrics: StepMetrics
    step: int
    alive: torch.Tensor  # bool: the run is still inside its clip and time limit
    ok: torch.Tensor  # bool: alive and not yet failed; tracking errors count only these


@dataclass
class EvalBatch:
    """A finished batch: its first ``runs`` environments are real runs, the rest padding."""

    runs: int
    available: torch.Tensor  # steps each run could last (clip end or time limit)
    failed_at: torch.Tensor  # step at which tracking failed; > available if it never did
    tracked: torch.Tensor  # steps counted as tracked (ok)
    dt: float


class MetricTerm(ABC):
    """One metric: ``start`` for a batch of ``n`` runs, ``update`` every step, ``finish``
    returns per-run values (length ``batch.runs``) for each of its columns' keys."""

    columns: Sequence[Column] = ()

    def start(self, n: int) -> None:  # noqa: B027 - terms without state need nothing
        """Reset per-batch state for ``n`` environments."""

    def update(self, step: EvalStep) -> None:  # noqa: B027 - terms read only the batch's end
        """Accumulate one step."""

    @abstractmethod
    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]: ...


def summarise(
    columns: Sequence[Column], per_run: Mapping[str, np.ndarray], mask: np.ndarray
) -> dict[str, float]:
    """The reported figures of the runs selected by ``mask``."""
    out: dict[str, float] = {}
    for col in columns:
        values = per_run[col.key][mask]
        if col.reduce == "rate":
            total = per_run[col.per][mask].sum()
            value = values.sum() / max(total, 1e-9) * col.factor
        elif not np.isfinite(values).any():  # e.g. errors over successful runs, none was
            value = np.nan
        elif col.reduce == "max":
            value = np.nanmax(values)
        else:
            value = np.nanmean(values)
        out[col.label] = float(value * col.scale)
    return out
