"""Observation groups made of named sources, each computed once per step.

A *source* is anything that turns a :class:`StepContext` into ``(N, size)`` columns: the
environment's own proprioception and privileged reference, and every sensor and observer. A
*group* (``actor``, ``critic``, ``teacher``, ...) is a list of source names whose columns are
concatenated in that order. Sources are resolved once at construction, so a step only calls
them; what a source needs the step to gather is its ``needs()`` (only sources some group uses
count), and the environment fills exactly that.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import torch

from retarget.errors import RecipeError
from retarget.kinds.step import StepNeeds

if TYPE_CHECKING:
    from retarget.kinds import Observer, Sensor
    from retarget.kinds.state import Layout, StepContext


class ObsSource(Protocol):
    """One named block of observation columns."""

    name: str
    size: int
    shape: tuple[int, ...]  # of one environment's observation; size is its product

    def needs(self) -> StepNeeds: ...

    def compute(self, ctx: StepContext) -> torch.Tensor: ...

    def reset(self, env_ids: torch.Tensor) -> None:
        """New episodes in ``env_ids``: forget what the source held for them."""
        ...


@dataclass
class PluginSource:
    """A sensor or observer as a source: its ``observe``, its spec's size, its requirements."""

    plugin: Sensor | Observer
    name: str
    size: int
    shape: tuple[int, ...]

    @classmethod
    def of(cls, plugin: Sensor | Observer, layout: Layout) -> PluginSource:
        spec = plugin.spec(layout)
        return cls(plugin, plugin.name, spec.size, tuple(spec.shape))

    def needs(self) -> StepNeeds:
        return self.plugin.needs()

    def compute(self, ctx: StepContext) -> torch.Tensor:
        return self.plugin.observe(ctx)

    def reset(self, env_ids: torch.Tensor) -> None:
        self.plugin.reset(env_ids)


class ObservationManager:
    """Groups of sources: validated names, column layouts, and one pass per step."""

    def __init__(
        self, sources: Sequence[ObsSource], groups: Mapping[str, Sequence[str]]
    ) -> None:
        self.sources = {s.name: s for s in sources}
        self.groups = {g: list(names) for g, names in groups.items()}
        for group, names in self.groups.items():
            unknown = [s for s in names if s not in self.sources]
            if unknown:
                raise RecipeError(
                    f"observation group '{group}' names unknown sources {unknown}",
                    field=f"env.groups.{group}",
                    hint=f"available: {', '.join(self.sources)}",
                )
        used = {name for names in self.groups.values() for name in names}
        self.needs = StepNeeds()
        for name in used:
            self.needs = self.needs | self.sources[name].needs()

    def reset(self, env_ids: torch.Tensor) -> None:
        """New episodes in ``env_ids``: every source (sensor, observer, built-in) resets them."""
        for source in self.sources.values():
            source.reset(env_ids)

    @property
    def dims(self) -> dict[str, int]:
        return {g: sum(self.sources[s].size for s in names) for g, names in self.groups.items()}

    @property
    def layout(self) -> dict[str, list[tuple[str, int]]]:
        """Each group's sources in column order, ``(name, size)``."""
        return {g: [(s, self.sources[s].size) for s in names] for g, names in self.groups.items()}

    @property
    def shapes(self) -> dict[str, list[tuple[str, tuple[int, ...]]]]:
        """Each group's sources in column order, ``(name, shape)``: images keep their
        ``(C, H, W)``, so a network can give them a convolutional encoder."""
        return {g: [(s, self.sources[s].shape) for s in names] for g, names in self.groups.items()}

    def compute(
        self, ctx: StepContext, groups: Sequence[str] | None = None
    ) -> dict[str, torch.Tensor]:
        """Every group's (or only ``groups``') ``(N, D)`` observation (non-finite values
        zeroed); each source once."""
        cache: dict[str, torch.Tensor] = {}
        out = {}
        for group, names in self.groups.items():
            if groups is not None and group not in groups:
                continue
            parts = []
            for name in names:
                if name not in cache:
                    cache[name] = self.sources[name].compute(ctx).reshape(ctx.num_envs, -1)
                parts.append(cache[name])
            out[group] = torch.nan_to_num(torch.cat(parts, dim=-1), 0.0, 0.0, 0.0)
        return out
