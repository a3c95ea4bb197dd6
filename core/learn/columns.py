"""Which columns of an observation group come from which source.

An environment that names its columns (``RetargetEnv`` does) exposes ``obs_layout``: for each
group, its sources in column order as ``(name, size)``. Algorithms use it to find one source
inside a group: the base of a residual policy, the columns a warm start carries over.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from retarget.errors import PluginError


@runtime_checkable
class NamedColumns(Protocol):
    """An environment whose observation columns are named by source."""

    @property
    def obs_layout(self) -> Mapping[str, Sequence[tuple[str, int]]]: ...


@runtime_checkable
class ShapedColumns(Protocol):
    """An environment that also says the shape of each source (``RetargetEnv`` does)."""

    @property
    def obs_shapes(self) -> Mapping[str, Sequence[tuple[str, tuple[int, ...]]]]: ...


@dataclass(frozen=True)
class ImageInput:
    """An image source inside an observation group: its first column and ``(C, H, W)``."""

    name: str
    start: int
    shape: tuple[int, int, int]

    @property
    def size(self) -> int:
        c, h, w = self.shape
        return c * h * w


def image_inputs(env: object, group: str) -> tuple[ImageInput, ...]:
    """The image sources (3-D observations) of ``group``; none for an env without shapes."""
    if not isinstance(env, ShapedColumns):
        return ()
    found, start = [], 0
    for name, shape in env.obs_shapes.get(group, ()):
        if len(shape) == 3:
            found.append(ImageInput(name, start, (int(shape[0]), int(shape[1]), int(shape[2]))))
        size = 1
        for s in shape:
            size *= int(s)
        start += size
    return tuple(found)


def source_columns(env: object, group: str, source: str) -> slice:
    """The columns of ``source`` inside observation ``group`` of ``env``."""
    if not isinstance(env, NamedColumns):
        raise PluginError(
            f"the environment does not name its observation columns, so source '{source}' "
            "cannot be found",
            plugin=type(env).__name__,
        )
    layout = env.obs_layout
    if group not in layout:
        raise PluginError(f"no observation group '{group}' (has {', '.join(layout)})")
    start = 0
    for name, size in layout[group]:
        if name == source:
            return slice(start, start + int(size))
        start += int(size)
    names = ", ".join(name for name, _ in layout[group])
    raise PluginError(
        f"observation group '{group}' has no source '{source}' (has {names})",
        hint=f"add the sensor '{source}' to the recipe's sensors",
    )


def residual_columns(env: Any, group: str, source: str | None, plugin: str) -> slice | None:
    """The columns a residual policy's output is added to (``algorithm.residual``), checked to
    be one value per action; ``None`` when the policy is not residual."""
    if source is None:
        return None
    found = source_columns(env, group, source)
    if found.stop - found.start != env.action_dim:
        raise PluginError(
            f"residual source '{source}' has {found.stop - found.start} columns, the action "
            f"{env.action_dim}",
            plugin=plugin,
            field="algorithm.residual",
        )
    return found
