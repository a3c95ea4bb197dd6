"""Feet levelled where they are planted (``retarget.motion.level_feet``): a capture whose toe
joint sits lower than the canonical skeleton's gives a tilted foot frame; levelling turns the
frame, never a joint position."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.bvh_write import write_bvh
from retarget.motion.level_feet import level_feet, mirrored, planted
from retarget.motion.procedural import default_motions
from retarget.motion.sources import read_clip
from retarget.registry.loader import load_plugins


def _pitch_deg(clip, side: int = 0) -> np.ndarray:
    """Angle of the foot frame's forward axis above the ground, per frame (toes down < 0)."""
    m = rot.to_matrix(clip.global_rot[:, sk.FEET[side]])
    return np.degrees(np.arcsin(np.clip(m[:, 2, 0], -1.0, 1.0)))


@pytest.fixture(scope="module")
def walk():
    return next(c for c in default_motions() if c.name == "walk")


@pytest.fixture(scope="module")
def low_toes(walk, tmp_path_factory) -> object:
    """The generated walk written with its toe joints 19 degrees lower (as Bandai Namco's
    skeleton has them) and read back: the reader builds the foot frame along the bone."""
    offsets = walk.offsets.copy()
    down = rot.from_axis_angle(np.array([0.0, 1.0, 0.0]), np.deg2rad(19.0))
    for toe in sk.TOES:
        offsets[toe] = rot.apply(down, offsets[toe])
    path = tmp_path_factory.mktemp("low_toes") / "walk.bvh"
    write_bvh(walk.with_(offsets=offsets), path)
    return read_clip(path, formats=load_plugins().motion_formats())


def test_a_low_toe_joint_tilts_the_foot_and_levelling_turns_it_back(low_toes) -> None:
    stance = planted(low_toes, 0)
    assert stance.sum() > 20
    assert np.median(_pitch_deg(low_toes)[stance]) == pytest.approx(-19.0, abs=1.5)
    flat = level_feet(low_toes)
    assert np.abs(_pitch_deg(flat)[stance]).max() < 1.5
    assert np.abs(_pitch_deg(flat, 1)[planted(flat, 1)]).max() < 1.5
    assert flat.meta["foot_tilt_deg"][0] == pytest.approx(19.0, abs=1.5)


def test_levelling_moves_no_joint_against_another_and_grounds_the_ankles(low_toes) -> None:
    flat = level_feet(low_toes)
    shift = flat.root_pos - low_toes.root_pos
    assert np.allclose(shift[:, :2], 0.0) and np.ptp(shift[:, 2]) < 1e-12
    np.testing.assert_allclose(flat.global_pos, low_toes.global_pos + shift[:1], atol=1e-9)
    # the written walk's floor sat at its lowered toe tips: its planted ankles stood high
    assert shift[0, 2] < -0.01
    down = planted(flat, 0)
    ankle = np.median(flat.global_pos[down, sk.FEET[0], 2])
    assert ankle == pytest.approx(sk.ANKLE_HEIGHT_175 * flat.height / sk.REFERENCE_HEIGHT, abs=3e-3)
    others = [j for j in range(sk.NUM_JOINTS) if j not in (*sk.FEET, *sk.TOES)]
    np.testing.assert_array_equal(flat.local_rot[:, others], low_toes.local_rot[:, others])


def test_level_feet_are_left_exactly_as_they_are(walk) -> None:
    assert level_feet(walk) is walk


def test_a_clip_never_planted_is_left_alone(walk) -> None:
    up = walk.slice(0, 120)
    lift = np.linspace(0.0, 2.0, 120)[:, None] * np.array([0.0, 0.0, 1.0])
    rising = up.with_(root_pos=up.root_pos + lift, contacts=np.zeros((120, 2), dtype=bool))
    assert planted(rising, 0).sum() < 5 and planted(rising, 1).sum() < 5
    assert level_feet(rising) is rising


def test_mirroring_a_correction_twice_is_the_correction() -> None:
    q = rot.normalize(np.array([0.9, 0.1, 0.3, -0.2]))
    np.testing.assert_allclose(mirrored(mirrored(q)), q)
    # a pitch (about y) is the same on both feet; a roll (about x) flips its sign
    pitch = rot.from_axis_angle(np.array([0.0, 1.0, 0.0]), 0.3)
    np.testing.assert_allclose(mirrored(pitch), pitch)
    roll = rot.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.3)
    np.testing.assert_allclose(mirrored(roll), rot.conj(roll))


def test_real_captures_are_levelled(mocap_dir: Path) -> None:
    """Bandai Namco's toe joints sit far below its ankles: its feet come out pitched
    toes-down by well over 10 degrees, and flat after levelling."""
    registry = load_plugins()
    files = sorted(mocap_dir.glob("bandai_*walk*.bvh"))
    if not files:
        pytest.skip(f"no Bandai Namco walk among the shared clips in {mocap_dir}")
    clip = read_clip(files[0], formats=registry.motion_formats())
    down = planted(clip, 0)  # a take cut mid-stride: one foot down at a time
    assert down.sum() >= 5
    assert np.median(_pitch_deg(clip)[down]) < -10.0
    flat = level_feet(clip)
    assert abs(np.median(_pitch_deg(flat)[down])) < 3.0
    shift = flat.root_pos[0] - clip.root_pos[0]
    np.testing.assert_allclose(flat.global_pos, clip.global_pos + shift, atol=1e-9)
    assert -0.08 < shift[2] < -0.02  # its ankle joints stand 4-5 cm above a level sole's


@pytest.mark.parametrize("level", [True, False])
def test_an_env_references_level_feet_unless_the_recipe_says_not(low_toes, tmp_path, level) -> None:
    """``motions.level_feet`` (default on) decides what the policy's reference feet do."""
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load

    write_bvh(low_toes, tmp_path / "walk.bvh")
    registry = load_plugins()
    sets = [f"motions.path={tmp_path}", f"motions.level_feet={level}"]
    resolved = load(None, registry, shorthands={"sensors": "three_point"}, assignments=sets)
    env = env_from_recipe(resolved, num_envs=1, threads=1, registry=registry)
    m = rot.to_matrix(env.library.global_rot[:, sk.FEET[0]].double().numpy())
    pitch = np.degrees(np.arcsin(np.clip(m[:, 2, 0], -1.0, 1.0)))
    assert bool(abs(np.median(pitch)) < 3.0) == level, np.median(pitch)
