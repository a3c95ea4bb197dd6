"""Reference scene contact labels: MuJoCo collision checks of the kinematic reference against
the scene, once per library frame, exposed to every step as ``ctx.ref.scene_contacts``
(when a plugin needs them)."""

from __future__ import annotations

import numpy as np
import torch

from retarget import StepNeeds
from retarget.env import EnvOptions, RetargetEnv
from retarget.env.reference import CharacterReference
from retarget.motion.procedural import default_motions
from retarget.motion.resample import resample
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.stool import Stool
from retarget.sim.world import build_world

SIT = resample(default_motions(names=("sit_stand",))[0], 30)
STILL = {"position": 0.0, "yaw": 0.0}


def _labels(position: tuple[float, float]) -> tuple[np.ndarray, list[str], np.ndarray]:
    human = Human()
    world = build_world(human, Stool(Stool.Config(position=position, randomize=STILL)))
    ref = CharacterReference(human, world.model, world.layout, [SIT])
    pelvis_z = ref.arrays["body_pos"][:, world.layout.body_names.index("pelvis"), 2].numpy()
    return ref.scene_contacts.numpy(), list(world.layout.body_groups), pelvis_z


def test_a_stool_under_the_seated_pelvis_is_labelled_only_while_seated() -> None:
    labels, groups, pelvis_z = _labels((-0.32, 0.0))  # where the clip's pelvis comes to rest
    col = {g: labels[:, groups.index(g)] for g in groups}
    seated = pelvis_z < pelvis_z.min() + 0.02  # the pelvis at its lowest: sitting
    standing = pelvis_z > pelvis_z.max() - 0.02
    assert seated.sum() > 20 and standing.sum() > 20
    assert col["pelvis"][seated].all() and not col["pelvis"][standing].any()
    assert col["left_foot"].all() and col["right_foot"].all()  # on the floor throughout
    assert not col["spine"].any() and not col["left_hand"].any() and not col["right_hand"].any()
    # the same clip with the stool 3 m away: the pelvis never touches anything
    far, _, _ = _labels((3.0, 0.0))
    assert not far[:, groups.index("pelvis")].any()


def test_env_exposes_labels_per_step_and_randomization_keeps_them() -> None:
    def env(randomize: dict | None) -> RetargetEnv:
        cfg = {"position": (-0.32, 0.0)} | ({"randomize": randomize} if randomize else {})
        made = RetargetEnv(
            Human(), [SIT], scene=Stool(Stool.Config(**cfg)), options=EnvOptions(num_envs=3)
        )
        made.gather(StepNeeds(scene_contacts=True))
        return made

    plain, noisy = env(STILL), env(None)  # default: 8 cm / 0.1 rad placement noise
    assert torch.equal(plain.reference.scene_contacts, noisy.reference.scene_contacts)
    frames = torch.tensor([10, 100, 150])
    noisy.place(torch.zeros(3, dtype=torch.long), frames)
    noisy.step(torch.zeros(3, noisy.action_dim))
    ctx = noisy.last_context
    labels = ctx.ref.scene_contacts
    assert labels.shape == (3, len(noisy.layout.body_groups)) and labels.dtype == torch.bool
    assert torch.equal(labels, noisy.reference.scene_contacts[frames + 1])
