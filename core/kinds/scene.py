"""Scenes: static and articulated props added to the world, plus batched geometry queries."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import torch

from retarget.kinds.base import Plugin

if TYPE_CHECKING:
    import mujoco


class Scene(Plugin):
    """Base class of scenes.

    ``build`` adds geometry to a world spec (the floor is the scene's job too).
    ``height_at`` answers height queries for many points of many environments at once, which
    is what the height-map observer uses instead of per-point ray casts.
    """

    kind: ClassVar[str] = "scene"

    @abstractmethod
    def build(self, spec: mujoco.MjSpec) -> None: ...

    @abstractmethod
    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        """Ground height under world points ``xy`` ``(N, K, 2)`` -> ``(N, K)``."""
        ...

    @abstractmethod
    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``count`` points sampled on the scene's surfaces, world frame ``(count, 3)``."""
        ...

    def randomize(self, env_ids: torch.Tensor, generator: torch.Generator) -> None:
        """Re-draw per-episode placement noise for ``env_ids`` (static scenes ignore this)."""
