"""The four characters against the paper's Table 1 and Table 4, and the body conventions."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from _characters_common import BUILT_DOF, CHARACTERS, TABLE1

from retarget.character.builder import CHARACTER_CONAFFINITY, CHARACTER_CONTYPE, geom_z_extent
from retarget.kinds.character import REQUIRED_GROUPS, REQUIRED_SITES
from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.jesse import Jesse
from retarget.plugins.characters.oppy import Oppy


def _compiled(cls, **cfg):
    c = cls(cls.Config(**cfg))
    return c, c.build_spec().compile()


@pytest.mark.parametrize("cls", CHARACTERS, ids=lambda c: c.name)
def test_table1_mass_height_links_dof(cls) -> None:
    c, m = _compiled(cls)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    low, high = geom_z_extent(m, d)
    mass = float(m.body_mass.sum())
    links, dof = m.nbody - 1, m.nv - 6
    target = TABLE1[c.name]
    print(f"\n{c.name}: mass {mass:.2f} kg (target {target['mass']}), height {high - low:.3f} m "
          f"(target {target['height']}), links {links} (Table 1: {target['links']}), DoF {dof} "
          f"(Table 1: {target['dof']}), actuated {m.nu}, density {c.built().density:.0f} kg/m3")
    assert abs(mass - target["mass"]) <= 0.05 * target["mass"]
    assert abs((high - low) - target["height"]) <= 0.05 * target["height"]
    assert abs(low) < 1e-6, "the lowest point at rest must touch the floor"
    assert links == target["links"]
    assert dof == BUILT_DOF[c.name]
    # Uniform density solved from the mass target: it must still be a plausible material.
    assert 200.0 <= c.built().density <= 1500.0


@pytest.mark.parametrize("cls", CHARACTERS, ids=lambda c: c.name)
def test_roles_groups_and_contacts(cls) -> None:
    c, m = _compiled(cls)
    for role in REQUIRED_SITES:
        assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, c.site_roles()[role]) >= 0
    groups = c.body_groups()
    for name in (*REQUIRED_GROUPS, "contact", "hands", "left_foot", "right_foot"):
        assert groups[name], name
        for body in groups[name]:
            assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body) >= 0, (name, body)
    assert not set(groups["feet"]) & set(groups["upper_body"])
    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    body_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0]
    assert all(m.geom_contype[g] == CHARACTER_CONTYPE for g in body_geoms)
    assert all(m.geom_conaffinity[g] == CHARACTER_CONAFFINITY for g in body_geoms)
    # Self-collision off: no pair of character geoms passes MuJoCo's contype/conaffinity test.
    assert not CHARACTER_CONTYPE & CHARACTER_CONAFFINITY
    # The headset mount is the highest role site and in front of the head body.
    head = m.site_pos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "head")]
    assert head[0] > 0


@pytest.mark.parametrize("cls", CHARACTERS, ids=lambda c: c.name)
def test_weights_and_passive_joints(cls) -> None:
    c, m = _compiled(cls)
    weights = c.joint_weights()
    hinges = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(1, m.njnt)]
    assert set(weights) == set(hinges)
    actuated = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, m.actuator_trnid[a, 0])
                for a in range(m.nu)}
    assert actuated.isdisjoint(c.passive_joints())
    assert set(hinges) == actuated | set(c.passive_joints())
    assert all(weights[p] == 0.0 for p in c.passive_joints())
    lower = 0.3 if c.name in ("dino", "oppy") else 1.0  # App. A
    assert weights["l_knee"] == lower and weights["r_hip_y"] == lower
    assert weights["neck_y"] == 1.0


def _gear(m, name: str) -> float:
    return float(m.actuator_gear[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name), 0])


def test_table4_torque_scales() -> None:
    _, dino = _compiled(Dino, max_torque=300.0)  # the paper's Table 3 limit
    assert _gear(dino, "l_shoulder_x") == pytest.approx(60.0)  # 0.2 * 300
    assert _gear(dino, "r_elbow") == pytest.approx(30.0)  # 0.1
    assert _gear(dino, "head_y") == pytest.approx(30.0) and _gear(dino, "neck_z") == 30.0
    assert _gear(dino, "spine2_x") == pytest.approx(300.0)
    assert _gear(dino, "tail0_z") == pytest.approx(150.0)  # Tail0 0.5
    assert _gear(dino, "tail1_y") == pytest.approx(120.0)  # Tail1 0.4
    assert _gear(dino, "l_knee") == pytest.approx(300.0)
    _, jesse = _compiled(Jesse)
    assert _gear(jesse, "spine_y") == pytest.approx(75.0)  # Jesse's spine 0.25
    assert np.max(jesse.actuator_gear[:, 0]) == pytest.approx(300.0)
    _, oppy = _compiled(Oppy)
    assert np.max(oppy.actuator_gear[:, 0]) == pytest.approx(40.0)
    assert _gear(oppy, "neck_x") == pytest.approx(4.0)
    assert all(oppy.actuator_forcerange[:, 1] == oppy.actuator_gear[:, 0])
    _, heavy = _compiled(Dino)  # the default: scaled for a body of 180 kg that can stand
    assert _gear(heavy, "l_knee") == pytest.approx(900.0)
    assert _gear(heavy, "tail0_z") == pytest.approx(450.0)


@pytest.mark.parametrize(
    ("cfg", "passive", "tail_motors", "tail_dof"),
    [
        ({}, 12, 4, 16),  # Fig. 8 left: 2 active + 6 passive (2 hinges each)
        ({"tail": "fixed"}, 0, 4, 4),  # Fig. 8 centre: 2 active + 6 welded
        ({"tail": "passive", "tail_active": 0}, 16, 0, 16),  # Fig. 8 right: all passive
        ({"tail": "active"}, 0, 16, 16),  # all eight actuated
    ],
)
def test_dino_tail_modes(cfg, passive, tail_motors, tail_dof) -> None:
    c, m = _compiled(Dino, **cfg)
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
    assert len(c.passive_joints()) == passive
    assert sum(n.startswith("tail") for n in names) == tail_dof
    motors = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(m.nu)]
    assert sum(n.startswith("tail") for n in motors) == tail_motors
    assert m.nbody - 1 == 30  # fixing joints keeps the links


def test_oppy_tail_and_ears_are_all_passive() -> None:
    c, _ = _compiled(Oppy)
    passive = set(c.passive_joints())
    assert len([p for p in passive if p.startswith("tail")]) == 3 * 2
    assert len([p for p in passive if "_ear" in p]) == 2 * 4 * 3
    assert passive == {p for p in passive if p.startswith("tail") or "_ear" in p}


def test_height_config_scales_everything() -> None:
    _, small = _compiled(Dino, height=1.25, mass=22.5)
    d = mujoco.MjData(small)
    mujoco.mj_forward(small, d)
    low, high = geom_z_extent(small, d)
    assert high - low == pytest.approx(1.25, rel=1e-3)
    assert small.body_mass.sum() == pytest.approx(22.5, rel=1e-3)


def _passive_only(character) -> mujoco.MjModel:
    """The character with its root and every active joint welded: only passive joints move."""
    spec = character.build_spec()
    passive = set(character.passive_joints())
    for j in list(spec.joints):
        if j.name not in passive:
            for act in [a for a in spec.actuators if a.target == j.name]:
                spec.delete(act)
            spec.delete(j)
    return spec.compile()


def test_passive_springs_hold_the_rest_pose_against_gravity() -> None:
    # Preloaded springs balance gravity at the modelled shape: a heavy tail does not sag.
    for cls in (Dino, Oppy):
        c = cls()
        m = _passive_only(c)
        assert m.nv == len(c.passive_joints())
        d = mujoco.MjData(m)
        for _ in range(720):  # 2 s
            mujoco.mj_step(m, d)
        sag = np.degrees(np.abs(d.qpos)).max()
        print(f"\n{c.name}: largest passive joint sag after 2 s, body held: {sag:.4f} deg")
        assert sag < 0.5
