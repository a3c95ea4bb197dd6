"""Test doubles for the contract suite's own tests: one well-behaved plugin per kind.

Kinds without a real implementation yet are exercised through these; each broken variant in
``test_contract_suite.py`` breaks exactly one rule.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

import retarget
from retarget import MotionError
from retarget.motion.clip import MotionClip
from retarget.motion.skeleton import NUM_JOINTS, rest_offsets
from retarget.testing.fakes import FlatScene, TinyCharacter


class GoodReward(retarget.RewardTerm):
    """Rewards a head close to the reference head."""

    name = "good_reward"

    def bind(self, layout: retarget.Layout) -> None:
        self.head = layout.site("head")

    def compute(self, ctx: retarget.StepContext) -> torch.Tensor:
        d = (ctx.sim.site_pos[:, self.head] - ctx.ref.pose.site_pos[:, self.head]).norm(dim=-1)
        return retarget.gaussian_kernel(d, 2.0).float()


class GoodTermination(retarget.Termination):
    """Ends episodes whose head drops below 0.3 m."""

    name = "good_termination"

    def bind(self, layout: retarget.Layout) -> None:
        self.head = layout.site("head")

    def check(self, ctx: retarget.StepContext) -> torch.Tensor:
        return ctx.sim.site_pos[:, self.head, 2] < 0.3


class GoodSensor(retarget.Sensor):
    """The headset window relative to the current headset position."""

    name = "good_sensor"

    def spec(self, layout: retarget.Layout) -> retarget.ObsSpec:
        return retarget.ObsSpec((5, 3))

    def frames_needed(self) -> tuple[int, int]:
        return (2, 2)

    def observe(self, ctx: retarget.StepContext) -> torch.Tensor:
        hmd = ctx.ref.devices[:, :, 0, :3]
        now = ctx.ref.window_offsets.index(0)
        return (hmd - hmd[:, now : now + 1]).float()


class GoodObserver(retarget.Observer):
    """Floor height at four points around the root."""

    name = "good_observer"

    def spec(self, layout: retarget.Layout) -> retarget.ObsSpec:
        return retarget.ObsSpec((4,))

    def observe(self, ctx: retarget.StepContext) -> torch.Tensor:
        offsets = torch.tensor([[0.3, 0.0], [-0.3, 0.0], [0.0, 0.3], [0.0, -0.3]])
        xy = ctx.sim.qpos[:, None, :2] + offsets
        return ctx.scene.height_at(xy)


class GoodScene(FlatScene):
    """A flat floor (the test double of scenes)."""

    name = "good_scene"


class GoodCharacter(TinyCharacter):
    """The tiny test character."""

    name = "good_character"


class GoodAlgorithm(retarget.Algorithm):
    """A linear policy fitted by one gradient step per iteration (the test double)."""

    name = "good_algorithm"

    def setup(self, env: retarget.VecEnv, generator: torch.Generator | None = None) -> None:
        g = generator or torch.Generator().manual_seed(0)
        self.weight = torch.randn(env.obs_dims["actor"], env.action_dim, generator=g) * 0.1
        self.iterations = 0

    def train_iteration(self, env: retarget.VecEnv) -> dict[str, float]:
        obs = env.reset()
        weight = self.weight.clone().requires_grad_(True)
        action = obs["actor"] @ weight
        _, reward, *_ = env.step(action.detach())
        loss = (
            -(reward * -(action - action.detach()).square().sum(-1)).mean() + weight.square().sum()
        )
        loss.backward()
        self.weight = (weight - 0.01 * weight.grad).detach()
        self.iterations += 1
        return {"loss": float(loss.detach()), "reward": float(reward.mean())}

    def act(self, obs):
        return obs["actor"] @ self.weight

    def state_dict(self) -> dict:
        return {"weight": self.weight.clone(), "iterations": self.iterations}

    def load_state_dict(self, state) -> None:
        self.weight = state["weight"].clone()
        self.iterations = state["iterations"]


class GoodFormat(retarget.MotionFormat):
    """Root trajectories as text: a line 'fps F' then one 'x y z' line per frame."""

    name = "good_format"
    suffixes = (".root",)

    def read(self, path: Path) -> MotionClip:
        lines = path.read_bytes().decode("utf-8", errors="replace").splitlines()
        if not lines or not lines[0].startswith("fps "):
            raise MotionError("expected 'fps F' on the first line", file=path, line=1)
        try:
            fps = float(lines[0].split()[1])
            root = np.array([[float(v) for v in line.split()] for line in lines[1:]])
        except (ValueError, IndexError) as exc:
            raise MotionError(f"bad number: {exc}", file=path) from None
        rot = np.zeros((len(root), NUM_JOINTS, 4))
        rot[..., 0] = 1.0
        return MotionClip(fps=fps, root_pos=root, local_rot=rot, offsets=rest_offsets())

    @classmethod
    def write_sample(cls, directory: Path) -> Path:
        path = directory / "sample.root"
        path.write_text("fps 30\n" + "\n".join(f"{0.01 * i} 0 0.9" for i in range(10)) + "\n")
        return path


class GoodCommand(retarget.Command):
    """Prints the number of installed plugins."""

    name = "good_command"

    def run(self, args) -> int:
        return 0


class GoodCallback(retarget.Callback):
    """Counts the iterations it is told of."""

    name = "good_callback"

    def on_iteration(self, iteration, env_steps, stats) -> None:
        self.seen = getattr(self, "seen", 0) + 1


class GoodPlanner(retarget.Planner):
    """Steps the reference's joint angles as PD targets, open loop."""

    name = "good_planner"

    def perturb(self, targets: np.ndarray) -> np.ndarray:
        """The actions stepped."""
        return targets

    def report(self, stepped: np.ndarray) -> np.ndarray:
        """The actions returned."""
        return stepped

    def track(self, env, clip, *, seconds=None, threads=1, progress=None):
        from retarget import Track

        sim, lay, ref = env.sim, env.layout, env.reference
        fps = 1.0 / sim.settings.control_dt
        start, length = int(env.library.start[clip]), int(env.library.length[clip])
        if seconds is not None:
            length = max(2, min(length, round(seconds * fps) + 1))
        env.place(torch.tensor([clip]), torch.tensor([0]))
        ranges = np.asarray(lay.actuator_ranges, dtype=np.float64).reshape(-1, 2)
        scale = np.abs(ranges).max(axis=1)
        rows = start + np.arange(1, length)
        targets = ref.qpos64[rows][:, np.asarray(lay.actuator_qpos)] / scale
        stepped = np.clip(self.perturb(targets), -1, 1)
        qpos, qvel = [sim.raw("qpos")[0].copy()], [sim.raw("qvel")[0].copy()]
        body = [sim.state.body_pos[0].numpy().copy()]
        for action in stepped:
            sim.step(action[None])
            qpos.append(sim.raw("qpos")[0].copy())
            qvel.append(sim.raw("qvel")[0].copy())
            body.append(sim.state.body_pos[0].numpy().copy())
        frames = start + np.arange(length)
        return Track(clip=env.library.names[clip], fps=fps,
                     actions=self.report(stepped).astype(np.float32), qpos=np.stack(qpos),
                     qvel=np.stack(qvel), body_pos=np.stack(body),
                     ref_body_pos=ref.arrays["body_pos"][frames].numpy(),
                     ref_qpos0=ref.qpos64[start].copy(), cpu_seconds=0.0)  # fmt: skip


GOOD = [
    GoodReward,
    GoodTermination,
    GoodSensor,
    GoodObserver,
    GoodScene,
    GoodCharacter,
    GoodAlgorithm,
    GoodFormat,
    GoodCommand,
    GoodCallback,
    GoodPlanner,
]


@retarget.hookimpl
def register_rewards(register) -> None:
    register(GoodReward)


@retarget.hookimpl
def register_terminations(register) -> None:
    register(GoodTermination)


@retarget.hookimpl
def register_sensors(register) -> None:
    register(GoodSensor)


@retarget.hookimpl
def register_observers(register) -> None:
    register(GoodObserver)


@retarget.hookimpl
def register_scenes(register) -> None:
    register(GoodScene)


@retarget.hookimpl
def register_characters(register) -> None:
    register(GoodCharacter)


@retarget.hookimpl
def register_algorithms(register) -> None:
    register(GoodAlgorithm)


@retarget.hookimpl
def register_motion_formats(register) -> None:
    register(GoodFormat)


@retarget.hookimpl
def register_commands(register) -> None:
    register(GoodCommand)


@retarget.hookimpl
def register_callbacks(register) -> None:
    register(GoodCallback)


@retarget.hookimpl
def register_planners(register) -> None:
    register(GoodPlanner)
