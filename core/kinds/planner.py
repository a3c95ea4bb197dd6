"""Planners: tracking experts that need no training (``retarget expert --method NAME``).

A planner tracks one clip of an environment's motion library offline, using the simulator
itself, and returns the path it found (:class:`retarget.Track`): the states, the
actions in the env's own action space that produce them from the clip's first frame, and
PHC's figures. ``retarget expert`` runs a planner over clips, in parallel and resumably,
and writes what it returns; students learn from those states and actions by supervised
learning (``retarget train --expert DIR``), so a planner only has to be good at tracking.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable
from typing import Any, ClassVar

from retarget.kinds.base import ConfigT, Plugin
from retarget.kinds.track import Track


class Planner(Plugin[ConfigT]):
    """Base class of planners; a planner holds only its settings, the env comes per call."""

    kind: ClassVar[str] = "planner"

    @abstractmethod
    def track(
        self,
        env: Any,
        clip: int,
        *,
        seconds: float | None = None,
        threads: int = 1,
        progress: Callable[[int], None] | None = None,
    ) -> Track:
        """Track clip ``clip`` (library index) of ``env`` (a :class:`retarget.TrackingEnv`
        with ``num_envs`` 1) from its first frame, for ``seconds`` of it (all when None),
        with ``threads`` physics threads. The returned actions, stepped in ``env`` from the
        placed first frame, must reproduce the returned states (the contract suite replays
        them). ``progress(frames)`` may be called as frames are planned."""
