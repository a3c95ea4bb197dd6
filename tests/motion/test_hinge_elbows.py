"""Elbows as hinges (``env.hinge_elbows``): the same body with its arm rotations split so a
hinged elbow can follow, and a character's hands where the person's controllers are."""

from __future__ import annotations

import numpy as np
import torch

from retarget.character.kinematic import root_height_ratio, scaled_clip
from retarget.env.reference import CharacterReference
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.devices import device_poses
from retarget.motion.hinge_elbows import ARMS, FULL_TWIST_BEND, hinge_elbows, hinge_split
from retarget.plugins.characters.human import Human
from retarget.sim.world import build_world

LEFT = ARMS[0]


def _bend(elbow: np.ndarray, bone: np.ndarray) -> np.ndarray:
    forearm = rot.apply(elbow, np.broadcast_to(bone, (*elbow.shape[:-1], 3)))
    return np.arccos(np.clip(forearm @ bone, -1.0, 1.0))


def test_the_arm_keeps_its_pose_and_the_elbow_becomes_a_hinge() -> None:
    rng = np.random.default_rng(0)
    q = rot.normalize(rng.normal(size=(2000, 3, 4)))
    bone, flex = (np.asarray(v, dtype=float) for v in LEFT[1:])
    s, e, w = hinge_split(q[:, 0], q[:, 1], q[:, 2], bone, flex)
    b = np.broadcast_to(bone, (len(q), 3))
    # the elbow turns about the flexion axis only
    axis_part = rot.apply(e, np.broadcast_to(flex, (len(q), 3)))
    assert np.allclose(axis_part, flex, atol=1e-9)
    # the upper arm points where it did, the hand turns as it did
    assert np.allclose(rot.apply(s, b), rot.apply(q[:, 0], b), atol=1e-9)
    before = rot.mul(rot.mul(q[:, 0], q[:, 1]), q[:, 2])
    after = rot.mul(rot.mul(s, e), w)
    assert np.allclose(np.abs((before * after).sum(-1)), 1.0, atol=1e-9)
    # the forearm too, wherever the elbow bends enough for its plane to mean something
    bent = _bend(q[:, 1], bone) >= FULL_TWIST_BEND
    assert bent.sum() > 1000
    fore_before = rot.apply(rot.mul(q[:, 0], q[:, 1]), b)
    fore_after = rot.apply(rot.mul(s, e), b)
    assert np.allclose(fore_before[bent], fore_after[bent], atol=1e-9)
    assert np.linalg.norm(fore_before - fore_after, axis=-1).max() < 2 * np.sin(FULL_TWIST_BEND)


def test_a_hyperextended_or_straight_elbow_does_not_turn_the_upper_arm() -> None:
    """A forearm bent 10 degrees backwards is a negative hinge angle, not half a turn of the
    upper arm; a straight arm bent 2 degrees sideways keeps its twist where it was."""
    bone, flex = (np.asarray(v, dtype=float) for v in LEFT[1:])
    back = rot.from_axis_angle(flex, np.array(-0.6))  # 34 degrees the wrong way
    side = rot.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.array(0.035))
    for elbow in (back, side):
        s, e, _ = hinge_split(rot.identity(), elbow, rot.identity(), bone, flex)
        assert rot.angle(s) < 0.05  # no turn of the upper arm about itself
    _, e, _ = hinge_split(rot.identity(), back, rot.identity(), bone, flex)
    assert np.allclose(e, back, atol=1e-9)  # already a hinge (a negative angle): unchanged


def test_a_real_clip_keeps_its_global_pose(real_clips) -> None:
    clip = real_clips["bandai_d2_wave-both-hands_normal_012.bvh"]
    hinged = hinge_elbows(clip)
    assert not np.allclose(hinged.local_rot, clip.local_rot)  # the file's elbows were not hinges
    gap = np.linalg.norm(hinged.global_pos - clip.global_pos, axis=-1)
    assert gap.max() < 0.03  # metres: only nearly straight arms move, and a little
    assert np.median(gap) < 1e-6
    turn = rot.angle(rot.mul(rot.conj(hinged.global_rot), clip.global_rot))
    arms = [sk.joint_index(f"{side}_{j}") for side in ("left", "right")
            for j in ("shoulder", "elbow")]  # fmt: skip
    kept = np.setdiff1d(np.arange(turn.shape[1]), arms)
    assert turn[:, kept].max() < 1e-6  # every other joint, the hands included, turns as it did
    assert turn[:, arms].max() > 0.5  # the upper arms took the elbows' twist


def _hands_to_controllers(clip, hinge: bool) -> float:
    human = Human()
    world = build_world(human)
    clip = scaled_clip(clip, root_height_ratio(world.model, clip))  # devices at its size
    ref = CharacterReference(human, world.model, world.layout, [clip], hinge=hinge)
    hands = [world.layout.site("left_hand"), world.layout.site("right_hand")]
    rows = torch.arange(clip.num_frames)
    held = ref.pose(rows).site_pos[:, hands].double().numpy()
    controllers = device_poses(clip.global_pos, clip.global_rot, clip.height)[:, 1:3, :3]
    return float(np.linalg.norm(held - controllers, axis=-1).mean())


def test_a_human_holds_its_hands_nearer_the_persons_controllers(real_clips) -> None:
    """A run and an arm wave retargeted onto the human: with the elbow's bend alone the hands
    land a forearm's swing away from the controllers the performer held; hinged, they follow."""
    for name in ("bandai_d2_run_normal_040.bvh", "bandai_d2_wave-both-hands_normal_012.bvh"):
        clip = real_clips[name]
        bent_only, hinged = _hands_to_controllers(clip, False), _hands_to_controllers(clip, True)
        assert hinged < 0.12, (name, hinged)
        assert hinged < 0.7 * bent_only, (name, hinged, bent_only)
