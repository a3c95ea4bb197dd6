"""``path_boxes``: random boxes on the walking path of the clip each episode plays.

QuestEnvSim's Fig. 5 setting: the user walks on flat ground while the simulation holds boxes
the user never touched; a policy that sees them (height map) should lift its feet over them
instead of stumbling. Every episode, ``count`` boxes of random height (``height``, default
5-25 cm) are put at random points of the reference root's ground path, ahead of where the
episode starts (uniform in distance walked, not in time, so standing still does not pile boxes
up), turned to face the walking direction and shifted sideways by up to ``lateral``.

Boxes are mocap bodies like every prop scene's (:mod:`retarget.scene.props`): one box
of the greatest height per slot, sunk into the floor to get a lower one, placed per
environment from the clip and start time :meth:`Scene.start_episodes` reports at each reset.
In the compiled model (what the reference contact labels are computed against) every box is
parked far from any motion, so the labels are those of flat ground: the user never touched
the boxes. A slot without a place to go (an episode starting near its clip's end) stays parked.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from pydantic import Field, model_validator

import retarget
from retarget.kinds import PluginConfig
from retarget.scene.props import Prop, PropScene, PropSetConfig, Randomization, box

if TYPE_CHECKING:
    import torch

    from retarget.motion.clip import MotionClip

PARK = (-50.0, -50.0)
"""Where boxes stand in the compiled model and when unused: far from any motion."""


class PathBoxesConfig(PropSetConfig):
    count: int = Field(4, ge=1, le=64, description="boxes per episode")
    height: tuple[float, float] = Field((0.05, 0.25), description="min, max box height, metres")
    size: tuple[float, float] = Field(
        (0.3, 0.6), description="extents along and across the walking direction, metres"
    )
    lateral: float = Field(0.1, ge=0, description="max sideways offset from the path, metres")
    clear: float = Field(
        0.6, ge=0, description="no box closer than this to the episode's start root, metres"
    )
    ahead: bool = Field(True, description="only on the part of the path after the start")
    heading_window: float = Field(
        0.2, gt=0, description="seconds either side over which the walking direction is taken"
    )
    density: float = Field(500.0, gt=0, description="kg/m^3 of every box (uniform density)")
    randomize: Randomization = Field(
        default_factory=lambda: Randomization(position=0.0, yaw=0.0),
        description="extra placement noise on top of the path placement (off by default)",
    )

    @model_validator(mode="after")
    def _heights(self) -> PathBoxesConfig:
        lo, hi = self.height
        if not 0 < lo <= hi:
            raise ValueError(f"height must be 0 < min <= max, got {self.height}")
        return self


class PathBoxes(PropScene[PathBoxesConfig]):
    """Boxes re-drawn every episode on the reference root's ground path (see module doc)."""

    name = "path_boxes"

    def __init__(self, config: PluginConfig | None = None) -> None:
        import torch
        super().__init__(config)
        self._path_xy = torch.zeros(0, 1, 2, dtype=torch.float64)
        self._path_yaw = torch.zeros(0, 1, dtype=torch.float64)
        self._path_step = torch.zeros(0, 1, dtype=torch.float64)
        self._fps = torch.zeros(0, dtype=torch.float64)
        self._length = torch.zeros(0, dtype=torch.long)
        self._clip = torch.zeros(0, dtype=torch.long)
        self._start = torch.zeros(0, dtype=torch.long)

    def props(self) -> list[Prop]:
        cfg: PathBoxesConfig = self.config  # type: ignore[assignment]
        top = cfg.height[1]
        part = box((cfg.size[0], cfg.size[1], top), (0.0, 0.0, top / 2))
        return [
            Prop(f"path_box{k}", (part,), xy=(PARK[0] - 2.0 * k, PARK[1])) for k in range(cfg.count)
        ]

    def placed_props(self) -> list[Prop]:
        return self.props()  # parked in world coordinates; episodes place them

    # ---------------------------------------------------------------- the clips' paths

    def fit_motion(self, clips: Sequence[MotionClip]) -> None:
        """Ground path (root x, y), walking direction and distance walked per frame of every
        clip, padded to the longest clip; frames are the clips' own (``fps`` per clip)."""
        import torch
        cfg: PathBoxesConfig = self.config  # type: ignore[assignment]
        longest = max((c.num_frames for c in clips), default=1)
        n = len(clips)
        self._path_xy = torch.zeros(n, longest, 2, dtype=torch.float64)
        self._path_yaw = torch.zeros(n, longest, dtype=torch.float64)
        self._path_step = torch.zeros(n, longest, dtype=torch.float64)
        self._fps = torch.tensor([float(c.fps) for c in clips], dtype=torch.float64)
        self._length = torch.tensor([c.num_frames for c in clips], dtype=torch.long)
        for i, clip in enumerate(clips):  # preprocessing, once per clip
            xy = torch.as_tensor(clip.root_pos[:, :2], dtype=torch.float64)
            t = len(xy)
            w = max(1, round(cfg.heading_window * clip.fps))
            idx = torch.arange(t)
            d = xy[(idx + w).clamp(max=t - 1)] - xy[(idx - w).clamp(min=0)]
            self._path_xy[i, :t] = xy
            self._path_yaw[i, :t] = torch.atan2(d[:, 1], d[:, 0])
            if t > 1:  # distance walked from each frame to the next
                self._path_step[i, : t - 1] = (xy[1:] - xy[:-1]).norm(dim=-1)

    def allocate(self, num_envs: int) -> None:
        import torch
        super().allocate(num_envs)
        self._clip = torch.zeros(num_envs, dtype=torch.long)
        self._start = torch.zeros(num_envs, dtype=torch.long)

    def start_episodes(
        self, env_ids: torch.Tensor, clip: torch.Tensor, seconds: torch.Tensor
    ) -> None:
        import torch
        if not self._allocated:
            self.allocate(int(env_ids.max()) + 1)
        clip = clip.long()
        if self._length.numel() == 0:
            return
        frame = torch.round(seconds.double() * self._fps[clip]).long()
        self._clip[env_ids] = clip
        self._start[env_ids] = torch.minimum(frame.clamp(min=0), self._length[clip] - 1)

    # ---------------------------------------------------------------- placement

    def randomize(self, env_ids: torch.Tensor, generator: torch.Generator) -> None:
        """Per box: a frame of the path drawn in proportion to the distance walked there
        (frames after the start when ``ahead``, at least ``clear`` from the start), a
        sideways offset, a height; then the configured extra noise. Vectorised over envs."""
        import torch
        cfg: PathBoxesConfig = self.config  # type: ignore[assignment]
        e, k = int(env_ids.numel()), len(self._props)
        if e == 0:
            return
        if not self._allocated:
            self.allocate(int(env_ids.max()) + 1)
        f64 = torch.float64
        offsets = torch.zeros(e, k, 4, dtype=f64)
        if self._length.numel():
            clip, start = self._clip[env_ids], self._start[env_ids]
            xy, yaw = self._path_xy[clip], self._path_yaw[clip]  # (E, T, 2), (E, T)
            frames = torch.arange(xy.shape[1])
            start_xy = xy[torch.arange(e), start][:, None]  # (E, 1, 2)
            ok = frames < self._length[clip][:, None]
            ok &= (xy - start_xy).norm(dim=-1) >= cfg.clear
            if cfg.ahead:
                ok &= frames >= start[:, None]
            weight = self._path_step[clip] * ok
            placed = weight.sum(-1) > 0  # (E,)
            weight[~placed] = 1.0  # drawn, then left parked
            pick = torch.multinomial(weight.float(), k, replacement=True, generator=generator)
            u = torch.rand(e, k, 2, generator=generator, dtype=f64)
            at = torch.gather(xy, 1, pick[..., None].expand(-1, -1, 2))  # (E, K, 2)
            heading = torch.gather(yaw, 1, pick)
            side = cfg.lateral * (2 * u[..., 0] - 1)
            normal = torch.stack([-torch.sin(heading), torch.cos(heading)], -1)
            at = at + side[..., None] * normal
            lo, hi = cfg.height
            sink = (lo + (hi - lo) * u[..., 1]) - hi  # <= 0: the box's top at its height
            base = self._tables.base  # (K, 3) parked x, y, yaw
            pose = torch.cat([at - base[:, :2], sink[..., None], heading[..., None]], -1)
            offsets = torch.where(placed[:, None, None], pose, offsets)
        noise = self.randomization
        if noise.position or noise.yaw:  # heights come from the path draw alone
            u = torch.rand(e, k, 4, generator=generator, dtype=f64)
            radius = noise.position * torch.sqrt(u[..., 0])
            angle = 2 * math.pi * u[..., 1]
            offsets[..., 0] += radius * torch.cos(angle)
            offsets[..., 1] += radius * torch.sin(angle)
            offsets[..., 3] += noise.yaw * (2 * u[..., 3] - 1)
        self._offsets[env_ids] = offsets


@retarget.hookimpl
def register_scenes(register) -> None:
    register(PathBoxes)
