"""Skeleton mapping: rest-pose independence, all known namings, user name maps, units, axes."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion import source_skeletons as ss
from retarget.motion.bvh_write import write_bvh
from retarget.motion.clip import MotionClip
from retarget.motion.import_bvh import load_bvh
from retarget.motion.procedural import default_motions


def _tpose_then_walk() -> MotionClip:
    """A T-pose frame followed by the generated walk (like a calibration frame in mocap)."""
    walk = default_motions(names=("walk",), fps=30.0)[0].slice(0, 60)
    tpose_root = walk.root_pos[:1].copy()
    tpose_root[0, 2] = sk.standing_pelvis_height(walk.offsets)
    return walk.with_(
        root_pos=np.concatenate([tpose_root, walk.root_pos]),
        local_rot=np.concatenate([rot.identity((1, sk.NUM_JOINTS)), walk.local_rot]),
        contacts=np.concatenate([np.ones((1, 2), bool), walk.contacts]),
    )


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(rot.angle(rot.mul(rot.conj(a), b)))


@pytest.mark.parametrize("rest", ["tpose", "random_frames", "bandai_like"])
def test_rest_pose_of_any_source_maps_to_canonical_tpose(rest, tmp_path: Path):
    """The same motion written with a different rest pose (joint frames rotated arbitrarily, or
    every bone along local X as in Bandai files) reads back as the same T-pose-relative
    rotations: the calibration frame is the identity and the walk is unchanged."""
    clip = _tpose_then_walk()
    rng = np.random.default_rng(3)
    frames = None
    if rest == "random_frames":
        frames = rot.normalize(rng.normal(size=(sk.NUM_JOINTS, 4)))
    elif rest == "bandai_like":
        # file frame of each joint: its outgoing bone along local +X
        rest_off = sk.rest_offsets()
        frames = rot.identity((sk.NUM_JOINTS,))
        for j in range(sk.NUM_JOINTS):
            kids = sk.children(j)
            if kids:
                frames[j] = rot.between(np.array([1.0, 0, 0]), rest_off[kids[0]])
    path = write_bvh(clip, tmp_path / "c.bvh", frame_rotations=frames)
    back = load_bvh(path, keep_source=True)
    assert back.meta["reference_frame"] == 0
    assert _angle_deg(back.local_rot[0], rot.identity((sk.NUM_JOINTS,))).max() < 5.0
    assert _angle_deg(back.local_rot, clip.local_rot).max() < 0.01
    assert np.abs(back.offsets - clip.offsets).max() < 1e-4
    assert np.abs(back.global_pos - back.meta["source_positions"]).max() < 1e-6


@pytest.mark.parametrize("up,units", [("+y", "cm"), ("+z", "m"), ("-x", "mm"), ("+y", "inch")])
def test_units_and_up_axis_detected(up, units, tmp_path: Path):
    clip = _tpose_then_walk()
    back = load_bvh(write_bvh(clip, tmp_path / "u.bvh", up=up, units=units))
    assert (back.meta["up"], back.meta["units"]) == (up, units)
    assert back.height == pytest.approx(clip.height, rel=1e-3)
    declared = load_bvh(tmp_path / "u.bvh", up=up, units=units)
    assert np.allclose(declared.global_pos, back.global_pos)


def _rename(text: str, mapping: dict[str, str]) -> str:
    def sub(m: re.Match) -> str:
        return f"{m.group(1)} {mapping.get(m.group(2), m.group(2))}"

    return re.sub(r"\b(ROOT|JOINT) (\S+)", sub, text)


def test_lafan1_naming_detected(tmp_path: Path):
    clip = _tpose_then_walk()
    text = write_bvh(clip, tmp_path / "c.bvh").read_text()
    lafan = {canon: src for canon, src in ss.LAFAN1.items() if src}
    (tmp_path / "l.bvh").write_text(_rename(text, lafan))
    back = load_bvh(tmp_path / "l.bvh")
    assert back.skeleton == "lafan1"
    assert _angle_deg(back.local_rot, clip.local_rot).max() < 0.01


def test_cmu_motionbuilder_naming_reads_like_3dsmax(mocap_dir: Path, tmp_path: Path):
    """The README's 3dsMax -> MotionBuilder name table applied to a real CMU file."""
    names = {"LeftHip": "LeftUpLeg", "LeftKnee": "LeftLeg", "LeftAnkle": "LeftFoot",
             "LeftToe": "LeftToeBase", "lowerback": "LowerBack", "Chest": "Spine",
             "Chest2": "Spine1", "lowerneck": "Neck", "Neck": "Neck1",
             "LeftCollar": "LeftShoulder", "LeftShoulder": "LeftArm",
             "LeftElbow": "LeftForeArm", "LeftWrist": "LeftHand", "lhand": "LeftFingerBase",
             "LFingers": "LeftHandIndex1"}
    for k, v in list(names.items()):
        if k.startswith("Left") or k in ("lhand", "LFingers"):
            rk = k.replace("Left", "Right").replace("lhand", "rhand").replace("LFingers",
                                                                              "RFingers")
            names[rk] = v.replace("Left", "Right")
    src = mocap_dir / "cmu_131_01_walk_start_stop.bvh"
    (tmp_path / "mb.bvh").write_text(_rename(src.read_text(), names))
    a, b = load_bvh(src), load_bvh(tmp_path / "mb.bvh")
    assert (a.skeleton, b.skeleton) == ("cmu_3dsmax", "cmu_motionbuilder")
    assert np.abs(a.global_pos - b.global_pos).max() < 1e-9


def test_user_name_map(tmp_path: Path):
    clip = _tpose_then_walk()
    text = write_bvh(clip, tmp_path / "c.bvh").read_text()
    odd = {n: f"bone_{i:02d}" for i, n in enumerate(sk.JOINT_NAMES)}
    (tmp_path / "odd.bvh").write_text(_rename(text, odd))
    with pytest.raises(MotionError) as info:
        load_bvh(tmp_path / "odd.bvh")
    assert "pelvis" in str(info.value) and "name map" in str(info.value)
    back = load_bvh(tmp_path / "odd.bvh", name_map=odd)
    assert back.skeleton == "custom"
    assert _angle_deg(back.local_rot, clip.local_rot).max() < 0.01
    bad = dict(odd, left_knee="nope")
    with pytest.raises(MotionError, match="left_knee -> nope"):
        load_bvh(tmp_path / "odd.bvh", name_map=bad)


def test_name_map_with_missing_joint_rides_on_parent(tmp_path: Path):
    clip = _tpose_then_walk()
    write_bvh(clip, tmp_path / "c.bvh")
    mapping = {n: n for n in sk.JOINT_NAMES}
    mapping["spine2"] = None  # pretend the source has no second chest joint
    back = load_bvh(tmp_path / "c.bvh", name_map=mapping, keep_source=True)
    assert np.linalg.norm(back.offsets[sk.joint_index("spine2")]) < 1e-9
    # the file's own spine2 joint still bends, which one canonical frame cannot carry exactly:
    # the error stays small (the generated walk barely bends the chest)
    err = np.abs(back.global_pos - back.meta["source_positions"]).max()
    assert 0 < err < 0.01


def test_plugin_config_passes_options(tmp_path: Path):
    from retarget.plugins.formats.bvh import Bvh

    path = Bvh.write_sample(tmp_path)
    native = Bvh().read(path)
    at36 = Bvh(Bvh.Config(fps=36.0)).read(path)
    assert at36.fps == 36.0 and at36.duration == pytest.approx(native.duration, abs=1 / 30)
    with pytest.raises(Exception, match="units"):
        Bvh.Config(units="furlong")
    first = Bvh(Bvh.Config(reference_frame=0)).read(path)  # the sample starts in the T-pose
    assert np.degrees(rot.angle(first.local_rot[0])).max() < 1e-3
    with pytest.raises(MotionError, match="outside"):
        Bvh(Bvh.Config(reference_frame=10_000)).read(path)
