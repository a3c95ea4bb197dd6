"""Joint maps and kinematic retargeting: exactness on the human, validation, every shared clip."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from _characters_common import CHARACTERS, clips

from retarget import RecipeError
from retarget.character import kinematic as km
from retarget.character.joint_map import JointLink, JointMap, euler_intrinsic
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip
from retarget.motion.import_bvh import load_bvh
from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.human import Human
from retarget.plugins.characters.oppy import Oppy


def test_hinges_compose_as_the_joint_map_decomposes() -> None:
    """MuJoCo composes a body's hinges intrinsically; the decomposition must invert that."""
    m = Human().build_spec().compile()
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    group = km.hinge_groups(m)["l_hip"]
    for _ in range(20):
        angles = rng.uniform(-0.6, 0.6, 3)
        d.qpos[:] = m.qpos0
        d.qpos[list(group.qpos_adr)] = angles
        mujoco.mj_kinematics(m, d)
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "l_thigh")
        rel = rot.mul(rot.conj(d.xquat[m.body_parentid[body]]), d.xquat[body])
        got = euler_intrinsic(rot.to_matrix(rel[None]), group.axes)[0]
        assert np.allclose(got, angles, atol=1e-9)


def _synthetic_clip(frames: int = 40) -> MotionClip:
    """Random root, hip, knee (about y) and ankle (y, x) rotations on the 1.75 m offsets."""
    rng = np.random.default_rng(2)
    local = rot.identity((frames, sk.NUM_JOINTS))
    for j in ("left_hip", "right_hip"):
        local[:, sk.joint_index(j)] = rot.from_euler(rng.uniform(-25, 25, (frames, 3)), "yzx")
    for j in ("left_ankle", "right_ankle"):  # the character's ankle has two hinges (y, x)
        local[:, sk.joint_index(j)] = rot.from_euler(rng.uniform(-25, 25, (frames, 2)), "yx")
    for j in ("left_knee", "right_knee"):
        local[:, sk.joint_index(j)] = rot.from_axis_angle(np.array([0.0, 1.0, 0.0]),
                                                          np.deg2rad(rng.uniform(0, 90, frames)))
    local[:, 0] = rot.from_euler(rng.uniform(-20, 20, (frames, 3)), "zyx")
    root = np.tile([0.0, 0.0, sk.standing_pelvis_height(sk.rest_offsets())], (frames, 1))
    return MotionClip(fps=30.0, root_pos=root, local_rot=local, offsets=sk.rest_offsets())


def test_human_character_reproduces_the_clip_exactly() -> None:
    clip = _synthetic_clip()
    human = Human()
    m = human.build_spec().compile()
    motion = km.retarget_clip(clip, m, human.joint_map())
    assert motion.root_scale == pytest.approx(1.0)
    assert motion.clip_rate == 0.0
    d = mujoco.MjData(m)
    err = 0.0
    for i in range(clip.num_frames):
        d.qpos[:] = motion.qpos[i]
        mujoco.mj_kinematics(m, d)
        for body, joint in (("l_shin", "left_knee"), ("r_foot", "right_ankle"),
                            ("l_toes", "left_toe")):
            b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
            err = max(err, float(np.linalg.norm(d.xpos[b] - clip.global_pos[i, sk.joint_index(
                joint)])))
    assert err < 1e-6, f"joint positions differ by {err:.2e} m"


def test_joint_map_errors_name_the_joint() -> None:
    oppy = Oppy()
    with pytest.raises(RecipeError, match="unknown human joint 'left_elbw'"):
        Oppy(Oppy.Config(joint_map={"l_elbow": {"human": "left_elbw"}})).joint_map()
    with pytest.raises(RecipeError, match="unknown character joint 'l_wrist'"):
        Oppy(Oppy.Config(joint_map={"l_wrist": {"human": "left_wrist"}})).joint_map()
    with pytest.raises(RecipeError, match="passive joint 'tail0'"):
        Oppy(Oppy.Config(joint_map={"tail0": {"human": "spine"}})).joint_map()
    with pytest.raises(RecipeError, match="gives 3 axes"):
        Oppy(Oppy.Config(joint_map={"l_knee": {"axes": "xyz"}})).joint_map()
    with pytest.raises(RecipeError, match="l_knee"):
        Oppy(Oppy.Config(joint_map={"l_knee": {"axes": "qq"}})).joint_map()
    assert "tail0" not in oppy.joint_map().links


def test_recipe_override_merges_and_removes() -> None:
    base = Dino().joint_map()
    dino = Dino(Dino.Config(joint_map={"spine0": {"scale": 0.5, "offset": [20, 0, 0]},
                                       "l_toe": None}))
    jmap = dino.joint_map()
    assert jmap.links["spine0"].human == base.links["spine0"].human
    assert jmap.links["spine0"].scale == 0.5
    assert "l_toe" not in jmap.links and "r_toe" in jmap.links
    # The offset leans the spine forward in the retargeted pose.
    clip = _synthetic_clip(5)
    m = dino.build_spec().compile()
    q = km.retarget_clip(clip, m, jmap).qpos
    adr = km.hinge_groups(m)["spine0"].qpos_adr
    assert np.allclose(q[:, adr[0]], np.deg2rad(20.0))  # hinge order y, z, x; spine still


def test_bend_mapping_ignores_where_twist_lives() -> None:
    link = JointMap(links={"e": JointLink(human=("left_elbow",), bend="y", axes=("-z",))})
    bend = rot.from_axis_angle(np.array([0.0, 0.0, -1.0]), np.deg2rad(70.0))
    twist = rot.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.deg2rad(60.0))
    for q in (bend, rot.mul(bend, twist), rot.mul(twist, bend)):
        angle = link.hinge_angles("e", ("z",), q[None])[0, 0]
        assert np.degrees(angle) == pytest.approx(-70.0)


CLIPS = clips()


@pytest.fixture(scope="module")
def loaded() -> list[MotionClip]:
    if not CLIPS:
        pytest.skip("shared mocap clips not available")
    return [load_bvh(p) for p in CLIPS]


@pytest.mark.parametrize("cls", CHARACTERS, ids=lambda c: c.name)
def test_every_clip_retargets_inside_limits(cls, loaded) -> None:
    c = cls()
    m = c.build_spec().compile()
    jmap = c.joint_map()
    lo, hi = m.jnt_range[1:, 0], m.jnt_range[1:, 1]
    hinge_adr = m.jnt_qposadr[1:]
    rows = []
    for clip in loaded:
        motion = km.retarget_clip(clip, m, jmap)
        q = motion.qpos
        assert np.isfinite(q).all()
        assert np.all(q[:, hinge_adr] >= lo - 1e-9) and np.all(q[:, hinge_adr] <= hi + 1e-9)
        assert np.allclose(np.linalg.norm(q[:, 3:7], axis=1), 1.0)
        art = km.foot_artefacts(m, motion, clip.contacts, c.body_groups())
        rows.append((clip.name or "?", motion.clip_rate, art))
    pen = np.mean([r[2].penetration for r in rows])
    flt = np.mean([r[2].float for r in rows])
    slide = np.mean([r[2].sliding for r in rows])
    clipped = np.mean([r[1] for r in rows])
    print(f"\n{c.name}: {len(rows)} clips, clipped {100 * clipped:.2f}% of mapped angles, foot "
          f"penetration {100 * pen:.2f} cm, float {100 * flt:.2f} cm, sliding {slide:.3f} m/s")
    assert clipped < 0.05, "the default joint map should rarely hit joint limits"
