"""What the imitation terms share: name resolution and the weighted squared distance (Eq. 11).

App. A defines every imitation distance as ``d = sum_i w_i ||x_sim,i - x_ref,i||^2`` over
joints or links, with per-character weights. ``reduce="mean"`` divides by the sum of weights
instead, which keeps a kernel sensitivity ``k`` meaningful across characters with very different
joint or link counts; ``"sum"`` is the paper's form and the default.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Literal

from retarget import Layout, PluginError

if TYPE_CHECKING:
    import torch

Reduce = Literal["sum", "mean"]
ROOT = "root"
"""Alias of the root body (the one carrying the free joint, first in ``layout.body_names``)."""


def hinge_count(layout: Layout, plugin: str) -> int:
    """Number of hinge joints after the free root; qpos[7:] and qvel[6:] hold them in order."""
    n = len(layout.joint_names)
    if layout.nq - 7 != n or layout.nv - 6 != n:
        raise PluginError(
            f"expected a free root followed by {n} one-dof joints (nq={7 + n}, nv={6 + n}), "
            f"got nq={layout.nq}, nv={layout.nv}: ball or slide joints are not supported",
            plugin=plugin,
        )
    return n


def joint_weight_tensor(layout: Layout, plugin: str) -> torch.Tensor:
    """Per-hinge reward weights from the character (missing weights count as 1)."""
    import torch
    n = hinge_count(layout, plugin)
    weights = layout.joint_weights or (1.0,) * n
    if len(weights) != n:
        raise PluginError(f"layout has {len(weights)} joint weights for {n} joints", plugin=plugin)
    return torch.tensor(weights, dtype=torch.float32)


def resolve_bodies(layout: Layout, names: Sequence[str] | None, plugin: str) -> torch.Tensor:
    """Body indices for a list of group names, body names or ``root``; ``None`` is all bodies.

    Group names win over body names (``head`` may be both a body and, in some characters, a
    group); duplicates are dropped so a body listed twice does not weigh twice.
    """
    import torch
    if names is None:
        return torch.arange(layout.num_bodies)
    picked: list[int] = []
    for name in names:
        if name in layout.body_groups:
            found = list(layout.body_groups[name])
        elif name in layout.body_names:
            found = [layout.body_names.index(name)]
        elif name == ROOT:
            found = [0]
        else:
            groups = ", ".join(sorted(layout.body_groups))
            raise PluginError(
                f"'{name}' is neither a body group ({groups}), a body nor '{ROOT}'",
                plugin=plugin,
            )
        picked.extend(i for i in found if i not in picked)
    if not picked:
        raise PluginError("the selected bodies are empty", plugin=plugin)
    return torch.tensor(picked, dtype=torch.long)


def weighted_sq_distance(
    diff: torch.Tensor, weights: torch.Tensor, reduce: Reduce = "sum"
) -> torch.Tensor:
    """``sum_i w_i ||diff_i||^2`` over dim 1 of ``diff`` (N, K) or (N, K, 3) -> (N,)."""
    sq = diff.square()
    if sq.ndim == 3:
        sq = sq.sum(dim=-1)
    d = (sq * weights).sum(dim=-1)
    if reduce == "mean":
        d = d / weights.sum().clamp_min(1e-9)
    return d
