"""The motion library: flat storage, weighted sampling, clamped windows, no per-env loops."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from retarget.motion.devices import device_poses
from retarget.motion.library import MotionLibrary, window_offsets
from retarget.motion.procedural import default_motions
from retarget.motion.resample import resample


@pytest.fixture(scope="module")
def clips():
    return default_motions()


@pytest.fixture(scope="module")
def lib(clips):
    return MotionLibrary(clips, fps=36.0, weights=[1, 2, 1, 1, 0])


def test_flat_layout(lib, clips):
    lengths = [resample(c, 36.0).num_frames for c in clips]
    assert lib.length.tolist() == lengths
    assert lib.start.tolist() == [0, *np.cumsum(lengths)[:-1].tolist()]
    assert lib.num_frames == sum(lengths)
    walk = resample(clips[1], 36.0)
    s = int(lib.start[1])
    assert torch.allclose(lib.global_pos[s:s + walk.num_frames],
                          torch.as_tensor(walk.global_pos, dtype=torch.float32), atol=1e-5)
    dev = device_poses(walk.global_pos, walk.global_rot, walk.height)
    assert torch.allclose(lib.devices[s:s + walk.num_frames],
                          torch.as_tensor(dev, dtype=torch.float32), atol=1e-5)


def test_weighted_sampling(lib):
    g = torch.Generator().manual_seed(0)
    clip, frame = lib.sample(20000, g)
    counts = torch.bincount(clip, minlength=5).double() / 20000
    assert counts[4] == 0  # zero weight is never sampled
    assert counts[1] == pytest.approx(0.4, abs=0.02)
    assert counts[0] == pytest.approx(0.2, abs=0.02)
    assert (frame >= 0).all() and (frame < lib.length[clip]).all()
    clip2, frame2 = lib.sample(5000, g, margin=36)
    assert (frame2 < lib.length[clip2] - 36).all()


def test_window_matches_direct_lookup_and_clamps(lib):
    off = window_offsets(1.0, 36.0, future=0.25)
    assert off[0] == -36 and off[-1] == 9 and 0 in off
    clip = torch.tensor([0, 1, 1, 3])
    frame = torch.tensor([0, 5, int(lib.length[1]) - 1, 100])
    w = lib.window(clip, frame, off)
    assert w.devices.shape == (4, len(off), 3, 7)
    assert w.global_pos.shape == (4, len(off), 22, 3)
    for n in range(4):  # reference loop in the test only
        c, f = int(clip[n]), int(frame[n])
        for k, o in enumerate(off):
            row = int(lib.start[c]) + min(max(f + o, 0), int(lib.length[c]) - 1)
            assert torch.equal(w.global_pos[n, k], lib.global_pos[row])
            assert torch.equal(w.contacts[n, k], lib.contacts[row])
    only = lib.window(clip, frame, off, fields=("devices",))
    assert torch.equal(only.devices, w.devices) and only.global_pos.numel() == 0


def test_advance_flags_clip_end(lib):
    clip = torch.tensor([0, 0])
    frame = torch.stack([lib.length[0] - 2, torch.tensor(0)])
    nxt, done = lib.advance(clip, frame, 1)
    assert done.tolist() == [False, False]
    nxt, done = lib.advance(clip, nxt, 1)
    assert done.tolist() == [True, False] and nxt[0] == lib.length[0] - 1


def test_mirrored_library_doubles_clips(clips):
    lib = MotionLibrary(clips[:2], mirrored=True)
    assert lib.num_clips == 4 and lib.names[2].endswith("_mirrored")
    a, b = int(lib.start[1]), int(lib.start[3])
    assert torch.allclose(lib.root_pos[a:a + 10, 1], -lib.root_pos[b:b + 10, 1])


def test_bad_weights(clips):
    with pytest.raises(ValueError):
        MotionLibrary(clips[:2], weights=[0, 0])
    with pytest.raises(ValueError):
        MotionLibrary([])


def test_devices_at_the_characters_scale_stay_on_its_reference() -> None:
    """A walk by a person 0.9 times the character's size: with ``env.devices: character`` the
    headset keeps one distance from the reference's head site all the way (the mount offset);
    at the person's size it falls behind with every metre walked."""
    from plugins.characters.human import Human
    from retarget.character.kinematic import scaled_clip
    from retarget.env.env import RetargetEnv
    from retarget.motion.procedural import default_motions
    from retarget.settings.env import EnvOptions

    walk = scaled_clip(default_motions(names=("walk",))[0], 0.9)
    assert walk.meta["scale"] == 0.9
    gap, body = {}, {}
    for mode in ("person", "character"):
        env = RetargetEnv(Human(), [walk], options=EnvOptions(num_envs=1, devices=mode))
        head = env.reference.arrays["site_pos"][:, env.layout.site("head")]
        gap[mode] = (head - env.library.devices[:, 0, :3]).norm(dim=-1)
        pelvis = env.reference.arrays["body_pos"][:, 0]  # the person's body goes with them
        body[mode] = (pelvis - env.library.global_pos[:, 0]).norm(dim=-1)
        if mode == "character":  # scalings compose: 0.9 and back up to the character's size
            assert float(env.library.heights[0]) == pytest.approx(1.75, abs=0.05)
    assert float(gap["character"].max() - gap["character"].min()) < 0.01
    assert float(gap["character"].max()) < 0.08 and float(body["character"].max()) < 0.01
    assert float(gap["person"][-1]) > float(gap["person"][0]) + 0.4  # ~8 m walked x 0.1
    assert float(body["person"][-1]) > 0.4
