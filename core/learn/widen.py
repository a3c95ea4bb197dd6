"""Carry trained weights into networks whose inputs changed (a new observer, a reordering).

A network's first linear layer is the only one whose shape depends on the observation; every
other tensor must match exactly. Columns for inputs the old network never saw start at zero
weight, so the widened network computes exactly what the old one did until training moves
those weights: a flat-ground walker keeps walking while it learns to use a height map.
"""

from __future__ import annotations

from collections.abc import Mapping

import torch
from torch import nn


def first_linear_weight(module: nn.Module) -> str:
    """State-dict key of the first ``nn.Linear`` weight (the layer that reads observations)."""
    for name, child in module.named_modules():
        if isinstance(child, nn.Linear):
            return f"{name}.weight"
    raise ValueError(f"{type(module).__name__} has no linear layer")


def widen_module(module: nn.Module, old: Mapping[str, torch.Tensor], index: torch.Tensor) -> None:
    """Load ``old`` (a state dict) into ``module``; its input columns follow ``index``.

    ``index[j]`` is the old input column feeding new column ``j``, or -1 for a new input.
    Raises ``ValueError`` naming the tensor whose shape does not fit.
    """
    first = first_linear_weight(module)
    merged = {}
    for key, new in module.state_dict().items():
        if key not in old:
            raise ValueError(f"the checkpoint has no '{key}'")
        value = old[key]
        if key == first:
            known = index >= 0
            too_few = known.any() and int(index.max()) >= value.shape[1]
            fits = value.shape[0] == new.shape[0] and not too_few
        else:
            fits = value.shape == new.shape
        if not fits:
            raise ValueError(
                f"'{key}' is {tuple(value.shape)} in the checkpoint, {tuple(new.shape)} here"
            )
        if key == first:
            weight = torch.zeros_like(new)
            weight[:, known] = value[:, index[known]].to(new.dtype)
            value = weight
        merged[key] = value
    module.load_state_dict(merged)


def widen_normalizer(
    module: nn.Module, old: Mapping[str, torch.Tensor], index: torch.Tensor, count: float
) -> None:
    """Running statistics of the kept columns, frozen; new columns start empty (mean 0,
    variance 0) and learn theirs, the whole weighted as ``count`` samples.

    The small count is what lets the new columns learn their scale: merged with a count of
    millions, their statistics would never move from the start, and a height map (a few cm
    spread) read unscaled would need weights ~30x larger than every other input, which Adam's
    fixed step size takes ~30x longer to grow. The kept columns are frozen because the weights
    that read them were learned with those statistics: merged with the new run's samples they
    move wherever the new run's states differ (a distilled three-point student fine-tuned by
    PPO visits falls and hard starts its distillation never did), and the same weights then
    compute another policy. Frozen, the warm-started network computes exactly what the old one
    did until training moves its weights.
    """
    known = index >= 0
    mean = torch.zeros_like(module.mean)
    var = torch.zeros_like(module.var)
    mean[known] = old["mean"][index[known]].to(mean.dtype)
    var[known] = old["var"][index[known]].to(var.dtype)
    total = torch.as_tensor(min(float(old["count"]), count), dtype=module.count.dtype)
    module.load_state_dict({"mean": mean, "var": var, "count": total, "frozen": known})


def sub_state(state: Mapping[str, torch.Tensor], prefix: str) -> dict[str, torch.Tensor]:
    """The entries of a flat state dict under ``prefix.`` with the prefix removed."""
    head = prefix + "."
    return {k[len(head):]: v for k, v in state.items() if k.startswith(head)}


def widen_group_normalizers(
    groups: nn.ModuleDict, old_state: Mapping[str, torch.Tensor],
    inputs: Mapping[str, torch.Tensor], count: float,
) -> None:
    """:func:`widen_normalizer` for each group of a ``GroupNormalizer`` (its ``groups``) from
    the source's flat ``obs_norm`` state; a group the source never had keeps its statistics
    (they come from the new run's data)."""
    for key, norm in groups.items():
        old = sub_state(old_state, f"groups.{key}")
        if old:
            widen_normalizer(norm, old, inputs[key], count)
