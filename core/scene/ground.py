"""The floor alone (z = 0): the scene an environment has when a recipe names none.

Every environment has a scene, so nothing downstream branches on its absence: observers query
it, terminations measure height above it, checkpoints save it. The built-in ``flat`` scene
plugin is this class under its registered name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

from retarget.kinds.base import PluginConfig
from retarget.kinds.scene import Scene
from retarget.scene.floor import add_floor

if TYPE_CHECKING:
    import mujoco
    import numpy as np
    import torch


class GroundConfig(PluginConfig):
    extent: float = Field(
        2.0, gt=0, description="half side (m) of the square around the origin surface points fill"
    )


class Ground(Scene[GroundConfig]):
    """An infinite flat floor at z = 0; nothing to randomize.

    The floor has no props, so its surface points are drawn on the floor inside a square of
    half side ``extent`` around the origin (other scenes leave the floor out of their points).
    """

    name = "ground"

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._num_envs = 1

    def build(self, spec: mujoco.MjSpec) -> None:
        add_floor(spec)

    def allocate(self, num_envs: int) -> None:
        self._num_envs = num_envs

    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        import torch
        return torch.zeros(xy.shape[:-1], dtype=torch.float32)

    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        import numpy as np
        e = self.config.extent
        pts = np.zeros((count, 3))
        pts[:, :2] = rng.uniform(-e, e, size=(count, 2))
        return np.broadcast_to(pts, (self._num_envs, count, 3)).copy()
