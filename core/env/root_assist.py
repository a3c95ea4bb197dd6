"""Root assist: a force and torque on the root toward the reference, annealed to zero.

Residual force control (Yuan & Kitani) lets a policy track motions it cannot yet balance: an
external wrench on the root pulls it toward the reference root, so early episodes last long
enough to learn the joints' part instead of ending in a fall after a second. The wrench is a PD
law on the root's position and orientation error (natural frequency ``frequency`` Hz, damping
ratio ``damping_ratio``) scaled by the body's mass (and an inertia of the same body size), held
over the control step's substeps and capped at ``max_force`` times body weight. Its scale goes
linearly from ``strength`` to zero over ``anneal_steps`` environment steps of *training*: an
environment only receives it while a trainer sets :attr:`RootAssist.scale`, so evaluation,
play, export and live sessions never see it.
"""

from __future__ import annotations

import numpy as np
import torch

from retarget.geometry.heading import quat_conj, quat_mul
from retarget.settings.env import RootAssistOptions


def rotation_vector(q: torch.Tensor) -> torch.Tensor:
    """Axis times angle ``(N, 3)`` of wxyz quaternions, the short way round."""
    q = torch.where(q[:, :1] < 0, -q, q)
    v = q[:, 1:]
    n = v.norm(dim=-1, keepdim=True)
    angle = 2.0 * torch.atan2(n, q[:, :1])
    return torch.where(n > 1e-8, v * angle / n.clamp(min=1e-8), 2.0 * v)


class RootAssist:
    """The wrench of a batch, from the simulated and reference root states."""

    def __init__(self, options: RootAssistOptions, mass: float, height: float) -> None:
        self.options = options
        self.scale = 0.0  # set by a trainer each iteration; zero everywhere else
        w = 2.0 * np.pi * options.frequency
        self.kp, self.kd = w * w, 2.0 * options.damping_ratio * w
        self.mass = mass
        self.inertia = mass * (0.25 * height) ** 2  # a body-sized radius of gyration
        self.cap = options.max_force * mass * 9.81

    def wrench(
        self,
        pos: torch.Tensor, quat: torch.Tensor, linvel: torch.Tensor, angvel: torch.Tensor,
        ref_pos: torch.Tensor, ref_quat: torch.Tensor, ref_linvel: torch.Tensor,
        ref_angvel: torch.Tensor,
    ) -> torch.Tensor:  # fmt: skip
        """World force and torque ``(N, 6)`` on the root body (all inputs ``(N, 3|4)``)."""
        s = self.scale
        force = self.mass * (self.kp * (ref_pos - pos) + self.kd * (ref_linvel - linvel))
        err = rotation_vector(quat_mul(ref_quat, quat_conj(quat)))
        torque = self.inertia * (self.kp * err + self.kd * (ref_angvel - angvel))
        out = torch.cat([force, torque], dim=-1) * s
        norm = out[:, :3].norm(dim=-1, keepdim=True).clamp(min=1e-9)
        out[:, :3] *= (self.cap / norm).clamp(max=1.0)
        tnorm = out[:, 3:].norm(dim=-1, keepdim=True).clamp(min=1e-9)
        out[:, 3:] *= (self.cap * 0.25 * self.inertia / self.mass / tnorm).clamp(max=1.0)
        return out
