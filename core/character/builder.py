"""Procedural MJCF for articulated characters, on top of ``mujoco.MjSpec``.

Characters are described in code (from their pydantic ``Config``), not as hand-written XML, so
that a height, a tail mode or a torque scale is a parameter rather than a fork of a file. This
module is the public helper every character (built-in or third-party) uses; it encodes the
conventions the rest of retarget relies on:

* **Free root first.** The root body carries a ``freejoint`` named ``root`` so ``qpos[:7]`` is
  the root position and wxyz quaternion.
* **Joints are groups of hinges.** A 3-DoF joint (hip, shoulder, spine) is three hinges in one
  body named ``<joint>_x``, ``<joint>_y``, ``<joint>_z`` (in the order given); a 1-DoF joint is a
  single hinge named ``<joint>``. Hinges composed in one body rotate intrinsically
  (``R = R1(q1) R2(q2) R3(q3)``), which is what :mod:`retarget.character.joint_map` decomposes
  into. Hinges rather than MuJoCo ball joints keep every DoF an angle with its own limit, torque
  limit and reward weight, which is how the paper counts DoF (Jesse: 16 links, 32 DoF).
* **Zero pose is the canonical T-pose frame.** Every body frame is world-aligned at ``qpos0``
  (bodies only translate relative to their parent), so a human local rotation relative to the
  canonical T-pose maps onto a character joint without a per-joint frame change.
* **Torque actuators.** Every active hinge gets a ``motor`` with ``ctrlrange = [-1, 1]`` and
  ``gear`` = its torque limit (N m), so the policy's action in ``[-1, 1]`` is scaled to the
  per-joint limit by MuJoCo itself; ``forcerange`` repeats the limit as a hard clamp.
* **Passive joints** (tails, ears) are spring-dampers without an actuator. Their stiffness and
  damping are given as a natural frequency and damping ratio and converted with the joint's
  effective inertia at the rest pose, so a scaled character keeps the same swing character.
* **Contacts.** Character geoms have ``contype=2, conaffinity=1``: two character geoms never
  collide (``2 & 1 == 0``), while a scene geom with ``contype=conaffinity=1`` collides with all
  of them.
* **Masses from uniform density.** Geoms get one density, chosen so the total mass hits the
  requested target (or the density is given directly); inertias follow from the geometry.
* **Integration.** ``implicitfast`` with ``DEFAULT_TIMESTEP`` = 1/360 s, i.e. 10 substeps per
  36 Hz control step. Joint damping is integrated implicitly, so even the light links of a 7 kg
  character under full torque stay stable; the ``armature`` added to actuated hinges keeps the
  joint-space mass matrix well conditioned for light distal links (hands, toes). The stability
  measurements behind these numbers are in ``benchmarks/bench_characters.py``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import mujoco

Vec3 = tuple[float, float, float]

DEFAULT_TIMESTEP = 1.0 / 360.0
"""Physics timestep (s): 10 substeps per control step at the paper's 36 Hz."""

CONTROL_RATE_HZ = 36.0
"""Control rate of the paper (Table 3); ``DEFAULT_TIMESTEP`` divides it evenly."""

CHARACTER_CONTYPE = 2
CHARACTER_CONAFFINITY = 1

DAMPING_PER_NM = 0.01
"""Joint damping (N m s/rad) per N m of torque limit on actuated hinges: bounds the speed a
saturated light link reaches (terminal velocity = 100 rad/s) without visibly slowing the body."""

ARMATURE_PER_NM = 1e-4
"""Armature (kg m^2) per N m of torque limit: a rotor inertia that scales with the joint's
strength, so a 300 N m hip gets 0.03 and a 4 N m Oppy elbow 4e-4."""

PASSIVE_ARMATURE = 0.5
"""Armature of a passive hinge as a fraction of its effective inertia at rest. Tail tips and ear
segments weigh grams; without it a violently moving body makes them the stiffest part of the
system. The spring is tuned with the armature included, so the frequency is unchanged."""

AXES: Mapping[str, Vec3] = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Capsule:
    """A capsule from ``start`` to ``end`` (body frame, metres)."""

    start: Vec3
    end: Vec3
    radius: float


@dataclass(frozen=True)
class Sphere:
    center: Vec3
    radius: float


@dataclass(frozen=True)
class Box:
    center: Vec3
    half_size: Vec3


@dataclass(frozen=True)
class Ellipsoid:
    center: Vec3
    radii: Vec3


Geom = Capsule | Sphere | Box | Ellipsoid


# ---------------------------------------------------------------------------------------------
# Joints
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Dof:
    """One hinge of a joint: an axis of the (world-aligned) body frame and limits in degrees."""

    axis: str
    lower: float
    upper: float

    def __post_init__(self) -> None:
        if self.axis not in AXES:
            raise ValueError(f"hinge axis must be one of x, y, z, got {self.axis!r}")
        if not self.lower < self.upper:
            raise ValueError(
                f"hinge limits must satisfy lower < upper, got {self.lower}, {self.upper}"
            )


@dataclass(frozen=True)
class Joint:
    """A joint between a body and its parent: one to three hinges.

    ``torque`` > 0 makes it active (one motor per hinge with that limit); ``torque == 0`` makes
    it passive: a spring-damper towards the rest pose with natural frequency ``frequency`` (Hz)
    and damping ratio ``damping_ratio``, and no actuator.
    """

    name: str
    dofs: tuple[Dof, ...]
    torque: float = 0.0
    frequency: float = 2.0
    damping_ratio: float = 0.2

    @property
    def passive(self) -> bool:
        return self.torque <= 0.0

    def hinge_names(self) -> tuple[str, ...]:
        if len(self.dofs) == 1:
            return (self.name,)
        return tuple(f"{self.name}_{d.axis}" for d in self.dofs)


def hinge(
    name: str, axis: str, lower: float, upper: float, torque: float = 0.0, **passive: float
) -> Joint:
    """A 1-DoF joint (elbow, knee, tail segment pitch)."""
    return Joint(name, (Dof(axis, lower, upper),), torque, **passive)


def ball(
    name: str,
    x: tuple[float, float],
    y: tuple[float, float],
    z: tuple[float, float],
    torque: float = 0.0,
    order: str = "xyz",
    **passive: float,
) -> Joint:
    """A 3-DoF joint as three hinges (limits in degrees per axis, applied in ``order``)."""
    limits = {"x": x, "y": y, "z": z}
    return Joint(name, tuple(Dof(a, *limits[a]) for a in order), torque, **passive)


def joint(
    name: str, limits: Mapping[str, tuple[float, float]], torque: float = 0.0, **passive: float
) -> Joint:
    """A joint with the hinges named in ``limits`` (insertion order = rotation order)."""
    return Joint(name, tuple(Dof(a, lo, hi) for a, (lo, hi) in limits.items()), torque, **passive)


# ---------------------------------------------------------------------------------------------
# What a build produces
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class JointInfo:
    """A built joint: its hinges (in rotation order), axes, body and whether it is actuated."""

    name: str
    body: str
    hinges: tuple[str, ...]
    axes: tuple[str, ...]
    passive: bool
    torque: float


@dataclass
class BuiltCharacter:
    """A finished spec plus the facts about it that are cheaper to keep than to rediscover."""

    spec: mujoco.MjSpec
    joints: dict[str, JointInfo]
    density: float
    mass: float
    height: float

    def passive_hinges(self) -> tuple[str, ...]:
        return tuple(h for j in self.joints.values() if j.passive for h in j.hinges)

    def hinge_names(self) -> tuple[str, ...]:
        return tuple(h for j in self.joints.values() for h in j.hinges)


@dataclass
class _BodyRecord:
    name: str
    parent: str | None
    pos: Vec3
    geoms: tuple[Geom, ...]
    joint: Joint | None
    rgba: tuple[float, float, float, float]
    sites: list[tuple[str, Vec3, float]] = field(default_factory=list)


class BodyBuilder:
    """Collects bodies, joints and sites, then builds an ``MjSpec`` with the conventions above.

    Example::

        b = BodyBuilder("stick")
        b.root("pelvis", (0, 0, 1), [Capsule((0, -.1, 0), (0, .1, 0), .08)])
        b.body("thigh_l", "pelvis", (0, .1, 0), [Capsule((0, 0, 0), (0, 0, -.4), .05)],
               ball("hip_l", (-30, 30), (-120, 30), (-30, 30), torque=300))
        b.site("root", "pelvis", (0, 0, 0))
        built = b.build(mass=20.0)   # a BuiltCharacter; built.spec is the MjSpec
    """

    def __init__(
        self,
        name: str,
        *,
        timestep: float = DEFAULT_TIMESTEP,
        rgba: tuple[float, float, float, float] = (0.7, 0.6, 0.5, 1.0),
        damping_per_nm: float = DAMPING_PER_NM,
        armature_per_nm: float = ARMATURE_PER_NM,
        passive_armature: float = PASSIVE_ARMATURE,
    ) -> None:
        self.name = name
        self.timestep = timestep
        self.damping_per_nm = damping_per_nm
        self.armature_per_nm = armature_per_nm
        self.passive_armature = passive_armature
        self.rgba = rgba
        self._bodies: dict[str, _BodyRecord] = {}
        self._root: str | None = None

    # -- description -------------------------------------------------------------------------

    def root(
        self,
        name: str,
        pos: Vec3,
        geoms: Iterable[Geom],
        rgba: tuple[float, float, float, float] | None = None,
    ) -> None:
        """The root body (free joint ``root``); ``pos`` is its rest position (z is adjusted so
        the lowest geom touches the floor)."""
        if self._root is not None:
            raise ValueError(f"root already set to {self._root!r}")
        self._root = name
        self._add(_BodyRecord(name, None, pos, tuple(geoms), None, rgba or self.rgba))

    def body(
        self,
        name: str,
        parent: str,
        pos: Vec3,
        geoms: Iterable[Geom],
        joint: Joint | None = None,
        rgba: tuple[float, float, float, float] | None = None,
    ) -> None:
        """A child body at ``pos`` in its parent's frame; ``joint=None`` welds it to the parent."""
        if parent not in self._bodies:
            raise ValueError(f"body {name!r}: unknown parent {parent!r}")
        self._add(_BodyRecord(name, parent, pos, tuple(geoms), joint, rgba or self.rgba))

    def site(self, name: str, body: str, pos: Vec3, size: float = 0.02) -> None:
        """A named site (role mount: head, hands, root) in a body's frame."""
        if body not in self._bodies:
            raise ValueError(f"site {name!r}: unknown body {body!r}")
        self._bodies[body].sites.append((name, pos, size))

    def has_body(self, name: str) -> bool:
        return name in self._bodies

    def _add(self, rec: _BodyRecord) -> None:
        if rec.name in self._bodies:
            raise ValueError(f"duplicate body {rec.name!r}")
        self._bodies[rec.name] = rec

    # -- build ---------------------------------------------------------------------------------

    def build(self, *, mass: float | None = None, density: float = 1000.0) -> BuiltCharacter:
        """Build the spec; with ``mass`` the uniform density is solved for to hit it exactly."""
        if self._root is None:
            raise ValueError("no root body")
        # Pass 1: geometry at the given density to learn the total volume and the floor offset.
        spec, joints = self._make_spec(density, lift=0.0, passive_gains=None)
        model = spec.compile()
        total = float(model.body_mass.sum())
        if mass is not None:
            density = density * mass / total
        low, high = _rest_extent(model)
        # Pass 2: correct density and lift so the lowest point is on the floor; learn the
        # passive joints' effective inertia at rest for their spring-damper gains.
        spec, joints = self._make_spec(density, lift=-low, passive_gains=None)
        model = spec.compile()
        params = {
            h: (r.joint.frequency, r.joint.damping_ratio)
            for r in self._bodies.values()
            if r.joint is not None and r.joint.passive
            for h in r.joint.hinge_names()
        }
        gains = _passive_gains(model, params, self.passive_armature)
        spec, joints = self._make_spec(density, lift=-low, passive_gains=gains)
        model = spec.compile()
        return BuiltCharacter(
            spec=spec,
            joints=joints,
            density=density,
            mass=float(model.body_mass.sum()),
            height=high - low,
        )

    def _make_spec(
        self,
        density: float,
        lift: float,
        passive_gains: Mapping[str, tuple[float, float, float, float]] | None,
    ) -> tuple[mujoco.MjSpec, dict[str, JointInfo]]:
        import mujoco
        spec = mujoco.MjSpec()
        spec.modelname = self.name
        spec.compiler.degree = False
        spec.compiler.autolimits = True
        spec.option.timestep = self.timestep
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        handles: dict[str, mujoco.MjsBody] = {}
        joints: dict[str, JointInfo] = {}
        for rec in self._bodies.values():
            parent = spec.worldbody if rec.parent is None else handles[rec.parent]
            pos = list(rec.pos)
            if rec.parent is None:
                pos[2] += lift
            body = parent.add_body(name=rec.name, pos=pos)
            handles[rec.name] = body
            if rec.parent is None:
                body.add_freejoint(name="root")
            for i, g in enumerate(rec.geoms):
                _add_geom(body, f"{rec.name}_geom{i}", g, density, rec.rgba)
            for sname, spos, ssize in rec.sites:
                body.add_site(
                    name=sname,
                    pos=list(spos),
                    size=[ssize, 0, 0],
                    rgba=[1.0, 0.2, 0.2, 0.6],
                    group=4,
                )
            if rec.joint is not None:
                joints[rec.joint.name] = _add_joint(
                    spec, body, rec.joint, passive_gains, self.damping_per_nm, self.armature_per_nm
                )
        return spec, joints


def _add_geom(
    body: mujoco.MjsBody, name: str, g: Geom, density: float, rgba: Sequence[float]
) -> None:
    import mujoco
    kw: dict[str, object] = dict(
        name=name,
        density=density,
        rgba=list(rgba),
        contype=CHARACTER_CONTYPE,
        conaffinity=CHARACTER_CONAFFINITY,
        condim=3,
        friction=[1.0, 0.05, 0.01],
    )
    if isinstance(g, Capsule):
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            fromto=[*g.start, *g.end],
            size=[g.radius, 0, 0],
            **kw,
        )
    elif isinstance(g, Sphere):
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_SPHERE, pos=list(g.center), size=[g.radius, 0, 0], **kw
        )
    elif isinstance(g, Box):
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(g.center), size=list(g.half_size), **kw
        )
    elif isinstance(g, Ellipsoid):
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, pos=list(g.center), size=list(g.radii), **kw
        )
    else:  # pragma: no cover - the Geom union is closed
        raise TypeError(f"unknown geom {g!r}")


def _add_joint(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    j: Joint,
    passive_gains: Mapping[str, tuple[float, float, float, float]] | None,
    damping_per_nm: float,
    armature_per_nm: float,
) -> JointInfo:
    import mujoco
    names = j.hinge_names()
    for hname, dof in zip(names, j.dofs, strict=True):
        jh = body.add_joint(
            name=hname,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=list(AXES[dof.axis]),
            range=[math.radians(dof.lower), math.radians(dof.upper)],
        )
        jh.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        if j.passive:
            k, c, ref, arm = (passive_gains or {}).get(hname, (1.0, 0.1, 0.0, 0.0))
            jh.stiffness = [k, 0.0, 0.0]  # MuJoCo >= 4: polynomial coefficients, linear first
            jh.damping = [c, 0.0, 0.0]
            jh.springref = ref
            jh.armature = arm
        else:
            jh.damping = [damping_per_nm * j.torque, 0.0, 0.0]
            jh.armature = armature_per_nm * j.torque
            act = spec.add_actuator(name=hname, target=hname, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_motor()
            act.gear = [j.torque, 0, 0, 0, 0, 0]
            act.ctrlrange = [-1.0, 1.0]
            act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = [-j.torque, j.torque]
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    return JointInfo(
        name=j.name,
        body=body.name,
        hinges=names,
        axes=tuple(d.axis for d in j.dofs),
        passive=j.passive,
        torque=j.torque,
    )


def _passive_gains(
    model: mujoco.MjModel, params: Mapping[str, tuple[float, float]], armature: float
) -> dict[str, tuple[float, float, float, float]]:
    """Stiffness/damping per passive hinge from its effective inertia at the rest pose.

    ``params`` maps hinge name -> (frequency Hz, damping ratio). ``k = I w^2`` and
    ``c = 2 zeta I w`` with ``w = 2 pi f`` and ``I`` the diagonal of the joint-space mass matrix:
    the joint swings at ``f`` Hz with damping ratio ``zeta`` when the rest of the chain is held,
    whatever the character's scale. Returns hinge -> (stiffness, damping, springref, armature),
    the armature being ``armature`` times the inertia and included in ``I``.
    """
    import mujoco
    import numpy as np
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    unit = np.zeros(model.nv)
    column = np.zeros(model.nv)
    out: dict[str, tuple[float, float, float, float]] = {}
    for hname, (freq, zeta) in params.items():
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, hname)
        dof = model.jnt_dofadr[jid]
        unit[:] = 0.0
        unit[dof] = 1.0
        mujoco.mj_mulM(model, data, column, unit)  # M e_dof: version-independent access to M
        arm = armature * float(column[dof])
        inertia = float(column[dof]) + arm
        w = 2 * math.pi * freq
        k = inertia * w * w
        # Pre-load the spring so gravity and spring balance at the rest pose: a heavy tail then
        # holds its modelled shape when standing and swings about it, instead of sagging.
        springref = float(data.qfrc_bias[dof]) / k
        out[hname] = (k, 2 * zeta * inertia * w, springref, arm)
    return out


def _rest_extent(model: mujoco.MjModel) -> tuple[float, float]:
    """Lowest and highest world z of any geom at ``qpos0`` (from the geoms' bounding boxes)."""
    import mujoco
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return geom_z_extent(model, data)


def geom_z_extent(
    model: mujoco.MjModel, data: mujoco.MjData, geoms: Sequence[int] | None = None
) -> tuple[float, float]:
    """World z range covered by ``geoms`` (all by default) in the pose of ``data``."""
    ids = range(model.ngeom) if geoms is None else geoms
    lo, hi = math.inf, -math.inf
    for g in ids:
        if model.geom_bodyid[g] == 0:
            continue
        z_lo, z_hi = _geom_z(model, data, g)
        lo, hi = min(lo, z_lo), max(hi, z_hi)
    return lo, hi


def _geom_z(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> tuple[float, float]:
    """Exact z extent of capsules, spheres, ellipsoids and boxes in the current pose."""
    import mujoco
    import numpy as np
    t = model.geom_type[g]
    size = model.geom_size[g]
    center = data.geom_xpos[g]
    rot = data.geom_xmat[g].reshape(3, 3)
    if t == mujoco.mjtGeom.mjGEOM_SPHERE:
        half = size[0]
    elif t == mujoco.mjtGeom.mjGEOM_CAPSULE:
        half = abs(rot[2, 2]) * size[1] + size[0]
    elif t == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        half = math.sqrt(float(np.sum((rot[2] * size) ** 2)))
    elif t == mujoco.mjtGeom.mjGEOM_BOX:
        half = float(np.sum(np.abs(rot[2]) * size))
    else:
        half = float(np.max(size))
    return float(center[2] - half), float(center[2] + half)
