"""Device calibration noise: per-episode heights of the devices, in training only."""

from __future__ import annotations

import pytest
import torch

from retarget.env.build import env_from_recipe
from retarget.env.device_noise import DeviceNoise
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.settings.env import DeviceNoiseOptions

REGISTRY = load_plugins(strict=True)
NOISE = "env.device_noise={height: 0.05, scale: 0.03}"


def _env(num_envs: int, *sets: str):
    resolved = load(None, REGISTRY, shorthands={"sensors": "three_point"}, assignments=list(sets))
    return env_from_recipe(resolved, num_envs=num_envs, threads=1)


def test_draws_stay_in_range_and_differ_between_episodes() -> None:
    noise = DeviceNoise(DeviceNoiseOptions(height=0.05, scale=0.03), num_envs=4000, seed=0)
    assert noise.offset.abs().max() <= 0.05 and noise.offset.abs().max() > 0.045
    assert (noise.scale - 1).abs().max() <= 0.03 and noise.offset.std() > 0.02
    before = noise.offset.clone()
    noise.redraw(torch.tensor([0, 1]))
    assert not torch.equal(noise.offset[:2], before[:2])
    assert torch.equal(noise.offset[2:], before[2:])  # other episodes keep theirs


def test_heights_move_only_while_active() -> None:
    noise = DeviceNoise(DeviceNoiseOptions(height=0.05, scale=0.0), num_envs=3, seed=1)
    devices = torch.rand(3, 2, 3, 7, dtype=torch.float64)
    assert noise.apply(devices) is devices  # inactive: evaluation, play, live
    noise.active = True
    moved = noise.apply(devices)
    assert torch.equal(moved[..., :2], devices[..., :2]) and torch.equal(moved[..., 3:],
                                                                        devices[..., 3:])
    shift = moved[..., 2] - devices[..., 2]
    # one offset per episode, the same for every device and frame of its window
    assert torch.allclose(shift, noise.offset.double()[:, None, None].expand_as(shift))


def test_state_round_trips_and_a_wrong_batch_is_refused() -> None:
    options = DeviceNoiseOptions()
    noise = DeviceNoise(options, num_envs=5, seed=2)
    again = DeviceNoise(options, num_envs=5, seed=9)
    again.load_state_dict(noise.state_dict())
    noise.redraw(torch.arange(5))
    again.redraw(torch.arange(5))
    assert torch.equal(noise.offset, again.offset) and torch.equal(noise.scale, again.scale)
    with pytest.raises(ValueError, match="5 environments, this env 3"):
        DeviceNoise(options, num_envs=3, seed=0).load_state_dict(noise.state_dict())


def test_the_env_moves_the_students_devices_only_in_training() -> None:
    plain, noisy = _env(8), _env(8, NOISE)
    exact = plain.reset()["actor"]
    torch.testing.assert_close(exact, noisy.reset()["actor"])  # inactive: the same starts
    noisy.device_noise.active = True
    obs = noisy.observe(noisy._context(torch.zeros(8, noisy.action_dim)))["actor"]
    # three_point, past 1: per frame headset xyz + 6D, so column 2 is the headset's height
    dz = obs[:, 2] - exact[:, 2]
    assert dz.abs().max() > 0.01  # up to 5 cm and 3% of 1.6 m
    noise = noisy.device_noise
    torch.testing.assert_close(dz, noise.offset + (noise.scale - 1) * exact[:, 2])
    torch.testing.assert_close(obs[:, 3:9], exact[:, 3:9])  # rotations untouched


def test_training_turns_it_on_and_leaves_it_off(tmp_path) -> None:
    from retarget.train.run_dir import new_run_dir
    from retarget.train.runner import Budget, Trainer

    resolved = load(None, REGISTRY, shorthands={"sensors": "three_point"},
                    assignments=[NOISE, "env.num_envs=4", "algorithm.rollout_steps=8",
                                 "algorithm.minibatch_size=16", "algorithm.epochs=1"])  # fmt: skip
    trainer = Trainer(resolved, new_run_dir(tmp_path, "noise"), threads=1, tensorboard=False)
    seen: list[bool] = []
    trainer.train(Budget(steps=64), on_iteration=lambda p: seen.append(
        trainer.env.device_noise.active))
    assert seen and all(seen)
    assert trainer.env.device_noise.active is False


def _poses_by_frame(frames: torch.Tensor) -> torch.Tensor:
    """``(N, 3, 7)`` devices whose every number is the frame they belong to."""
    return frames.double()[:, None, None].expand(-1, 3, 7).clone()


def test_lost_controllers_are_held_at_the_frame_they_were_lost() -> None:
    options = DeviceNoiseOptions(height=0.0, scale=0.0, lost=10.0, lost_seconds=1.0)
    noise = DeviceNoise(options, num_envs=64, seed=3, control_dt=1.0 / 30.0)
    window = (-2, -1, 0)
    frame = torch.full((64,), 10)
    devices = torch.stack([_poses_by_frame(frame + w) for w in window], dim=1)  # (N, W, D, 7)
    flags = torch.ones(devices.shape[:-1], dtype=torch.bool)
    assert noise.hold(devices, flags, frame, window, _poses_by_frame)[0] is devices  # inactive
    noise.active = True
    seen_lost = 0
    for step in range(30):
        frame = torch.full((64,), 10 + step)
        devices = torch.stack([_poses_by_frame(frame + w) for w in window], dim=1)
        held, tracked = noise.hold(devices, flags, frame, window, _poses_by_frame)
        assert torch.equal(held[:, :, 0], devices[:, :, 0])  # the headset is never lost
        assert tracked[:, :, 0].all()
        for j, d in enumerate(DeviceNoise.CONTROLLERS):
            lost = noise.lost_from[:, j]
            for w_i, w in enumerate(window):
                entry = frame + w
                expect = torch.where((lost >= 0) & (entry >= lost), lost, entry).double()
                assert torch.equal(held[:, w_i, d, 0], expect)
                assert torch.equal(~tracked[:, w_i, d], (lost >= 0) & (entry >= lost))
            seen_lost += int((lost >= 0).sum())
    assert seen_lost > 0
    # the same frame read twice (a step with resets) draws no new loss
    before = noise.lost_from.clone()
    for _ in range(5):  # at a third of a chance per step, five fresh frames would start some
        noise.hold(devices, flags, frame, window, _poses_by_frame)
    assert torch.equal(noise.lost_from, before)
    # a loss ends: past its last frame the controller follows again
    later = torch.full((64,), 10 + 30 + 31)
    noise.options = DeviceNoiseOptions(height=0.0, scale=0.0, lost=1e-9)
    out, _ = noise.hold(_poses_by_frame(later)[:, None], flags[:, :1], later, (0,),
                        _poses_by_frame)
    assert torch.equal(out[:, 0, :, 0], later.double()[:, None].expand(-1, 3))


def test_lost_state_round_trips_and_old_states_load() -> None:
    options = DeviceNoiseOptions(lost=10.0)
    noise = DeviceNoise(options, num_envs=8, seed=4)
    noise.active = True
    frame = torch.full((8,), 5)
    for _ in range(5):
        noise.hold(_poses_by_frame(frame)[:, None], torch.ones(8, 1, 3, dtype=torch.bool), frame,
                   (0,), _poses_by_frame)
    assert (noise.lost_from >= 0).any()
    again = DeviceNoise(options, num_envs=8, seed=0)
    again.load_state_dict(noise.state_dict())
    assert torch.equal(again.lost_from, noise.lost_from)
    assert torch.equal(again.lost_to, noise.lost_to)
    old = {k: v for k, v in noise.state_dict().items() if not k.startswith("lost")}
    DeviceNoise(options, num_envs=8, seed=0).load_state_dict(old)  # saved before: no losses
    noise.redraw(torch.arange(8))
    assert (noise.lost_from == -1).all()  # a new episode starts tracked


def _losing_env():
    """16 environments in training whose controllers are lost often (10 per second)."""
    env = _env(16, "env.device_noise={height: 0.0, scale: 0.0, lost: 10.0, lost_seconds: 2.0}")
    env.reset()
    env.device_noise.active = True
    return env


def test_the_env_holds_a_lost_controller_in_training() -> None:
    env = _losing_env()
    for _ in range(12):
        ctx = env._context(torch.zeros(16, env.action_dim))
        env.frame = env.frame + 1
    lost = env.device_noise.lost_from[:, 0]
    assert (lost >= 0).any()
    n = int(torch.nonzero(lost >= 0)[0, 0])
    lib = env.library
    held = lib.devices[lib.rows(env.clip[n : n + 1], lost[n : n + 1])[:, 0]][0, 1]
    torch.testing.assert_close(ctx.ref.devices[n, -1, 1], held.to(ctx.ref.devices.dtype))


def test_a_held_controller_is_reported_untracked_while_it_is_held() -> None:
    env = _losing_env()
    for _ in range(12):
        ctx = env._context(torch.zeros(16, env.action_dim))
        tracked, lost = ctx.ref.devices_tracked, env.device_noise.lost_from
        assert tracked is not None and tracked[..., 0].all()  # the headset is never lost
        for j, d in enumerate(DeviceNoise.CONTROLLERS):  # the current entry: lost now or not
            assert torch.equal(~tracked[:, -1, d], lost[:, j] >= 0)
        env.frame = env.frame + 1
    assert not tracked.all()
    env.device_noise.active = False  # evaluation: every device tracked
    assert env._context(torch.zeros(16, env.action_dim)).ref.devices_tracked.all()
