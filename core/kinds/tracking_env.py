"""What an algorithm may read of the retarget environment beyond stepping it.

:class:`~retarget.kinds.algorithm.VecEnv` is all a policy-gradient learner needs. A method that
learns from the motion library without acting (a pose estimator), one that replays a planner's
recorded states (behaviour cloning from a tracking expert) or an evaluator that reads each
step's state asks for a :class:`TrackingEnv`: the environment's layout, its motion library and
kinematic reference, its sensors, scene and observation window, starting environments in a
given physical state and recomputing observations. :func:`tracking_env` checks an environment
once and names every missing member, so a plugin states its need instead of probing
attributes one by one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from typing_extensions import get_protocol_members

from retarget.errors import PluginError
from retarget.kinds.algorithm import VecEnv

if TYPE_CHECKING:
    import numpy as np
    import torch

    from retarget.kinds.scene import Scene
    from retarget.kinds.sensor import Observer, Sensor
    from retarget.kinds.state import Layout, StepContext
    from retarget.motion.library import MotionLibrary


@runtime_checkable
class TrackingEnv(VecEnv, Protocol):
    """N environments tracking reference motion (``retarget.env.RetargetEnv``).

    ``layout``: the character's indices; ``library``: the motion library (clips at the control
    rate); ``reference``: the character's kinematic reference of every library row;
    ``sensors``/``observers``: the step plugins, bound; ``scene``: the scene plugin (``None`` on
    the plain floor); ``window_offsets``: the device frames each step gathers; ``sim``: the
    batched simulator; ``last_context``: the most recent step's state before its resets
    (``None`` before the first step).
    """

    layout: Layout
    library: MotionLibrary
    reference: Any
    sensors: Sequence[Sensor[Any]]
    observers: Sequence[Observer[Any]]
    scene: Scene[Any] | None
    window_offsets: tuple[int, ...]
    sim: Any
    last_context: StepContext | None

    def place_state(
        self,
        env_ids: torch.Tensor,
        clip: torch.Tensor,
        frame: torch.Tensor,
        qpos: np.ndarray,
        qvel: np.ndarray,
        prev_action: torch.Tensor | None = None,
    ) -> None:
        """Start ``env_ids`` at reference (clip, frame) in the given physical state."""
        ...

    def observe_now(self, groups: Sequence[str] | None = None) -> dict[str, torch.Tensor]:
        """The observation of the current state and reference rows, recomputed."""
        ...


MEMBERS = tuple(sorted(get_protocol_members(TrackingEnv)))
"""Every member of :class:`TrackingEnv` (those of ``VecEnv`` included), as reported missing."""


def tracking_env(env: object, plugin: str) -> TrackingEnv:
    """``env`` as a :class:`TrackingEnv`, or a :class:`PluginError` naming ``plugin`` and
    every member the environment lacks."""
    if isinstance(env, TrackingEnv):
        return env
    missing = [m for m in MEMBERS if not hasattr(env, m)]
    raise PluginError(
        f"needs a retarget environment (retarget.kinds.tracking_env.TrackingEnv); "
        f"{type(env).__name__} has no {', '.join(missing) or 'VecEnv members'}",
        plugin=plugin,
    )
