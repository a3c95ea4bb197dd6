"""Compose a character and a scene into one MuJoCo model, and describe it as a :class:`Layout`.

The character's spec is the world: the scene adds its floor and props to it, so names stay
unprefixed and role sites resolve by their plain names. Without a scene a plain floor is added.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from retarget.errors import PluginError
from retarget.kinds import REQUIRED_GROUPS, REQUIRED_SITES, Character, Scene
from retarget.kinds.state import Layout
from retarget.scene.ground import Ground
from retarget.sim.batched import add_contact_force_sensor


@dataclass(frozen=True)
class World:
    """A compiled model plus the layout plugins bind to."""

    model: mujoco.MjModel
    layout: Layout
    spec: mujoco.MjSpec


def _fail(character: Character, message: str) -> PluginError:
    return PluginError(message, plugin=f"character {character.name}")


def build_world(character: Character, scene: Scene | None = None) -> World:
    """Build and compile character + scene; errors name the plugin that caused them."""
    spec = character.build_spec()
    body_names = tuple(b.name for b in spec.bodies if b.name and b.name != "world")
    if scene is None:
        scene = Ground()
    try:
        scene.build(spec)
    except Exception as exc:
        raise PluginError(f"build failed: {exc}", plugin=f"scene {scene.name}") from exc
    root_site = dict(character.site_roles()).get("root")
    if root_site is not None:
        add_contact_force_sensor(spec, root_site)
    try:
        model = spec.compile()
    except Exception as exc:
        raise _fail(character, f"MJCF does not compile: {exc}") from exc
    return World(model=model, layout=layout_of(character, model, body_names), spec=spec)


_QPOS_SIZE = {
    mujoco.mjtJoint.mjJNT_FREE: (7, 6),
    mujoco.mjtJoint.mjJNT_BALL: (4, 3),
    mujoco.mjtJoint.mjJNT_SLIDE: (1, 1),
    mujoco.mjtJoint.mjJNT_HINGE: (1, 1),
}


def _character_dofs(
    character: Character, model: mujoco.MjModel, body_names: tuple[str, ...]
) -> tuple[int, int]:
    """``(nq, nv)`` of the character alone: a scene's articulated props add joints after it.

    The character's spec is compiled first, so its joints are the leading block of ``qpos`` and
    ``qvel``; a scene joint inside that block would break every ``qpos[:, 7:]`` slice, so it is
    an error rather than a silent mix.
    """
    names = set(body_names)
    nq = nv = 0
    for j in range(model.njnt):
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
        if body not in names:
            continue
        q, v = _QPOS_SIZE[mujoco.mjtJoint(model.jnt_type[j])]
        if model.jnt_qposadr[j] != nq or model.jnt_dofadr[j] != nv:
            raise _fail(
                character,
                f"joint {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)} does not follow "
                "the character's previous joints in qpos",
            )
        nq, nv = nq + q, nv + v
    return nq, nv


def layout_of(character: Character, model: mujoco.MjModel, body_names: tuple[str, ...]) -> Layout:
    """Names and index groups of the character inside ``model``."""

    def name(obj: int, i: int) -> str:
        return mujoco.mj_id2name(model, obj, i) or ""

    if model.njnt == 0 or model.jnt_type[0] != mujoco.mjtJoint.mjJNT_FREE:
        raise _fail(character, "the first joint must be the root's free joint")
    joints = tuple(
        name(mujoco.mjtObj.mjOBJ_JOINT, j)
        for j in range(1, model.njnt)
        if model.jnt_bodyid[j] != 0
        and name(mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j]) in body_names
    )
    actuators = tuple(name(mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu))
    roles = dict(character.site_roles())
    missing = [r for r in REQUIRED_SITES if r not in roles]
    if missing:
        raise _fail(character, f"site_roles() lacks required roles: {', '.join(missing)}")
    for role, site in roles.items():
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site) < 0:
            raise _fail(character, f"role '{role}' names site '{site}', which does not exist")
    groups: dict[str, tuple[int, ...]] = {}
    for group, members in character.body_groups().items():
        idx = []
        for body in members:
            if body not in body_names:
                raise _fail(character, f"body group '{group}' names unknown body '{body}'")
            idx.append(body_names.index(body))
        groups[group] = tuple(idx)
    missing = [g for g in REQUIRED_GROUPS if g not in groups]
    if missing:
        raise _fail(character, f"body_groups() lacks required groups: {', '.join(missing)}")
    weights = character.joint_weights()
    unknown = sorted(set(weights) - set(joints))
    if unknown:
        raise _fail(character, f"joint_weights() names unknown joints: {', '.join(unknown)}")
    passive = tuple(character.passive_joints())
    nq, nv = _character_dofs(character, model, body_names)
    gear = np.asarray(model.actuator_gear[:, 0], dtype=float)
    hinge = model.actuator_trnid[:, 0]
    return Layout(
        body_names=body_names,
        body_ids=tuple(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in body_names),
        joint_names=joints,
        actuator_names=actuators,
        site_names=tuple(roles),
        site_ids=tuple(
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, s) for s in roles.values()
        ),
        body_groups=groups,
        nq=nq,
        nv=nv,
        joint_weights=tuple(float(weights.get(j, 1.0)) for j in joints),
        torque_limits=tuple(float(g) for g in gear),
        passive_joints=passive,
        actuator_qpos=tuple(int(model.jnt_qposadr[j]) for j in hinge),
        actuator_ranges=tuple((float(model.jnt_range[j, 0]), float(model.jnt_range[j, 1]))
                              for j in hinge),
    )
