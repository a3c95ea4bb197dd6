"""Position-only captures and AMASS files onto the canonical skeleton: round trips from known
canonical clips, the layouts the project knows, and clear errors for what is missing."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.amass_write import amass_arrays, write_amass
from retarget.motion.import_amass import SMPL_OF_CANONICAL, C, load_amass
from retarget.motion.import_positions import load_positions, read_joint_names
from retarget.motion.position_layouts import MIXAMO_SHORT_SPINE, SMPL
from retarget.motion.procedural import default_motions
from retarget.motion.resample import resample

CLIPS = default_motions()


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(2 * np.arccos(np.clip(np.abs((a * b).sum(-1)), 0, 1)))


@pytest.mark.parametrize("clip", CLIPS, ids=[c.name for c in CLIPS])
def test_positions_of_a_known_clip_fit_back_within_a_centimetre(clip, tmp_path) -> None:
    path = tmp_path / "clip.npz"
    np.savez(path, positions=clip.global_pos.astype(np.float32), joints=np.array(sk.JOINT_NAMES),
             fps=np.array(clip.fps))  # fmt: skip
    fitted = load_positions(path)
    shift = fitted.meta["floor_shift"]
    target = clip.global_pos + np.array([0.0, 0.0, shift])
    err = np.linalg.norm(fitted.global_pos - target, axis=-1)
    assert err.max() < 0.01, f"max joint error {err.max() * 1e3:.1f} mm"
    # bones with a child get their rotation from the data: close to the clip's own
    inner = [j for j in range(sk.NUM_JOINTS) if sk.children(j)]
    assert np.median(_angle(fitted.global_rot[:, inner], clip.global_rot[:, inner])) < 3.0


def test_mixamo_names_with_a_two_joint_spine_and_a_names_file(tmp_path) -> None:
    """The box-climb layout: Mixamo-style names, extra finger and foot points, no Spine2."""
    walk = CLIPS[1]
    layout = {v: k for k, v in MIXAMO_SHORT_SPINE.items() if isinstance(v, str)}
    names = [*layout, "LeftHandMiddle1", "RightHandMiddle1", "LeftFootMod"]
    index = {n: i for i, n in enumerate(sk.JOINT_NAMES)}
    pos = np.stack([walk.global_pos[:, index[layout[n]]] if n in layout else
                    walk.global_pos[:, index["left_wrist"]] + [0.0, 0.08, 0.0]
                    for n in names], axis=1)  # fmt: skip
    array, names_file = tmp_path / "take.npy", tmp_path / "names.txt"
    np.save(array, pos.astype(np.float32))
    names_file.write_text("# a capture's joints\n" + "\n".join(f"mixamorig:{n}" for n in names))
    clip = load_positions(array, joints=read_joint_names(names_file), fps=walk.fps)
    assert clip.meta["layout"] == "mixamo (two-joint spine)" and clip.num_frames == walk.num_frames
    mapped = [index[c] for c, v in MIXAMO_SHORT_SPINE.items() if isinstance(v, str)]
    shift = np.array([0.0, 0.0, clip.meta["floor_shift"]])
    err = np.linalg.norm(clip.global_pos[:, mapped] - (walk.global_pos[:, mapped] + shift), axis=-1)
    assert err.max() < 0.01


def test_what_a_position_file_lacks_is_named(tmp_path) -> None:
    walk = CLIPS[1]
    bare = tmp_path / "bare.npy"
    np.save(bare, walk.global_pos[:10])
    with pytest.raises(MotionError, match="needs its joint names and frame rate") as info:
        load_positions(bare)
    assert "bare.npy" in str(info.value) and "--joints" in (info.value.hint or "")
    with pytest.raises(MotionError, match="needs its frame rate"):
        load_positions(bare, joints=list(sk.JOINT_NAMES))
    with pytest.raises(MotionError, match="21 joint names for 22 joints"):
        load_positions(bare, joints=list(sk.JOINT_NAMES[:-1]), fps=30)
    odd = [n.replace("left_wrist", "LWristX") for n in sk.JOINT_NAMES]
    with pytest.raises(MotionError, match="left_wrist") as info:
        load_positions(bare, joints=odd, fps=30)
    assert "LWristX" in str(info.value) and "name map" in (info.value.hint or "")
    # a user name map fixes it, laid over the closest known layout
    clip = load_positions(bare, joints=odd, fps=30, name_map={"left_wrist": "LWristX"})
    assert clip.meta["layout"].startswith("custom")
    broken = walk.global_pos[:10].copy()
    broken[4, 3] = np.nan
    np.save(bare, broken)
    with pytest.raises(MotionError, match="frame 4: joint 'left_ankle' is not finite"):
        load_positions(bare, joints=list(sk.JOINT_NAMES), fps=30)
    with pytest.raises(MotionError, match="floats"):
        np.save(bare, np.zeros((5, 22), dtype=np.float32))
        load_positions(bare, joints=list(sk.JOINT_NAMES), fps=30)


@pytest.mark.parametrize("joints", [52, 55, 24], ids=["smplh", "smplx", "smpl"])
def test_amass_rotations_in_give_the_same_canonical_pose_out(joints, tmp_path) -> None:
    walk = resample(CLIPS[1], 60.0)
    arrays = amass_arrays(walk)
    poses = np.zeros((walk.num_frames, 3 * joints))
    poses[:, :66] = arrays["poses"][:, :66]
    key = "mocap_frame_rate" if joints == 55 else "mocap_framerate"
    path = tmp_path / "take.npz"
    np.savez(path, poses=poses, trans=arrays["trans"], betas=np.zeros(10),
             gender=np.array("female"), **{key: np.array(60.0)})  # fmt: skip
    clip = load_amass(path)
    assert clip.fps == 60.0 and clip.skeleton == "smpl" and clip.meta["gender"] == "female"
    assert _angle(clip.local_rot, walk.local_rot).max() < 1e-3
    drift = clip.root_pos[:, :2] - walk.root_pos[:, :2]
    assert np.abs(drift).max() < 1e-9
    # a known rotation: SMPL's left knee bent 90 degrees about SMPL x is the canonical knee
    # bent about canonical y (SMPL x is the body's left)
    poses[:, 3 * 4 : 3 * 4 + 3] = [np.pi / 2, 0.0, 0.0]
    np.savez(path, poses=poses, trans=arrays["trans"], mocap_framerate=np.array(60.0))
    knee = load_amass(path).local_rot[:, sk.joint_index("left_knee")]
    want = rot.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.array(np.pi / 2))
    assert _angle(knee, np.broadcast_to(want, knee.shape)).max() < 1e-6
    assert SMPL_OF_CANONICAL[sk.joint_index("left_knee")] == 4 and SMPL["left_knee"] == "left_knee"


def test_amass_y_up_and_missing_keys(tmp_path) -> None:
    walk = resample(CLIPS[1], 30.0)
    arrays = amass_arrays(walk)
    z_up = tmp_path / "z.npz"
    np.savez(z_up, **arrays, mocap_framerate=np.array(30.0))
    # the same take in a Y-up world: rotate the root's global rotation and the translation
    from retarget.motion.canonicalize import up_axis_matrix

    to_y = up_axis_matrix("+y").T  # the Z-up world into the file's Y-up one
    root = rot.to_matrix(rot.from_axis_angle(
        arrays["poses"][:, :3] / np.maximum(np.linalg.norm(arrays["poses"][:, :3], axis=-1,
                                                           keepdims=True), 1e-12),
        np.linalg.norm(arrays["poses"][:, :3], axis=-1)))  # fmt: skip
    q = rot.from_matrix(to_y @ root)
    angle = 2 * np.arctan2(np.linalg.norm(q[:, 1:], axis=-1), q[:, 0])
    axis = q[:, 1:] / np.maximum(np.linalg.norm(q[:, 1:], axis=-1, keepdims=True), 1e-12)
    poses = arrays["poses"].copy()
    poses[:, :3] = axis * angle[:, None]
    from retarget.motion.import_amass import MEAN_PELVIS

    trans = (arrays["trans"] + MEAN_PELVIS) @ to_y.T - MEAN_PELVIS
    y_up = tmp_path / "y.npz"
    np.savez(y_up, poses=poses, trans=trans, mocap_framerate=np.array(30.0))
    a, b = load_amass(z_up), load_amass(y_up, up="+y")
    np.testing.assert_allclose(a.global_pos, b.global_pos, atol=1e-6)
    bad = tmp_path / "bad.npz"
    np.savez(bad, poses=poses)
    with pytest.raises(MotionError, match="no trans") as info:
        load_amass(bad)
    assert "bad.npz" in str(info.value)
    np.savez(bad, poses=poses, trans=trans)
    with pytest.raises(MotionError, match="no frame rate"):
        load_amass(bad)
    np.savez(bad, poses=poses[:, :30], trans=trans, mocap_framerate=np.array(30.0))
    with pytest.raises(MotionError, match=">= 22 joints"):
        load_amass(bad)


def test_amass_bone_lengths_from_the_users_body_model(tmp_path) -> None:
    """A body model .npz (template, shape directions, joint regressor): joints from betas."""
    rng = np.random.default_rng(0)
    rest = np.zeros((22, 3))  # a T-pose in SMPL's frame: canonical rest positions via C
    offsets = sk.rest_offsets(1.6)
    canon = np.zeros((22, 3))
    for j in range(1, 22):
        canon[j] = canon[sk.PARENTS[j]] + offsets[j]
    for j, s in enumerate(SMPL_OF_CANONICAL):
        rest[s] = C @ canon[j]
    verts = rest.copy()  # one vertex per joint, regressor = identity
    dirs = np.zeros((22, 3, 10))
    dirs[..., 0] = rest * 0.1  # beta 0 scales the body by 10 % per unit
    model = tmp_path / "model" / "neutral"
    model.mkdir(parents=True)
    np.savez(model / "model.npz", v_template=verts, shapedirs=dirs, J_regressor=np.eye(22))
    walk = resample(CLIPS[1], 30.0)
    arrays = amass_arrays(walk)
    path = tmp_path / "take.npz"
    betas = np.zeros(10)
    betas[0] = 1.0
    np.savez(path, **arrays, betas=betas, mocap_framerate=np.array(30.0))
    clip = load_amass(path, model=tmp_path / "model")
    np.testing.assert_allclose(clip.offsets, offsets * 1.1, atol=1e-9)
    assert rng is not None
    with pytest.raises(MotionError, match="body model"):
        load_amass(path, model=tmp_path / "nowhere")


def test_amass_sample_writer_reads_back(tmp_path) -> None:
    path = write_amass(CLIPS[1], tmp_path / "w.npz", seconds=1.0)
    clip = load_amass(path)
    assert clip.num_frames == 120 and clip.fps == 120.0
