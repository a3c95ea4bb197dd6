"""The hooks a plugin module can implement. Every hook only *registers* classes.

A plugin module (named by an entry point in the ``retarget`` group) implements any of these
with ``@retarget.hookimpl``; each receives a ``register(cls, *, name=None, aliases=())``
callable. Behaviour lives in the typed base classes of :mod:`retarget.kinds`, because pluggy
does not type-check hook implementations.

Example::

    import retarget

    @retarget.hookimpl
    def register_rewards(register):
        register(TailSwingReward)
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Protocol

import pluggy

if TYPE_CHECKING:
    from retarget.kinds.base import Plugin

PROJECT = "retarget"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)

class Registrar(Protocol):
    """What every ``register_*`` hook receives: ``register(cls, name=..., aliases=...)``."""

    def __call__(
        self, cls: type[Plugin], *, name: str | None = None, aliases: Iterable[str] = ()
    ) -> None: ...


@hookspec
def register_characters(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Character` subclasses (bodies to drive)."""


@hookspec
def register_sensors(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Sensor` subclasses (headset/controller/camera signals)."""


@hookspec
def register_observers(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Observer` subclasses (height maps, point clouds)."""


@hookspec
def register_scenes(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Scene` subclasses (floors, chairs, boxes, meshes)."""


@hookspec
def register_rewards(register: Registrar) -> None:
    """Register :class:`retarget.kinds.RewardTerm` subclasses."""


@hookspec
def register_terminations(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Termination` subclasses."""


@hookspec
def register_algorithms(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Algorithm` subclasses (PPO, distillation, ...)."""


@hookspec
def register_motion_formats(register: Registrar) -> None:
    """Register :class:`retarget.kinds.MotionFormat` subclasses (BVH, recordings, ...)."""


@hookspec
def register_commands(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Command` subclasses (extra ``retarget`` subcommands)."""


@hookspec
def register_callbacks(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Callback` subclasses (training loggers and monitors)."""


@hookspec
def register_planners(register: Registrar) -> None:
    """Register :class:`retarget.kinds.Planner` subclasses (tracking experts, no training)."""


HOOK_KINDS: dict[str, str] = {
    "register_characters": "character",
    "register_sensors": "sensor",
    "register_observers": "observer",
    "register_scenes": "scene",
    "register_rewards": "reward",
    "register_terminations": "termination",
    "register_algorithms": "algorithm",
    "register_motion_formats": "motion_format",
    "register_commands": "command",
    "register_callbacks": "callback",
    "register_planners": "planner",
}
"""Hook name -> plugin kind it registers."""
