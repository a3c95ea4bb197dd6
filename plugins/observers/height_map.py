"""``height_map``: scene heights on a circular grid around the character (paper Sec. 3.2.3).

The grid is centred on the root's ground point and turns with the character's heading, so a
box 40 cm ahead is always "ahead" whatever way the character faces. The paper's grid has 6
rings 8 cm apart (radius 0.48 m) of 20 points each (1/20 of a turn apart): 120 points. Each
point's value is the scene's height there (``Scene.height_at``: one batched query, no ray
casts), reported as chosen by ``relative``:

* ``world`` (default): height above the floor at z = 0, matching the heading frame's
  convention of keeping world heights (a 20 cm box reads 0.2 wherever the character stands);
* ``ground``: minus the height under the root (steps relative to where the character is);
* ``root``: minus the root's height (how far below the pelvis each surface is).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import Layout, Observer, ObsSpec, PluginConfig, StepContext

if TYPE_CHECKING:
    import torch


class HeightMapConfig(PluginConfig):
    radius: float = Field(0.48, gt=0, description="outer ring radius, metres")
    rings: int = Field(6, ge=1, description="rings, evenly spaced out to the radius")
    per_ring: int = Field(20, ge=1, description="points per ring, evenly spaced in angle")
    relative: Literal["world", "ground", "root"] = Field(
        "world", description="heights above the floor, the ground under the root, or the root"
    )


def circular_grid(radius: float, rings: int, per_ring: int) -> torch.Tensor:
    """Heading-frame offsets ``(rings * per_ring, 2)``: ring ``i`` at ``radius * i / rings``."""
    import torch
    r = torch.arange(1, rings + 1, dtype=torch.float32) * (radius / rings)
    a = torch.arange(per_ring, dtype=torch.float32) * (2 * math.pi / per_ring)
    xy = torch.stack([r[:, None] * torch.cos(a), r[:, None] * torch.sin(a)], dim=-1)
    return xy.reshape(-1, 2)


class HeightMap(Observer[HeightMapConfig]):
    """Scene heights on a circular grid around the root in its heading frame (120 points)."""

    name = "height_map"

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        cfg = self.config
        self.grid = circular_grid(cfg.radius, cfg.rings, cfg.per_ring)

    def spec(self, layout: Layout) -> ObsSpec:
        return ObsSpec((self.grid.shape[0],))

    def points(self, ctx: StepContext) -> torch.Tensor:
        """World xy ``(N, K, 2)`` of the grid for every environment."""
        import torch

        from retarget.geometry.heading import heading_cos_sin
        root = ctx.sim.qpos[:, :3]
        c, s = heading_cos_sin(ctx.sim.qpos[:, 3:7])
        gx, gy = self.grid[:, 0], self.grid[:, 1]
        x = root[:, :1] + c[:, None] * gx - s[:, None] * gy
        y = root[:, 1:2] + s[:, None] * gx + c[:, None] * gy
        return torch.stack([x, y], dim=-1)

    def observe(self, ctx: StepContext) -> torch.Tensor:
        h = ctx.scene.height_at(self.points(ctx)).float()
        if self.config.relative == "ground":
            h = h - ctx.scene.height_at(ctx.sim.qpos[:, None, :2]).float()
        elif self.config.relative == "root":
            h = h - ctx.sim.qpos[:, 2:3].float()
        return h


@retarget.hookimpl
def register_observers(register) -> None:
    register(HeightMap)
