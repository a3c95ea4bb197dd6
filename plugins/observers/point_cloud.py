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

Cost: testing every pool point every step was most of the work (N x pool distances), and
most points are metres away. So the pool is kept sorted along a Z-order curve of ``cell``-sized
horizontal cells (one order, taken from the first placement: placements differ by centimetres)
and cut into chunks of ``chunk`` consecutive points, each environment holding its own chunk
bounding boxes. A step tests the root's sphere against the boxes, gathers only the reached
(environment, chunk) pairs' points, and restores pool order among the points in range by their
original pool index: the result equals the full scan's exactly, at about a tenth of its cost
(``benchmarks/bench_observers.py``). Prop scenes' samples are drawn once in the props' frames
and only re-placed at resets.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import Layout, Observer, ObsSpec, PluginConfig, StepContext

if TYPE_CHECKING:
    import torch

    from retarget import Scene


class PointCloudConfig(PluginConfig):
    count: int = Field(1000, ge=1, description="points per environment (EnvPoser: 1000)")
    radius: float = Field(1.0, gt=0, description="metres from the root a point may be")
    pool: int = Field(8192, ge=1, description="surface samples held per environment")
    seed: int = Field(0, description="seed of the surface samples")
    chunk: int = Field(64, ge=1, description="pool points per spatial chunk (the pre-filter)")
    cell: float = Field(0.1, gt=0, description="metres of the Z-order cells chunks follow")


def _spread_bits(v: torch.Tensor) -> torch.Tensor:
    """Interleave zeros between the low 16 bits of ``v`` (int64), for a Morton code."""
    v = v & 0xFFFF
    v = (v | (v << 8)) & 0x00FF00FF
    v = (v | (v << 4)) & 0x0F0F0F0F
    v = (v | (v << 2)) & 0x33333333
    return (v | (v << 1)) & 0x55555555


def morton_order(xy: torch.Tensor, cell: float) -> torch.Tensor:
    """Per row, the permutation sorting points ``(E, C, 2)`` along a Z-order curve of
    ``cell``-sized cells; ties keep pool order (so each cell's points stay a random sample)."""
    import torch
    ij = torch.floor(xy / cell).long()
    ij = ij - ij.amin(dim=1, keepdim=True)
    code = _spread_bits(ij[..., 0]) | (_spread_bits(ij[..., 1]) << 1)
    rank = torch.arange(xy.shape[1])
    return torch.argsort(code * xy.shape[1] + rank, dim=1)


@dataclass
class _Pool:
    """Every environment's sampled surface points, Z-ordered in chunks with their boxes."""

    points: torch.Tensor  # (N, chunks * chunk, 3) world, Z-ordered
    rank: torch.Tensor  # (N, chunks * chunk) pool index (pad: pool)
    lo: torch.Tensor  # (N, chunks, 3) chunk bounding boxes
    hi: torch.Tensor
    scene: Scene  # the scene they were drawn from
    dirty: torch.Tensor  # (N,) environments reset since: their props moved

    def parts(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        return self.points, self.rank, self.lo, self.hi


class PointCloud(Observer[PointCloudConfig]):
    """Up to 1000 scene surface points within 1 m of the root, heading frame, with a mask."""

    name = "point_cloud"

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._pool: _Pool | None = None
        self._order: torch.Tensor | None = None  # (pool,) Z-order of the first placement
        self._local: torch.Tensor | None = None  # prop-frame samples of a prop scene
        self._global = False  # the scene gives world samples only (no prop frames)
        self._any_dirty = False

    def spec(self, layout: Layout) -> ObsSpec:
        return ObsSpec((self.config.count, 4))

    def reset(self, env_ids: torch.Tensor) -> None:
        if self._pool is not None and env_ids.numel():
            self._pool.dirty[env_ids] = True
            self._any_dirty = True

    def _sample(self, scene: Scene, rows: int) -> tuple[torch.Tensor, bool]:
        """Pool points of ``rows`` environments, and whether they are already in Z-order."""
        import numpy as np
        import torch
        rng = np.random.default_rng(self.config.seed)
        presorted = False
        if self._local is None and not self._global:
            drawn = scene.local_surface_points(self.config.pool, rng)
            self._global = drawn is None
            if drawn is not None:
                self._local = torch.from_numpy(drawn)
        if self._local is not None:  # prop scenes: draw once, place per reset
            local = self._local
            if self._order is not None:  # place the samples in Z-order directly
                local, presorted = self._local[self._order], True
            pts = scene.place_surface_points(local.float(), dtype=torch.float32)
        else:
            pts = torch.from_numpy(np.asarray(scene.surface_points(self.config.pool, rng)))
        pts = pts.reshape(-1, self.config.pool, 3).float()
        if pts.shape[0] != rows:  # a static scene: the same points for every environment
            pts = pts[:1].expand(rows, -1, -1)
        return pts, presorted

    def _chunked(
        self, pts: torch.Tensor, presorted: bool = False
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """Z-ordered, padded points, their pool indices and chunk boxes for rows ``pts``."""
        import torch
        e, c = pts.shape[:2]
        size = self.config.chunk
        chunks = -(-c // size)
        if self._order is None:
            # one order for every environment: placements differ by centimetres, so the first
            # one's cells stay compact for all; the boxes below are each row's own, so an
            # order only affects how tight they are, never which points are found
            self._order = morton_order(pts[:1, :, :2], self.config.cell)[0]
        order = self._order
        rank = torch.full((e, chunks * size), c, dtype=torch.int32)
        rank[:, :c] = order
        sorted_pts = pts if presorted else pts[:, order]
        # padding repeats the last point, so it never widens a box; its rank marks it out
        padded = torch.cat([sorted_pts, sorted_pts[:, -1:].expand(-1, chunks * size - c, -1)], 1)
        boxes = padded.reshape(e, chunks, size, 3)
        return padded.contiguous(), rank, boxes.amin(2), boxes.amax(2)

    def _refresh(self, scene: Scene, n: int) -> _Pool:
        import torch
        held = self._pool
        if held is None or held.scene is not scene or held.points.shape[0] != n:
            self._order = self._local = None
            self._global = False
            parts = self._chunked(*self._sample(scene, n))
            held = _Pool(*parts, scene=scene, dirty=torch.zeros(n, dtype=torch.bool))
            self._pool = held
            self._any_dirty = False
        elif self._any_dirty:
            ids = held.dirty.nonzero()[:, 0]
            parts = self._chunked(*self._sample(scene.select(ids), ids.shape[0]))
            for old, new in zip(held.parts(), parts, strict=True):
                old[ids] = new
            held.dirty.zero_()
            self._any_dirty = False
        return held

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch

        from retarget.geometry.heading import heading_cos_sin, unyaw
        n, k, size = ctx.num_envs, self.config.count, self.config.chunk
        out = torch.zeros(n, k, 4)
        pool, rank, lo, hi = self._refresh(ctx.scene, n).parts()
        root = ctx.sim.qpos[:, :3].float()
        r2 = self.config.radius**2
        # (environment, chunk) pairs whose box the root's sphere reaches (box-sphere distance)
        gap = (root[:, None] - root[:, None].clamp(lo, hi)).square().sum(-1)  # (N, chunks)
        env, chunk = (gap <= r2).nonzero(as_tuple=True)  # (H,) each
        chunks, end = pool.shape[1] // size, self.config.pool
        rel = pool.view(n, chunks, size, 3)[env, chunk] - root[env, None]  # (H, size, 3)
        ranks = rank.view(n, chunks, size)[env, chunk]
        near = ((rel * rel).sum(-1) <= r2) & (ranks < end)  # padding has rank ``end``
        env = env[:, None].expand(-1, size)[near]
        rel, ranks = rel[near], ranks[near].long()
        # pool order within each environment: sort by (environment, pool index)
        order = torch.argsort(env * end + ranks)
        env, rel = env[order], rel[order]
        counts = torch.bincount(env, minlength=n)
        slot = torch.arange(env.shape[0]) - (counts.cumsum(0) - counts)[env]
        keep = slot < k
        env, slot, rel = env[keep], slot[keep], rel[keep]
        c, sn = heading_cos_sin(ctx.sim.qpos[:, 3:7].float())
        local = unyaw(rel, c[env], sn[env])  # only the kept points enter the heading frame
        local[:, 2] += root[env, 2]  # z: world height (padding stays 0)
        out[env, slot, :3] = local
        out[env, slot, 3] = 1.0
        return out


@retarget.hookimpl
def register_observers(register) -> None:
    register(PointCloud)
