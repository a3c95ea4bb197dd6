"""A kinematic pose estimator with per-joint uncertainty (EnvPoser stage I), trained supervised.

From the device features of a time window (the run's sensors, in the headset frame of
:mod:`retarget.learn.pose_samples`) an MLP predicts the canonical body (root position, root
and joint rotations as 6D), the two foot contacts and, per joint, a log-variance of its
position and of its rotation. Training minimises the Gaussian negative log-likelihood (as
EnvPoser does) of the joint positions (forward kinematics of the predicted rotations) and of
the 6D rotations, plus the contacts' cross-entropy: where the devices say little (the legs
from three points, the hands from a headset alone) the network learns a large variance
instead of being pulled towards every sample's exact pose. No physics is stepped: samples
are library frames, half of them mirrored.

An MLP over a flat window is what keeps one frame at tens of microseconds on a CPU (EgoPoser
reports > 600 frames/s; EnvPoser's transformer is slower), which leaves the real-time budget
to the physics of a two-stage tracker.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import torch
from torch import nn

from retarget.learn.normalizer import RunningNormalizer
from retarget.learn.pose_samples import (
    HeadsetFrame,
    J,
    PoseTargets,
    forward_kinematics,
    pose_targets,
    reads_controllers,
    sensor_inputs,
    sixd_to_matrix,
)

LOGVAR_RANGE = (-14.0, 4.0)
"""Clamp of predicted log-variances (std 0.9 mm .. 7 m for positions): keeps the NLL finite."""


@dataclass
class PoseOutput:
    """The network's prediction for a batch, in the headset frame."""

    root_pos: torch.Tensor  # (B, 3)
    rot6d: torch.Tensor  # (B, J, 6)
    contact_logits: torch.Tensor  # (B, 2)
    pos_logvar: torch.Tensor  # (B, J)
    rot_logvar: torch.Tensor  # (B, J)

    @property
    def matrices(self) -> torch.Tensor:
        return sixd_to_matrix(self.rot6d)


OUTPUT_SIZE = 3 + J * 6 + 2 + J + J
"""The network's output: root, 6D rotations, contact logits, two log-variances per joint."""
DEPLOYED_SIZE = 3 + J * 6 + 2 + J
"""What an exported estimator gives: root, 6D rotations, contact probabilities, position std."""


class PoseNet(nn.Module):
    """Normaliser + MLP: raw device features ``(B, D)`` -> the flat pose output."""

    def __init__(self, obs_dim: int, hidden: tuple[int, ...]) -> None:
        super().__init__()
        self.norm = RunningNormalizer(obs_dim)
        layers: list[nn.Module] = []
        last = obs_dim
        for h in hidden:
            layers += [nn.Linear(last, h), nn.SiLU()]
            last = h
        layers.append(nn.Linear(last, OUTPUT_SIZE))
        self.mlp = nn.Sequential(*layers)
        with torch.no_grad():  # start at identity rotations and moderate variances
            out = self.mlp[-1]
            assert isinstance(out, nn.Linear)
            out.weight.mul_(0.01)
            bias = torch.zeros(OUTPUT_SIZE)
            bias[3 : 3 + J * 6] = torch.tensor([1.0, 0, 0, 0, 1.0, 0]).repeat(J)
            bias[2] = 0.9
            bias[3 + J * 6 + 2 :] = -4.0
            out.bias.copy_(bias)

    def forward(
        self, obs: torch.Tensor, noise: float = 0.0, generator: torch.Generator | None = None
    ) -> torch.Tensor:
        """``noise``: std of Gaussian noise on the normalised inputs (training only), so that
        the network cannot key on exact device trajectories of the few training clips."""
        x = self.norm(obs)
        if noise > 0:
            x = x + torch.randn(x.shape, generator=generator) * noise
        return self.mlp(x)

    @staticmethod
    def split(flat: torch.Tensor) -> PoseOutput:
        b = flat.shape[0]
        a = 3 + J * 6
        lo, hi = LOGVAR_RANGE
        return PoseOutput(
            root_pos=flat[:, :3],
            rot6d=flat[:, 3:a].reshape(b, J, 6),
            contact_logits=flat[:, a : a + 2],
            pos_logvar=flat[:, a + 2 : a + 2 + J].clamp(lo, hi),
            rot_logvar=flat[:, a + 2 + J :].clamp(lo, hi),
        )


class DeployedEstimator(nn.Module):
    """What a headset application runs: raw features ``(B, D)`` -> ``(B, 3 + 6J + 2 + J)``:
    root position, 6D rotations (root relative to the headset's heading, then local), contact
    probabilities and each joint's position standard deviation (metres), headset frame."""

    def __init__(self, net: PoseNet) -> None:
        super().__init__()
        self.net = net

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        out = PoseNet.split(self.net(obs))
        b = obs.shape[0]
        return torch.cat([
            out.root_pos, out.rot6d.reshape(b, -1), torch.sigmoid(out.contact_logits),
            torch.exp(0.5 * out.pos_logvar),
        ], dim=-1)  # fmt: skip


def gaussian_nll(error_sq: torch.Tensor, logvar: torch.Tensor, dims: int) -> torch.Tensor:
    """Per-joint NLL (constant dropped) of squared errors summed over ``dims`` components."""
    return 0.5 * (error_sq * torch.exp(-logvar) + dims * logvar)


@dataclass(frozen=True)
class EstimatorSettings:
    hidden: tuple[int, ...] = (512, 512)
    lr: float = 1e-3
    batch_size: int = 2048
    updates_per_iteration: int = 4
    mirror: bool = True
    rot_weight: float = 0.1
    contact_weight: float = 0.1
    scale_range: float = 0.0
    input_noise: float = 0.0
    weight_decay: float = 0.0
    lost_controllers: float = 0.0
    reach: bool = False  # wrists onto the controllers by IK when estimating (reach.py),
    # where the sensors read the controllers


class EstimatorLearner:
    """Supervised training on an env's motion library; checkpoints resume exactly."""

    def __init__(self, env: Any, settings: EstimatorSettings, generator: torch.Generator) -> None:
        self.env, self.settings, self.generator = env, settings, generator
        probe, _ = sensor_inputs(env, env.library.start[:1].clone())
        self.obs_dim = int(probe.shape[1])
        self.reach = settings.reach and reads_controllers(env)
        """Whether estimates reach the controllers (asked for, and the inputs have them)."""
        self.net = PoseNet(self.obs_dim, settings.hidden)
        self.optimizer = torch.optim.AdamW(
            self.net.parameters(), lr=settings.lr, weight_decay=settings.weight_decay
        )
        self.iteration = 0

    def sample(self, n: int) -> tuple[torch.Tensor, HeadsetFrame, PoseTargets]:
        lib = self.env.library
        clip, frame = lib.sample(n, self.generator, margin=0)
        rows = lib.rows(clip, frame)[:, 0]
        s, g = self.settings, self.generator
        mirrored = torch.rand(n, generator=g) < 0.5 if s.mirror else None
        scale = None
        if s.scale_range > 0:
            scale = 1.0 + (torch.rand(n, generator=g) * 2 - 1) * s.scale_range
        frozen = None
        if s.lost_controllers > 0:  # lost from a random entry of the window on
            w = len(self.env.window_offsets)
            lost = torch.rand(n, 2, generator=g) < s.lost_controllers
            start = torch.randint(0, w, (n, 2), generator=g)
            frozen = torch.where(lost, start, torch.full_like(start, w))
        inputs, hf = sensor_inputs(self.env, rows, mirrored, scale, frozen)
        return inputs, hf, pose_targets(self.env, rows, hf, mirrored, scale)

    def losses(
        self, inputs: torch.Tensor, target: PoseTargets, noise: bool = False
    ) -> dict[str, torch.Tensor]:
        flat = self.net(inputs, self.settings.input_noise if noise else 0.0, self.generator)
        out = PoseNet.split(flat)
        pos = forward_kinematics(out.root_pos, out.matrices, target.heights)
        pos_err = (pos - target.positions).square().sum(-1)  # (B, J)
        rot_err = (out.rot6d - target.rot6d).square().sum(-1)
        s = self.settings
        contact = nn.functional.binary_cross_entropy_with_logits(
            out.contact_logits, target.contacts
        )
        nll_pos = gaussian_nll(pos_err, out.pos_logvar, 3).mean()
        nll_rot = gaussian_nll(rot_err, out.rot_logvar, 6).mean()
        return {
            "loss": nll_pos + s.rot_weight * nll_rot + s.contact_weight * contact,
            "nll_pos": nll_pos,
            "nll_rot": nll_rot,
            "contact_bce": contact,
            "mpjpe_mm": pos_err.sqrt().mean().detach() * 1e3,
        }

    def train_iteration(self) -> dict[str, float]:
        s = self.settings
        stats: dict[str, float] = {}
        for _ in range(s.updates_per_iteration):
            inputs, _, target = self.sample(s.batch_size)
            self.net.norm.update(inputs)
            parts = self.losses(inputs, target, noise=True)
            self.optimizer.zero_grad()
            parts["loss"].backward()
            nn.utils.clip_grad_norm_(self.net.parameters(), 1.0)
            self.optimizer.step()
            for k, v in parts.items():
                stats[k] = stats.get(k, 0.0) + float(v.detach()) / s.updates_per_iteration
        self.iteration += 1
        stats["samples"] = float(s.batch_size * s.updates_per_iteration)
        return stats

    @torch.no_grad()
    def estimate_rows(self, rows: torch.Tensor) -> tuple[PoseOutput, HeadsetFrame]:
        """The prediction at library ``rows`` (causal: only the window's devices)."""
        inputs, hf = sensor_inputs(self.env, rows)
        out = PoseNet.split(self.net.eval()(inputs))
        if self.reach:
            out = self._reach(out, rows, hf)
        return out, hf

    def _reach(self, out: PoseOutput, rows: torch.Tensor, hf: HeadsetFrame) -> PoseOutput:
        """The estimate with its wrists on the controllers at ``rows`` (headset frame)."""
        from dataclasses import replace

        from retarget.learn.pose_samples import matrix_to_6d
        from retarget.learn.reach import reach, wrist_targets

        lib = self.env.library
        clip = torch.searchsorted(lib.start, rows, right=True) - 1
        ctrl = hf.poses_in(lib.devices[rows][:, 1:3])  # (B, 2, 7)
        wrist_pos, wrist_rot = wrist_targets(ctrl, lib.heights[clip].float())
        local = reach(out.root_pos, out.matrices, lib.bones[clip].float(), wrist_pos, wrist_rot)
        return replace(out, rot6d=matrix_to_6d(local))

    def warm_start(self, state: Mapping[str, Any]) -> None:
        """The pose network of another estimator run that read the same device features
        (``state``, its :meth:`state_dict`). The optimiser and the counters start fresh, and
        the input statistics count as a few batches, so devices of another scale
        (``env.devices``) or other motions take them over within minutes."""
        if "net" not in state:
            raise ValueError("the source run is not a pose estimator (no 'net' in its state)")
        try:
            self.net.load_state_dict(state["net"])
        except RuntimeError as exc:  # a tensor of another shape: hidden sizes differ
            raise ValueError(f"the networks differ: {str(exc).splitlines()[-1].strip()}") from None
        batches = 10.0 * self.settings.batch_size
        self.net.norm.count.fill_(min(float(self.net.norm.count), batches))

    def state_dict(self) -> dict[str, Any]:
        return {
            "net": self.net.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "iteration": self.iteration,
            "generator": self.generator.get_state(),
        }

    def load_state_dict(self, state: Any) -> None:
        self.net.load_state_dict(state["net"])
        if "optimizer" not in state:  # a policy-only checkpoint (pretrained): estimating only
            return
        self.optimizer.load_state_dict(state["optimizer"])
        self.iteration = int(state["iteration"])
        self.generator.set_state(state["generator"])
