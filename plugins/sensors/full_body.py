"""Teacher sensors: the whole target body, which only a simulator (never a headset) provides.

``full_body`` is the motion imitator's goal state of PHC as SimXR (Sec. 3.1) writes it: for the
reference frame(s) ahead, every body's rotation difference to the simulated body, position
difference, linear and angular velocity differences, and the reference rotation and position
themselves, all in the simulated character's heading frame. For Dino, Oppy and Jesse the
reference is the kinematically retargeted character motion, so any character has a teacher.

``reference_action`` is the reference's next joint angles as PD-target actions
(:mod:`retarget.sim.actuation`): an imitator whose actions are this plus a learned residual
(``ppo`` with ``residual: reference_action``) already moves its joints with the motion before
training and only has to learn the balance corrections. With ``feedforward`` the base also
carries the reference's own inverse-dynamics torque (``SimState.pd_feedforward``): a servo
aimed at the reference angle alone sags under gravity by ``torque / kp`` and lags by its
damping, so a residual policy would first have to learn to hold every limb up.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field, field_validator

import retarget
from retarget import Layout, ObsSpec, PluginConfig, PluginError, Sensor, StepContext, StepNeeds

if TYPE_CHECKING:
    import torch


def _offsets_valid(value: list[int]) -> list[int]:
    if not value or any(k < 1 for k in value) or len(set(value)) != len(value):
        raise ValueError("offsets must be distinct frame counts >= 1, e.g. [1] or [1, 3]")
    if max(value) > 360:
        raise ValueError("offsets beyond 360 frames (10 s at 36 Hz) are not supported")
    return value


class FullBodyConfig(PluginConfig):
    offsets: list[int] = Field(
        default_factory=lambda: [1],
        description="reference frames ahead; PHC's goal is the next frame only ([1])",
    )
    velocities: bool = Field(True, description="include linear/angular velocity differences")

    _check = field_validator("offsets")(classmethod(lambda cls, v: _offsets_valid(v)))


class FullBody(Sensor[FullBodyConfig]):
    """The whole reference body ahead, relative to the simulated body (teacher input).

    Per offset and body: rotation difference sim->reference (6D, body frame), position
    difference (3), linear and angular velocity differences (3 + 3, optional), reference
    rotation (6D) and position relative to the root (3), in the heading frame; then the
    reference root's offset from the simulated root (3).
    """

    name = "full_body"

    def needs(self) -> StepNeeds:
        return StepNeeds(reference_offsets=tuple(self.config.offsets))

    def _per_body(self) -> int:
        return 6 + 3 + (6 if self.config.velocities else 0) + 6 + 3

    def spec(self, layout: Layout) -> ObsSpec:
        per = self._per_body() * layout.num_bodies + 3
        return ObsSpec((len(self.config.offsets) * per,))

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch

        from retarget.geometry.heading import (
            ground_origin,
            heading_cos_sin,
            quat_conj,
            quat_mul,
            quat_to_6d,
            to_heading_quats,
            unyaw,
        )
        s = ctx.sim
        root_pos, root_quat = s.qpos[:, :3], s.qpos[:, 3:7]
        c, sn = heading_cos_sin(root_quat)
        origin = ground_origin(root_pos)
        n = ctx.num_envs
        parts = []
        for k in self.config.offsets:
            ref = ctx.ref.future.get(k)
            if ref is None:
                raise PluginError(
                    f"the step context has no reference {k} frames ahead "
                    f"(has {sorted(ctx.ref.future)})",
                    plugin=self.name,
                    hint="the environment gathers the offsets needs() names",
                )
            diff_rot = quat_to_6d(quat_mul(quat_conj(s.body_quat), ref.body_quat))
            ref_rot = quat_to_6d(to_heading_quats(ref.body_quat, root_quat))
            vectors = [ref.body_pos - s.body_pos]
            if self.config.velocities:
                vectors += [ref.body_linvel - s.body_linvel, ref.body_angvel - s.body_angvel]
            vectors += [ref.body_pos - origin[:, None], (ref.qpos[:, :3] - root_pos)[:, None]]
            vec = unyaw(torch.cat(vectors, dim=1), c, sn)
            b = s.body_pos.shape[1]
            chunks = vec[:, :-1].split(b, dim=1)
            per_body = torch.cat([diff_rot, *chunks[:-1], ref_rot, chunks[-1]], dim=-1)
            parts += [per_body.reshape(n, -1), vec[:, -1]]
        return torch.cat(parts, dim=-1).float()


class ReferenceActionConfig(PluginConfig):
    offset: int = Field(1, ge=1, le=360, description="reference frame whose joint angles to use")
    feedforward: float = Field(
        0.0, ge=0.0, le=2.0,
        description="share of the reference's PD feedforward (its inverse-dynamics torque and "
        "the servo's damping over kp) added to each target; 0 gives the plain joint angles",
    )  # fmt: skip


class ReferenceAction(Sensor[ReferenceActionConfig]):
    """The reference's joint angles ``offset`` frames ahead as PD-target actions in [-1, 1],
    plus ``feedforward`` x its PD feedforward.

    ``target / scale`` per actuator, ``scale`` the larger magnitude of its joint range, clamped
    to the range, exactly the mapping of ``sim.actuation: pd``: the base a residual imitator
    adds its corrections to. Meaningful with PD actuation only.
    """

    name = "reference_action"

    def bind(self, layout: Layout) -> None:
        import torch
        if len(layout.actuator_qpos) != layout.nu or len(layout.actuator_ranges) != layout.nu:
            raise PluginError(
                "the layout does not say which joint each actuator drives (actuator_qpos, "
                "actuator_ranges)",
                plugin=self.name,
            )
        ranges = torch.tensor(layout.actuator_ranges, dtype=torch.float32).reshape(-1, 2)
        scale = ranges.abs().amax(dim=-1).clamp_min(1e-6)
        self._qpos = torch.tensor(layout.actuator_qpos, dtype=torch.long)
        self._scale = scale
        self._low, self._high = (ranges[:, 0] / scale).clamp(-1, 1), (ranges[:, 1] / scale).clamp(
            -1, 1
        )

    def needs(self) -> StepNeeds:
        return StepNeeds(reference_offsets=(self.config.offset,))

    def spec(self, layout: Layout) -> ObsSpec:
        return ObsSpec((layout.nu,))

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch
        ref = ctx.ref.future[self.config.offset]
        target = ref.qpos[:, self._qpos]
        if self.config.feedforward:
            if ref.pd_feedforward is None:
                raise PluginError(
                    "feedforward needs the reference's pd_feedforward, which this step "
                    "context's reference state lacks",
                    plugin=self.name,
                    hint="set feedforward: 0, or run it in retarget's tracking environment",
                )
            target = target + self.config.feedforward * ref.pd_feedforward
        target = target / self._scale
        return torch.maximum(torch.minimum(target, self._high), self._low).float()


@retarget.hookimpl
def register_sensors(register) -> None:
    register(FullBody)
    register(ReferenceAction)
