"""``point_cloud``: scene surface points near the character, in its heading frame (EnvPoser).

Each environment holds a fixed pool of ``pool`` points sampled on its scene's surfaces
(``Scene.surface_points``, area weighted, placed where that environment's props are). Every
step the points within ``radius`` of the root are kept, in pool order (the pool is a random
sample, so its first ``count`` points in range are a uniform subsample of them), up to
``count``. The output is ``(count, 4)`` per environment: x, y, z in the heading frame (x, y
relative to the root's ground point, z the world height) and a mask, 1 for a point, 0 for
padding (whose coordinates are 0). A policy or estimator should use the mask, not the zeros.

The pool of an environment is redrawn after it resets (its props may have moved): only the
reset environments' pools are re-placed, from the same samples (a fixed ``seed``), so two
environments with the same placement see the same points. The floor counts as a surface only
in scenes that say so (``flat``, meshes with a floor); props' undersides on the floor do not.
"""

from __future__ import annotations

import numpy as np
import torch
from pydantic import Field

import retarget
from retarget import Layout, Observer, ObsSpec, PluginConfig, StepContext
from retarget.heading import heading_cos_sin, unyaw


class PointCloudConfig(PluginConfig):
    count: int = Field(1000, ge=1, description="points per environment (EnvPoser: 1000)")
    radius: float = Field(1.0, gt=0, description="metres from the root a point may be")
    pool: int = Field(8192, ge=1, description="surface samples held per environment")
    seed: int = Field(0, description="seed of the surface samples")


class PointCloud(Observer):
    """Up to 1000 scene surface points within 1 m of the root, heading frame, with a mask."""

    name = "point_cloud"
    Config = PointCloudConfig

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._pool: torch.Tensor | None = None  # (N, pool, 3) world
        self._scene: object = None
        self._dirty: torch.Tensor | None = None
        self._any_dirty = False

    def spec(self, layout: Layout) -> ObsSpec:
        return ObsSpec((self.config.count, 4))

    def reset(self, env_ids: torch.Tensor) -> None:
        if self._dirty is not None and env_ids.numel():
            self._dirty[env_ids] = True
            self._any_dirty = True

    def _sample(self, scene, rows: int) -> torch.Tensor:
        rng = np.random.default_rng(self.config.seed)
        pts = torch.from_numpy(np.asarray(scene.surface_points(self.config.pool, rng)))
        pts = pts.reshape(-1, self.config.pool, 3).float()
        if pts.shape[0] != rows:  # a static scene: the same points for every environment
            pts = pts[:1].expand(rows, -1, -1)
        return pts

    def _refresh(self, ctx: StepContext) -> torch.Tensor:
        n = ctx.num_envs
        if self._pool is None or self._scene is not ctx.scene or self._pool.shape[0] != n:
            self._pool = self._sample(ctx.scene, n).clone()
            self._scene = ctx.scene
            self._dirty = torch.zeros(n, dtype=torch.bool)
            self._any_dirty = False
        elif self._any_dirty:
            ids = self._dirty.nonzero()[:, 0]
            self._pool[ids] = self._sample(ctx.scene.select(ids), ids.shape[0])
            self._dirty.zero_()
            self._any_dirty = False
        return self._pool

    def observe(self, ctx: StepContext) -> torch.Tensor:
        n, k = ctx.num_envs, self.config.count
        out = torch.zeros(n, k, 4)
        if ctx.scene is None:
            return out
        pool = self._refresh(ctx)
        root = ctx.sim.qpos[:, :3].float()
        rel = pool - root[:, None]  # (N, P, 3)
        near = rel.square().sum(-1) <= self.config.radius**2
        slot = near.cumsum(dim=1) - 1
        keep = near & (slot < k)
        env = torch.arange(n)[:, None].expand_as(keep)[keep]
        slot = slot[keep]
        out[env, slot, :3] = rel[keep]  # only the kept points are turned into the heading frame
        out[env, slot, 3] = 1.0
        c, sn = heading_cos_sin(ctx.sim.qpos[:, 3:7].float())
        local = unyaw(out[..., :3], c, sn)
        local[..., 2] += root[:, 2:3] * out[..., 3]  # z: world height (padding stays 0)
        out[..., :3] = local
        return out


@retarget.hookimpl
def register_observers(register) -> None:
    register(PointCloud)
