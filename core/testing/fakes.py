"""Small, real stand-ins the contract suite runs plugins against.

``TinyCharacter`` is a genuine MuJoCo character (free root, a torso with a head site, two arms
with hand sites, two legs, a passive tail joint) small enough to compile in milliseconds;
``fake_context`` fills a :class:`StepContext` with random but *valid* state (unit quaternions,
non-negative forces) for any layout and number of environments.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import mujoco
import torch

from retarget.kinds import Character, Scene
from retarget.kinds.state import Layout, ReferenceBatch, SimState, StepContext
from retarget.scene.ground import Ground
from retarget.sim.world import World, build_world

if TYPE_CHECKING:
    from retarget.character.joint_map import JointMap
    from retarget.motion.library import MotionLibrary

_CAPSULE = mujoco.mjtGeom.mjGEOM_CAPSULE
_HINGE = mujoco.mjtJoint.mjJNT_HINGE


class TinyCharacter(Character):
    """A seven-body test character: pelvis, torso, two arms, two legs and a passive tail."""

    name = "tiny"

    def build_spec(self) -> mujoco.MjSpec:
        spec = mujoco.MjSpec()
        spec.option.timestep = 1 / 240
        pelvis = spec.worldbody.add_body(name="pelvis", pos=[0, 0, 0.9])
        pelvis.add_freejoint(name="root")
        pelvis.add_geom(type=_CAPSULE, size=[0.1, 0.1, 0], density=1000, contype=2, conaffinity=1)
        pelvis.add_site(name="root")
        torso = pelvis.add_body(name="torso", pos=[0, 0, 0.25])
        self._hinge(spec, torso, "spine", [0, 1, 0], 100.0)
        torso.add_geom(
            type=_CAPSULE,
            fromto=[0, 0, 0, 0, 0, 0.3],
            size=[0.08, 0, 0],
            density=1000,
            contype=2,
            conaffinity=1,
        )
        torso.add_site(name="head", pos=[0, 0, 0.45])
        for side, y in (("left", 0.2), ("right", -0.2)):
            arm = torso.add_body(name=f"{side}_arm", pos=[0, y, 0.25])
            self._hinge(spec, arm, f"{side}_shoulder", [1, 0, 0], 50.0)
            arm.add_geom(
                type=_CAPSULE,
                fromto=[0, 0, 0, 0, 0, -0.5],
                size=[0.04, 0, 0],
                density=1000,
                contype=2,
                conaffinity=1,
            )
            arm.add_site(name=f"{side}_hand", pos=[0, 0, -0.5])
            leg = pelvis.add_body(name=f"{side}_leg", pos=[0, y / 2, -0.1])
            self._hinge(spec, leg, f"{side}_hip", [0, 1, 0], 150.0)
            leg.add_geom(
                type=_CAPSULE,
                fromto=[0, 0, 0, 0, 0, -0.75],
                size=[0.05, 0, 0],
                density=1000,
                contype=2,
                conaffinity=1,
            )
        tail = pelvis.add_body(name="tail", pos=[-0.12, 0, 0])
        tail.add_joint(
            name="tail_swing",
            type=_HINGE,
            axis=[0, 0, 1],
            stiffness=5.0,
            damping=0.5,
            range=[-1.0, 1.0],
        )
        tail.add_geom(
            type=_CAPSULE,
            fromto=[0, 0, 0, -0.3, 0, 0],
            size=[0.02, 0, 0],
            density=500,
            contype=2,
            conaffinity=1,
        )
        return spec

    @staticmethod
    def _hinge(spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, axis, limit: float) -> None:
        body.add_joint(
            name=name, type=_HINGE, axis=axis, range=[-1.5, 1.5], damping=2.0, armature=0.01
        )
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.gear[0] = limit
        act.ctrllimited = True
        act.ctrlrange = [-1.0, 1.0]

    def site_roles(self) -> Mapping[str, str]:
        return {
            "head": "head",
            "left_hand": "left_hand",
            "right_hand": "right_hand",
            "root": "root",
        }

    def body_groups(self) -> Mapping[str, Sequence[str]]:
        return {
            "feet": ["left_leg", "right_leg"],
            "upper_body": ["torso", "left_arm", "right_arm"],
            # the contact reward's groups (QuestEnvSim: feet, hands, pelvis and spine)
            "left_foot": ["left_leg"],
            "right_foot": ["right_leg"],
            "left_hand": ["left_arm"],
            "right_hand": ["right_arm"],
            "pelvis": ["pelvis"],
            "spine": ["torso"],
        }

    def joint_map(self) -> JointMap:
        """Spine, shoulders and hips follow the human's; the tail stays passive."""
        from retarget.character.joint_map import JointLink, JointMap

        return JointMap(links={name: JointLink(human=(name,)) for name in (
            "spine", "left_shoulder", "right_shoulder", "left_hip", "right_hip")})  # fmt: skip

    def passive_joints(self) -> Sequence[str]:
        return ("tail_swing",)


class FlatScene(Ground):
    """A flat floor at height 0: the scene the contract suite gives observers (the floor
    every environment has without a scene, under a name of its own)."""

    name = "flat_test"


_TINY_WORLD: World | None = None


def tiny_world() -> World:
    """The compiled TinyCharacter on a flat floor (cached: it never changes)."""
    global _TINY_WORLD
    if _TINY_WORLD is None:
        _TINY_WORLD = build_world(TinyCharacter())
    return _TINY_WORLD


def _unit_quat(shape: tuple[int, ...], g: torch.Generator) -> torch.Tensor:
    q = torch.randn(*shape, 4, generator=g)
    return q / q.norm(dim=-1, keepdim=True)


def _fake_state(layout: Layout, n: int, g: torch.Generator) -> SimState:
    b, s = layout.num_bodies, len(layout.site_names)
    qpos = torch.randn(n, layout.nq, generator=g) * 0.3
    qpos[:, 2] += 0.9
    qpos[:, 3:7] = _unit_quat((n,), g)
    body_pos = torch.randn(n, b, 3, generator=g) * 0.3
    body_pos[..., 2] = body_pos[..., 2].abs() + 0.05
    return SimState(
        qpos=qpos,
        qvel=torch.randn(n, layout.nv, generator=g),
        body_pos=body_pos,
        body_quat=_unit_quat((n, b), g),
        body_linvel=torch.randn(n, b, 3, generator=g),
        body_angvel=torch.randn(n, b, 3, generator=g),
        site_pos=torch.randn(n, s, 3, generator=g) * 0.5 + torch.tensor([0.0, 0.0, 1.0]),
        site_quat=_unit_quat((n, s), g),
        contact_force=torch.rand(n, b, generator=g) * 200.0,
        contact_force_up=torch.rand(n, b, generator=g) * 200.0 - 50.0,
    )


def _fake_reference(layout: Layout, n: int, g: torch.Generator, extra: torch.Generator) -> SimState:
    """A fake reference state: a random state plus its PD feedforward (drawn from ``extra``,
    so the other fake values do not move with it)."""
    return replace(_fake_state(layout, n, g),
                   pd_feedforward=torch.randn(n, layout.nu, generator=extra) * 0.05)  # fmt: skip


FAKE_LIBRARY_SECONDS = 1.0


@functools.cache
def fake_library() -> MotionLibrary:
    """A one-second generated idle at the control rate: what ``prepare`` gets in the contract
    suite, and what ``fake_context``'s ``ref.rows`` index into."""
    from retarget.motion.library import MotionLibrary
    from retarget.motion.procedural import idle_clip

    return MotionLibrary([idle_clip(FAKE_LIBRARY_SECONDS)], fps=36.0)


def fake_context(
    layout: Layout | None = None,
    num_envs: int = 4,
    *,
    seed: int = 0,
    window_offsets: tuple[int, ...] = (-2, -1, 0, 1, 2),
    num_devices: int = 3,
    scene: Scene | None = None,
    dt: float = 1 / 36,
    future_offsets: tuple[int, ...] = (1, 2, 3),
) -> StepContext:
    """A random but valid step for ``num_envs`` environments of ``layout`` (default: tiny);
    ``future_offsets`` are the frames ahead whose full reference state ``ref.future`` holds."""
    if layout is None:
        layout = tiny_world().layout
    g = torch.Generator().manual_seed(seed)
    w = len(window_offsets)
    devices = torch.cat(
        [
            torch.randn(num_envs, w, num_devices, 3, generator=g) * 0.5
            + torch.tensor([0.0, 0.0, 1.2]),
            _unit_quat((num_envs, w, num_devices), g),
        ],
        dim=-1,
    )
    extra = torch.Generator().manual_seed(seed + 1)
    ref = ReferenceBatch(
        pose=_fake_reference(layout, num_envs, g, extra),
        devices=devices,
        window_offsets=window_offsets,
        contacts=torch.rand(num_envs, 2, generator=g) > 0.5,  # left, right foot
        future={k: _fake_reference(layout, num_envs, g, extra)
                for k in sorted(set(future_offsets))},
        scene_contacts=torch.rand(num_envs, len(layout.body_groups), generator=g) > 0.5,
        rows=torch.randint(0, int(FAKE_LIBRARY_SECONDS * 36), (num_envs,), generator=g),
    )
    return StepContext(
        layout=layout,
        sim=_fake_state(layout, num_envs, g),
        ref=ref,
        action=torch.rand(num_envs, layout.nu, generator=g) * 2 - 1,
        prev_action=torch.rand(num_envs, layout.nu, generator=g) * 2 - 1,
        episode_step=torch.randint(0, 400, (num_envs,), generator=g),
        terminated=torch.rand(num_envs, generator=g) > 0.7,
        dt=dt,
        scene=scene if scene is not None else FlatScene(),
    )


class FakeVecEnv:
    """A tiny linear-dynamics vector environment for algorithm checks (no physics).

    Reward is higher the closer the action is to a fixed linear function of the observation,
    so a working learner has a real signal; episodes end every ``horizon`` steps.
    """

    def __init__(
        self,
        num_envs: int = 4,
        obs_dims: Mapping[str, int] | None = None,
        action_dim: int = 3,
        horizon: int = 16,
        seed: int = 0,
    ) -> None:
        self.num_envs = num_envs
        self.obs_dims = dict(obs_dims or {"actor": 5, "critic": 8})
        self.action_dim = action_dim
        self.horizon = horizon
        self._g = torch.Generator().manual_seed(seed)
        self._target = torch.randn(self.obs_dims["actor"], action_dim, generator=self._g) * 0.3
        self._t = torch.zeros(num_envs, dtype=torch.long)
        self._obs = self._draw()

    def _draw(self) -> dict[str, torch.Tensor]:
        return {
            k: torch.randn(self.num_envs, d, generator=self._g) for k, d in self.obs_dims.items()
        }

    def reset(self) -> dict[str, torch.Tensor]:
        self._t.zero_()
        self._obs = self._draw()
        return self._obs

    def step(self, action: torch.Tensor):
        want = self._obs["actor"] @ self._target
        reward = torch.exp(-(action - want).square().sum(-1))
        self._t += 1
        truncated = self._t >= self.horizon
        terminated = torch.zeros_like(truncated)
        self._t[truncated] = 0
        self._obs = self._draw()
        return self._obs, reward.float(), terminated, truncated, {}


def kinematic_env():
    """A real one-environment human env with a three-point sensor (4-frame window) over two
    seconds of generated walking: what kinematic algorithms (pose estimators) are checked on."""
    from retarget.env import RetargetEnv
    from retarget.motion.procedural import default_motions
    from retarget.registry.loader import load_plugins
    from retarget.settings.env import EnvOptions

    registry = load_plugins()
    human = registry.get("character", "human").cls()
    sensor_cls = registry.get("sensor", "three_point").cls
    sensor = sensor_cls(sensor_cls.Config.model_validate({"past": 3}))
    walk = default_motions(names=("walk",))[0]
    walk = walk.with_(root_pos=walk.root_pos[:60], local_rot=walk.local_rot[:60],
                      contacts=walk.contacts[:60])  # fmt: skip
    return RetargetEnv(human, [walk], sensors=[sensor], options=EnvOptions(num_envs=1))


def planning_env():
    """A real one-environment human env with PD servos over one second of generated walking,
    no sensors: what planners (``retarget expert``) are checked on."""
    from retarget.env import RetargetEnv
    from retarget.motion.procedural import default_motions
    from retarget.registry.loader import load_plugins
    from retarget.settings.env import EnvOptions
    from retarget.settings.sim import SimSettings

    human = load_plugins().get("character", "human").cls()
    walk = default_motions(names=("walk",))[0]
    walk = walk.with_(root_pos=walk.root_pos[:30], local_rot=walk.local_rot[:30],
                      contacts=walk.contacts[:30])  # fmt: skip
    return RetargetEnv(human, [walk], options=EnvOptions(num_envs=1),
                       sim=SimSettings(actuation="pd"))  # fmt: skip
