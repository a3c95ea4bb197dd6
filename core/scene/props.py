"""Props made of primitives, placed per environment: what the primitive scenes share.

A *prop* (a chair, a box, a couch) is a mocap body on the floor holding axis-aligned boxes and
vertical cylinders in its own frame, optionally with a child body on a hinge (a tilting seat,
a swivel seat). Because all environments share one compiled model, per-episode placement
noise (the paper's scene randomization, Sec. 3.4) moves the mocap bodies: their poses are
per-environment state, written by the environment at every reset.

Every query is batched over environments and loops only over the (few) primitives:

* ``height_at``: each query point is moved into the frame of every primitive of the props
  near the queries (a footprint-circle test first), tested against its footprint (rectangle
  or disc) and the highest top wins; the floor is 0.
* ``surface_points``: points are drawn once per call on the primitives' faces (area weighted,
  in prop frames; faces lying on the floor are left out) and placed for every environment.

Moving parts (hinged seats) are queried at their rest pose: the height map of a chair tilted
by a few degrees differs by millimetres to centimetres, which the policy's own proprioception
and contacts cover.

Masses follow from uniform density over the collision geometry (the paper's choice), default
500 kg/m^3 (wood-like); only hinged parts' masses matter to the dynamics, since mocap bodies
are immovable.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from typing import TYPE_CHECKING, ClassVar, Literal

from pydantic import Field
from typing_extensions import TypeVar

from retarget.errors import PluginError
from retarget.kinds import PluginConfig, Scene
from retarget.scene.floor import add_floor

if TYPE_CHECKING:
    import mujoco
    import numpy as np
    import torch

_FLOOR_EPS = 1e-6


@dataclass(frozen=True)
class Part:
    """An axis-aligned primitive in its prop's frame (metres).

    ``half``: box half extents ``(x, y, z)``, or for a vertical cylinder ``(radius, radius,
    half height)``; ``pos``: its centre.
    """

    shape: Literal["box", "cylinder"]
    half: tuple[float, float, float]
    pos: tuple[float, float, float]

    @property
    def top(self) -> float:
        return self.pos[2] + self.half[2]


def box(size: tuple[float, float, float], pos: tuple[float, float, float]) -> Part:
    """A box of full extents ``size`` centred at ``pos``."""
    return Part("box", (size[0] / 2, size[1] / 2, size[2] / 2), pos)


def cylinder(radius: float, height: float, pos: tuple[float, float, float]) -> Part:
    """A vertical cylinder of ``radius`` and full ``height`` centred at ``pos``."""
    return Part("cylinder", (radius, radius, height / 2), pos)


@dataclass(frozen=True)
class Hinge:
    """A child body carrying ``parts`` (given in the prop frame) on a hinge at ``pos``.

    ``stiffness`` (N m/rad) and ``damping`` (N m s/rad) make a spring-damper; ``range`` limits
    the angle (radians) when given.
    """

    axis: tuple[float, float, float]
    pos: tuple[float, float, float]
    parts: tuple[Part, ...]
    stiffness: float = 0.0
    damping: float = 0.0
    frictionloss: float = 0.0
    range: tuple[float, float] | None = None


@dataclass(frozen=True)
class Prop:
    """One placed object: ``parts`` fixed to its body, an optional hinged child."""

    name: str
    parts: tuple[Part, ...]
    xy: tuple[float, float] = (0.0, 0.0)
    yaw: float = 0.0
    hinge: Hinge | None = None

    def all_parts(self) -> tuple[Part, ...]:
        return self.parts + (self.hinge.parts if self.hinge else ())

    def moved(self, xy: tuple[float, float], yaw: float) -> Prop:
        """This prop with its frame moved by ``xy`` and turned by ``yaw`` (composition)."""
        c, s = math.cos(yaw), math.sin(yaw)
        x, y = self.xy
        return replace(self, xy=(xy[0] + c * x - s * y, xy[1] + s * x + c * y), yaw=self.yaw + yaw)


class Randomization(PluginConfig):
    """Per-episode placement noise of every prop (uniform; 0 disables)."""

    position: float = Field(0.08, ge=0, description="max horizontal offset, metres (in a disc)")
    yaw: float = Field(0.1, ge=0, description="max rotation about the vertical, radians")
    height: float = Field(0.0, ge=0, description="max vertical offset, metres")


class PropSetConfig(PluginConfig):
    """What every prop scene's config has: the props' density and their randomization.
    Scenes that place their props themselves (per clip, along a path) derive from this."""

    density: float = Field(500.0, gt=0, description="kg/m^3 of every part (uniform density)")
    randomize: Randomization = Field(default_factory=Randomization)


class PropSceneConfig(PropSetConfig):
    """A scene placed as a whole: where it stands (``position``, ``yaw``), plus density and
    randomization."""

    position: tuple[float, float] = Field((0.0, 1.2), description="world x, y of the prop")
    yaw: float = Field(
        -math.pi / 2, description="rotation about +Z, radians (default: front faces the origin)"
    )


@dataclass
class _Tables:
    """Primitive data flattened over all props, as tensors for batched queries."""

    prop_of: torch.Tensor  # (Q,) prop index of each part
    center: torch.Tensor  # (Q, 2) in the prop frame
    half: torch.Tensor  # (Q, 2)
    top: torch.Tensor  # (Q,)
    round: torch.Tensor  # (Q,) bool: cylinder footprint
    base: torch.Tensor  # (P, 3) default x, y, yaw
    parts: list[tuple[int, Part]] = field(default_factory=list)

    def __post_init__(self) -> None:
        """Per-prop copies ``(P, M, ...)`` padded to the most parts of any prop (float32), and
        each prop's ``reach``: the radius of its footprint around its origin."""
        import torch
        props = len(self.base)
        count = torch.bincount(self.prop_of, minlength=props) if props else torch.zeros(0)
        m = int(count.max()) if props else 0
        self.valid = torch.zeros(props, m, dtype=torch.bool)
        self.p_center = torch.zeros(props, m, 2)
        self.p_half = torch.zeros(props, m, 2)
        self.p_top = torch.zeros(props, m)
        self.p_round = torch.zeros(props, m, dtype=torch.bool)
        self.reach = torch.zeros(props)
        slot = [0] * props
        for q, prop in enumerate(self.prop_of.tolist()):
            j, slot[prop] = slot[prop], slot[prop] + 1
            self.valid[prop, j] = True
            self.p_center[prop, j] = self.center[q].float()
            self.p_half[prop, j] = self.half[q].float()
            self.p_top[prop, j] = float(self.top[q])
            self.p_round[prop, j] = bool(self.round[q])
            far = float(self.center[q].norm() + self.half[q].norm())
            self.reach[prop] = max(float(self.reach[prop]), far)


PropConfigT = TypeVar("PropConfigT", bound=PropSetConfig, default=PropSceneConfig)
"""A prop scene's config: a :class:`PropSetConfig`, placed as a whole when a
:class:`PropSceneConfig`."""


class PropScene(Scene[PropConfigT]):
    """Base of scenes made of :class:`Prop` s; subclasses say which props in :meth:`props`."""

    Config: ClassVar[type[PluginConfig]] = PropSceneConfig

    def __init__(self, config: PluginConfig | None = None) -> None:
        import torch
        super().__init__(config)
        if not isinstance(self.config, PropSetConfig):
            raise PluginError(
                f"{type(self).__name__}.Config must derive from PropSetConfig (density, "
                "randomize) or PropSceneConfig (and position, yaw)", plugin=f"scene {self.name}",
            )
        self._props = self.placed_props()
        names = [p.name for p in self._props]
        if len(set(names)) != len(names):
            raise PluginError(f"duplicate prop names {names}", plugin=f"scene {self.name}")
        self._tables = self._flatten()
        self._offsets = torch.zeros(0, len(self._props), 4, dtype=torch.float64)
        self._allocated = False

    # ---------------------------------------------------------------- what subclasses give

    def props(self) -> list[Prop]:
        """Props in the scene's own frame (before ``position``/``yaw`` of the config)."""
        raise NotImplementedError

    def placed_props(self) -> list[Prop]:
        cfg = self.config
        xy: tuple[float, float] = (0.0, 0.0)
        yaw = 0.0
        if isinstance(cfg, PropSceneConfig):
            xy, yaw = (float(cfg.position[0]), float(cfg.position[1])), float(cfg.yaw)
        return [p.moved(xy, yaw) for p in self.props()]

    @property
    def randomization(self) -> Randomization:
        return self.config.randomize

    # ---------------------------------------------------------------- building

    def body_name(self, prop: Prop) -> str:
        return f"scene_{prop.name}"

    def build(self, spec: mujoco.MjSpec) -> None:
        import mujoco
        import torch

        from retarget.geometry.heading import yaw_quat
        add_floor(spec)
        density = float(self.config.density)
        for prop in self._props:
            body = spec.worldbody.add_body(
                name=self.body_name(prop),
                mocap=True,
                pos=[prop.xy[0], prop.xy[1], 0.0],
                quat=yaw_quat(torch.tensor(prop.yaw, dtype=torch.float64)).tolist(),
            )
            for k, part in enumerate(prop.parts):
                _add_part(body, part, (0.0, 0.0, 0.0), density, f"{self.body_name(prop)}_{k}")
            if prop.hinge is not None:
                h = prop.hinge
                child = body.add_body(name=f"{self.body_name(prop)}_moving", pos=list(h.pos))
                joint = child.add_joint(
                    name=f"{self.body_name(prop)}_hinge",
                    type=mujoco.mjtJoint.mjJNT_HINGE,
                    axis=list(h.axis),
                    stiffness=h.stiffness,
                    damping=h.damping,
                    frictionloss=h.frictionloss,
                    armature=0.01,
                )
                if h.range is not None:
                    joint.range = list(h.range)
                    joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
                for k, part in enumerate(h.parts):
                    name = f"{self.body_name(prop)}_moving_{k}"
                    _add_part(child, part, h.pos, density, name)

    def mocap_bodies(self) -> tuple[str, ...]:
        return tuple(self.body_name(p) for p in self._props)

    # ---------------------------------------------------------------- placement

    def _flatten(self) -> _Tables:
        import torch
        rows = [(i, part) for i, p in enumerate(self._props) for part in p.all_parts()]
        f64 = torch.float64
        return _Tables(
            prop_of=torch.tensor([i for i, _ in rows], dtype=torch.long),
            center=torch.tensor([part.pos[:2] for _, part in rows], dtype=f64).reshape(-1, 2),
            half=torch.tensor([part.half[:2] for _, part in rows], dtype=f64).reshape(-1, 2),
            top=torch.tensor([part.top for _, part in rows], dtype=f64),
            round=torch.tensor([part.shape == "cylinder" for _, part in rows], dtype=torch.bool),
            base=torch.tensor([[*p.xy, p.yaw] for p in self._props], dtype=f64).reshape(-1, 3),
            parts=rows,
        )

    def allocate(self, num_envs: int) -> None:
        import torch
        self._offsets = torch.zeros(num_envs, len(self._props), 4, dtype=torch.float64)
        self._allocated = True

    def randomize(self, env_ids: torch.Tensor, generator: torch.Generator) -> None:
        """Offsets ``(dx, dy, dz, dyaw)`` per prop for ``env_ids``: a uniform point in a disc
        of radius ``position``, ``dz`` in ``[-height, height]``, ``dyaw`` in ``[-yaw, yaw]``."""
        import torch
        r = self.randomization
        p = len(self._props)
        if p == 0 or env_ids.numel() == 0:
            return
        if not self._allocated:
            self.allocate(int(env_ids.max()) + 1)
        u = torch.rand(int(env_ids.numel()), p, 4, generator=generator, dtype=torch.float64)
        radius = r.position * torch.sqrt(u[..., 0])
        angle = 2 * math.pi * u[..., 1]
        self._offsets[env_ids] = torch.stack(
            [
                radius * torch.cos(angle),
                radius * torch.sin(angle),
                r.height * (2 * u[..., 2] - 1),
                r.yaw * (2 * u[..., 3] - 1),
            ],
            dim=-1,
        )

    def select(self, env_ids: torch.Tensor) -> PropScene[PropConfigT]:
        if not self._allocated:
            return self
        view = object.__new__(type(self))
        view.__dict__.update(self.__dict__)
        view._offsets = self._offsets[env_ids]
        return view

    def placement(self, n: int | None = None) -> torch.Tensor:
        """Per-environment prop poses ``(N, P, 4)``: x, y, z, yaw (float64)."""
        import torch
        t = self._tables
        base = torch.cat([t.base[:, :2], torch.zeros_like(t.base[:, :1]), t.base[:, 2:]], -1)
        if not self._allocated:
            return base.expand(n or 1, -1, -1)
        if n is not None and n != self._offsets.shape[0]:
            raise PluginError(
                f"holds placements of {self._offsets.shape[0]} environments but was queried "
                f"for {n}; query a subset through scene.select(env_ids)",
                plugin=f"scene {self.name}",
            )
        return base + self._offsets

    def mocap_poses(self, env_ids: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        from retarget.geometry.heading import yaw_quat
        pose = self.placement()[env_ids] if self._allocated else self.placement(len(env_ids))
        return pose[..., :3].contiguous(), yaw_quat(pose[..., 3].double())

    def state_dict(self) -> dict[str, torch.Tensor]:
        return {"offsets": self._offsets.clone()}

    def load_state_dict(self, state: Mapping[str, torch.Tensor]) -> None:
        self._offsets = state["offsets"].clone()
        self._allocated = True

    # ---------------------------------------------------------------- queries

    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        """Each environment tests only the props whose footprint circle reaches its query
        points' bounding circle (a height map covers one or two of a room's props), each prop's
        parts padded to the most any prop has; float32 keeps micrometres within a room."""
        import torch
        n = xy.shape[0]
        t = self._tables
        if t.top.numel() == 0:
            return torch.zeros(xy.shape[:-1], dtype=torch.float32)
        xy = xy.float()
        pose = self.placement(n).float()  # (N, P, 4)
        lo, hi = xy.amin(1), xy.amax(1)  # (N, 2) box of the queries
        reach = (hi - lo).norm(dim=-1, keepdim=True) / 2 + t.reach  # (N, P)
        hit = (pose[..., :2] - (lo + hi)[:, None] / 2).norm(dim=-1) <= reach
        env, prop = hit.nonzero(as_tuple=True)  # (H,) pairs to test
        pose = pose[env, prop][:, None, None]  # (H, 1, 1, 4)
        d = xy[env][:, :, None] - pose[..., :2]  # (H, K, 1, 2)
        c, s = torch.cos(pose[..., 3]), torch.sin(pose[..., 3])
        dx, dy = d[..., 0], d[..., 1]
        center, half = t.p_center[prop][:, None], t.p_half[prop][:, None]  # (H, 1, M, 2)
        lx = c * dx + s * dy - center[..., 0]
        ly = c * dy - s * dx - center[..., 1]
        inside_box = (lx.abs() <= half[..., 0]) & (ly.abs() <= half[..., 1])
        inside_disc = lx * lx + ly * ly <= half[..., 0] ** 2
        inside = torch.where(t.p_round[prop][:, None], inside_disc, inside_box)
        inside &= t.valid[prop][:, None]
        top = (t.p_top[prop] + pose[:, 0, :, 2])[:, None]  # (H, 1, M)
        pair = torch.where(inside, top, torch.zeros(())).amax(-1)  # (H, K)
        h = torch.zeros(xy.shape[:-1], dtype=torch.float32)
        h.scatter_reduce_(0, env[:, None].expand_as(pair), pair, "amax")
        return h.clamp_min(0.0)

    def local_surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``(count, 4)``: prop index and x, y, z in that prop's frame (area-weighted)."""
        import numpy as np
        faces: list[tuple[int, float, Sampler]] = []  # (prop, area, sampler)
        for i, part in self._tables.parts:
            faces.extend((i, area, fn) for area, fn in _faces(part))
        if not faces or count == 0:
            return np.zeros((count, 4))
        areas = np.array([a for _, a, _ in faces])
        pick = rng.choice(len(faces), size=count, p=areas / areas.sum())
        out = np.zeros((count, 4))
        for f in np.unique(pick):  # a loop over faces, not environments
            rows = np.nonzero(pick == f)[0]
            out[rows, 0] = faces[f][0]
            out[rows, 1:] = faces[f][2](rng, len(rows))
        return out

    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        import torch
        local = torch.from_numpy(self.local_surface_points(count, rng))
        return self.place_surface_points(local).numpy()

    def place_surface_points(
        self, local: torch.Tensor, dtype: torch.dtype | None = None
    ) -> torch.Tensor:
        """Prop-frame samples ``(C, 4)`` (:meth:`local_surface_points`) placed for every
        held environment ``(N, C, 3)``: callers that redraw often sample once and place many
        times (in ``dtype``, float64 when None; float32 is plenty for observations)."""
        import torch
        dtype = torch.float64 if dtype is None else dtype
        n = self._offsets.shape[0] if self._allocated else 1
        pose = self.placement(n).to(dtype)
        if local.shape[0] == 0 or pose.shape[1] == 0:
            return torch.zeros(n, local.shape[0], 3, dtype=dtype)
        return place_points(local.to(dtype), pose)


def place_points(local: torch.Tensor, pose: torch.Tensor) -> torch.Tensor:
    """Points ``(C, 4)`` (prop index, local xyz) placed by poses ``(N, P, 4)`` -> ``(N, C, 3)``."""
    import torch
    p = pose[:, local[:, 0].long()]  # (N, C, 4)
    c, s = torch.cos(p[..., 3]), torch.sin(p[..., 3])
    x, y, z = local[:, 1], local[:, 2], local[:, 3]
    return torch.stack([p[..., 0] + c * x - s * y, p[..., 1] + s * x + c * y, p[..., 2] + z], -1)


Sampler = Callable[["np.random.Generator", int], "np.ndarray"]
"""Draws ``k`` points ``(k, 3)`` on one face of a part."""


def _faces(part: Part) -> list[tuple[float, Sampler]]:
    """(area, sampler) of each exposed face of a part; samplers draw ``(k, 3)`` points."""
    import numpy as np
    hx, _, hz = part.half
    cx, cy, cz = part.pos
    out: list[tuple[float, Sampler]] = []
    if part.shape == "box":
        for axis, (a, b) in ((0, (1, 2)), (1, (0, 2)), (2, (0, 1))):
            for sign in (-1.0, 1.0):
                centre = np.array(part.pos, dtype=float)
                centre[axis] += sign * part.half[axis]
                if axis == 2 and sign < 0 and centre[2] <= _FLOOR_EPS:
                    continue  # resting on the floor: not a visible surface
                ha, hb = part.half[a], part.half[b]

                def draw(rng, k, centre=centre, a=a, b=b, ha=ha, hb=hb):
                    pts = np.tile(centre, (k, 1))
                    pts[:, a] += rng.uniform(-ha, ha, k)
                    pts[:, b] += rng.uniform(-hb, hb, k)
                    return pts

                out.append((4 * ha * hb, draw))
    else:
        r = hx

        def disc(rng: np.random.Generator, k: int, z: float) -> np.ndarray:
            rad = r * np.sqrt(rng.uniform(0, 1, k))
            ang = rng.uniform(0, 2 * np.pi, k)
            return np.stack([cx + rad * np.cos(ang), cy + rad * np.sin(ang), np.full(k, z)], 1)

        out.append((np.pi * r * r, partial(disc, z=cz + hz)))
        if cz - hz > _FLOOR_EPS:
            out.append((np.pi * r * r, partial(disc, z=cz - hz)))

        def side(rng: np.random.Generator, k: int) -> np.ndarray:
            ang = rng.uniform(0, 2 * np.pi, k)
            z = rng.uniform(cz - hz, cz + hz, k)
            return np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang), z], 1)

        out.append((2 * np.pi * r * 2 * hz, side))
    return out


def _add_part(
    body: mujoco.MjsBody,
    part: Part,
    origin: tuple[float, float, float],
    density: float,
    name: str,
) -> None:
    """A collision geom for ``part`` on ``body`` whose frame sits at ``origin`` (prop frame)."""
    import mujoco
    pos = [part.pos[i] - origin[i] for i in range(3)]
    size = list(part.half) if part.shape == "box" else [part.half[0], part.half[2], 0.0]
    body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX if part.shape == "box" else mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=size,
        pos=pos,
        density=density,
        contype=1,
        conaffinity=1,
        rgba=[0.55, 0.42, 0.3, 1.0],
    )
