"""``retarget train --init-from RUN``: a new run that starts from another run's weights.

The two recipes may differ in anything the networks do not see (scene, rewards, terminations,
clips) and in which sensors and observers feed them: inputs are matched by source name, so a
policy trained on flat ground can be given a height map. Inputs the old run had and the new
one lacks are dropped; new ones start at zero weight (see :mod:`retarget.learn.widen`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import torch

from retarget.errors import RecipeError
from retarget.kinds import Algorithm
from retarget.kinds.capabilities import WarmStartable, require
from retarget.registry import Registry
from retarget.train.load import load_run
from retarget.train.run_dir import LOCK

INIT_FROM = "init_from.txt"  # in the new run's directory: the checkpoint it started from
Layout = Mapping[str, Sequence[tuple[str, int]]]


@dataclass
class WarmStart:
    """What was carried over: the checkpoint, and per group the kept, new and dropped sources."""

    checkpoint: Path
    kept: dict[str, list[str]]
    new: dict[str, list[str]]
    dropped: dict[str, list[str]]
    inputs: dict[str, torch.Tensor] = field(default_factory=dict)
    """Per group, the old column feeding each new column (-1: new), as :func:`input_maps`."""

    def summary(self) -> str:
        parts = []
        for group in self.kept:
            line = f"{group}: kept {', '.join(self.kept[group]) or 'nothing'}"
            if self.new[group]:
                line += f"; new (zero weight) {', '.join(self.new[group])}"
            if self.dropped[group]:
                line += f"; dropped {', '.join(self.dropped[group])}"
            parts.append(line)
        return "\n".join(parts)


def input_maps(new: Layout, old: Layout) -> tuple[dict[str, torch.Tensor], WarmStart]:
    """For each group of ``new``: the old column feeding each new column (-1: a new input).

    A source matches by name and size within the same group; one whose size changed (an
    observer with another resolution) counts as new.
    """
    maps: dict[str, torch.Tensor] = {}
    info = WarmStart(Path(), {}, {}, {})
    for group, sources in new.items():
        offsets, at = {}, 0
        for name, size in old.get(group, ()):
            offsets[name] = (at, size)
            at += size
        columns: list[torch.Tensor] = []
        kept, added = [], []
        for name, size in sources:
            start, old_size = offsets.get(name, (0, -1))
            if old_size == size:
                columns.append(torch.arange(start, start + size))
                kept.append(name)
            else:
                columns.append(torch.full((size,), -1))
                added.append(name)
        maps[group] = torch.cat(columns) if columns else torch.zeros(0, dtype=torch.long)
        info.kept[group], info.new[group] = kept, added
        info.dropped[group] = [n for n in offsets if n not in kept]
    return maps, info


def warm_start(
    algorithm: Algorithm, layout: Layout, source: str | Path, registry: Registry
) -> WarmStart:
    """Load ``source``'s latest checkpoint into ``algorithm`` (already set up for the new env
    whose observation ``layout`` is given). Errors name the checkpoint and what did not fit."""
    old = load_run(source, registry, num_envs=1)
    maps, info = input_maps(layout, old.env.obs_layout)
    info.checkpoint, info.inputs = old.checkpoint, maps
    if not any(info.kept.values()):
        raise RecipeError(
            "the new run observes nothing the source run observed",
            file=str(old.checkpoint),
            hint="--init-from needs at least one sensor in common",
        )
    theirs = getattr(getattr(old.algorithm, "config", None), "residual", None)
    ours = getattr(getattr(algorithm, "config", None), "residual", None)
    if theirs != ours:
        raise RecipeError(
            f"the source run's policy adds {theirs or 'nothing'} to its network's output, this "
            f"run's {ours or 'nothing'}: the network would start from other actions",
            file=str(old.run / LOCK),
            field="algorithm.residual",
            hint=f"--set algorithm.residual={theirs or 'null'}",
        )
    starts = require(algorithm, WarmStartable, hint="train from scratch (drop --init-from)")
    try:
        starts.warm_start(old.algorithm.state_dict(), maps)
    except (ValueError, KeyError) as exc:
        raise RecipeError(
            f"cannot start from {old.checkpoint}: {exc}",
            file=str(old.run / LOCK),
            field="algorithm",
            hint="the network sizes (algorithm.actor_hidden, critic_hidden) and the character "
            "(its action count) must match the source run",
        ) from None
    return info
