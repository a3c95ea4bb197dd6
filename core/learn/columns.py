"""Which columns of an observation group come from which source.

An environment that names its columns (``RetargetEnv`` does) exposes ``obs_layout``: for each
group, its sources in column order as ``(name, size)``. Algorithms use it to find one source
inside a group: the base of a residual policy, the columns a warm start carries over.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol, runtime_checkable

from retarget.errors import PluginError


@runtime_checkable
class NamedColumns(Protocol):
    """An environment whose observation columns are named by source."""

    @property
    def obs_layout(self) -> Mapping[str, Sequence[tuple[str, int]]]: ...


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
