"""Stance feet put on the floor (``retarget.character.grounding``, ``env.ground_feet``)."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.character import kinematic as km
from retarget.character.grounding import ground_feet, stance_heights
from retarget.errors import PluginError
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.human import Human


def _feet(model, character) -> list[list[int]]:
    import mujoco

    groups = character.body_groups()
    return [
        [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in groups[side]]
        for side in ("left_foot", "right_foot")
    ]


def _walk_on(character):
    model = character.build_spec().compile()
    clip = default_motions(names=("walk",))[0]
    motion = km.retarget_clip(clip, model, character.joint_map())
    return model, clip, motion


def _stance_heights(model, qpos, contacts, feet) -> np.ndarray:
    """The lowest point of the feet the performer has down, in frames with one down."""
    stance = stance_heights(model, qpos, contacts, feet)
    return stance[np.isfinite(stance)]


def test_the_dinos_stance_feet_come_down_onto_the_floor() -> None:
    dino = Dino()
    model, clip, motion = _walk_on(dino)
    feet = _feet(model, dino)
    before = _stance_heights(model, motion.qpos, clip.contacts, feet)
    assert np.median(before) > 0.03  # rough retargeting leaves its stance feet in the air
    qpos = ground_feet(model, motion.qpos, clip.contacts, feet, clip.fps)
    after = _stance_heights(model, qpos, clip.contacts, feet)
    assert abs(np.median(after)) < 0.01
    assert np.abs(after).mean() < 0.4 * np.abs(before).mean()
    # only the root's height moves, and smoothly: no jump where the stance foot changes
    np.testing.assert_array_equal(qpos[:, [0, 1]], motion.qpos[:, [0, 1]])
    np.testing.assert_array_equal(qpos[:, 3:], motion.qpos[:, 3:])
    shift = qpos[:, 2] - motion.qpos[:, 2]
    assert np.abs(np.diff(shift)).max() < 0.01  # metres per frame


def test_a_clip_with_no_foot_down_is_left_as_it_is() -> None:
    dino = Dino()
    model, clip, motion = _walk_on(dino)
    none = np.zeros_like(clip.contacts, dtype=bool)
    out = ground_feet(model, motion.qpos, none, _feet(model, dino), clip.fps)
    np.testing.assert_array_equal(out, motion.qpos)


def test_contact_labels_that_do_not_fit_the_clip_are_refused() -> None:
    dino = Dino()
    model, clip, motion = _walk_on(dino)
    with pytest.raises(ValueError, match="contact labels of shape"):
        ground_feet(model, motion.qpos, clip.contacts[:-1], _feet(model, dino), clip.fps)


def test_the_human_barely_moves() -> None:
    """A human's retargeted feet are already on the floor to a couple of centimetres."""
    human = Human()
    model, clip, motion = _walk_on(human)
    qpos = ground_feet(model, motion.qpos, clip.contacts, _feet(model, human), clip.fps)
    assert np.abs(qpos[:, 2] - motion.qpos[:, 2]).max() < 0.03


def test_the_env_option_grounds_the_reference_and_keys_its_cache_apart() -> None:
    from retarget.env import EnvOptions, RetargetEnv
    from retarget.env.reference_cache import reference_key
    from retarget.sim import SimSettings

    dino, one = Dino(), SimSettings(threads=1)
    clips = default_motions(names=("walk",))
    envs = {
        on: RetargetEnv(Dino(), clips, options=EnvOptions(num_envs=1, ground_feet=on), sim=one)
        for on in (False, True)
    }
    lib = envs[True].library
    feet = _feet(envs[True].world.model, dino)
    heights = {
        on: _stance_heights(env.world.model, env.reference.qpos64, lib.contacts.numpy(), feet)
        for on, env in envs.items()
    }
    assert np.median(heights[False]) > 0.03 and abs(np.median(heights[True])) < 0.01
    # the idle pose live sessions start in stands on the floor too
    idle = {on: env.idle_qpos(lib.fps)[2] for on, env in envs.items()}
    assert idle[True] < idle[False] - 0.01
    model = envs[True].world.model
    plain = reference_key(model, dino.joint_map(), clips, 0.02, None)
    grounded = reference_key(model, dino.joint_map(), clips, 0.02, None, ground=True)
    assert plain is None or plain != grounded


def test_a_character_without_feet_groups_is_named() -> None:
    from types import SimpleNamespace

    from retarget.env.reference import foot_bodies

    layout = SimpleNamespace(body_groups={"feet": (1, 2)}, body_ids=(0, 1, 2))
    with pytest.raises(PluginError, match=r"character blob.*left_foot or right_foot"):
        foot_bodies(layout, "blob")
