"""PHC's evaluation protocol beside the project's own metrics.

Perpetual Humanoid Control (Luo et al. 2023) and the imitators after it report, per clip run:
*success* (the run fails when, at any frame, the mean position error over all bodies exceeds
0.5 m), and over every frame of the run (not only until a failure, unlike the QuestEnvSim
figures): root-relative MPJPE, global MPJPE, Procrustes-aligned MPJPE, and the acceleration
and velocity errors of the bodies (mm/frame^2 and mm/frame, from finite differences of
positions). Each error is reported twice, over all runs (``phc_*``) and over successful runs
only (``phc_*_succ``, NaN for a failed run so the mean over runs leaves it out). Run with
``retarget eval --protocol phc`` to get PHC's one run per clip from its first to last frame.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import torch

from retarget.eval.metrics import procrustes_error
from retarget.eval.terms import Column, EvalBatch, EvalStep, MetricTerm

FAIL_DISTANCE = 0.5
"""Metres of mean body-position error at which a PHC run has failed."""
MM = 1000.0
ERRORS = ("mpjpe", "g_mpjpe", "pa_mpjpe", "accel", "vel")
LABELS = {"mpjpe": "mpjpe_mm", "g_mpjpe": "g_mpjpe_mm", "pa_mpjpe": "pa_mpjpe_mm",
          "accel": "accel_mm_f2", "vel": "vel_mm_f"}  # fmt: skip


class PhcProtocol(MetricTerm):
    """Success and the MPJPE family over all bodies, every frame of each run."""

    columns = (
        Column("phc_success", "phc_success"),
        *(Column(f"phc_{k}", f"phc_{LABELS[k]}", MM) for k in ERRORS),
        *(Column(f"phc_{k}_succ", f"phc_{LABELS[k]}_succ", MM) for k in ERRORS),
    )

    def start(self, n: int) -> None:
        self.failed = torch.zeros(n, dtype=torch.bool)
        self.sums = {k: torch.zeros(n, dtype=torch.float64) for k in ERRORS}
        self.counts = {k: torch.zeros(n, dtype=torch.float64) for k in ERRORS}
        self.history: list[tuple[torch.Tensor, torch.Tensor]] = []

    def _add(self, key: str, value: torch.Tensor, mask: torch.Tensor) -> None:
        self.sums[key] += torch.where(mask, value.double(), 0.0)
        self.counts[key] += mask.double()

    def update(self, step: EvalStep) -> None:
        sim, ref = step.ctx.sim.body_pos, step.ctx.ref.pose.body_pos
        alive = step.alive
        err = (sim - ref).norm(dim=-1)  # (N, B)
        self.failed |= alive & (err.mean(-1) > FAIL_DISTANCE)
        self._add("g_mpjpe", err.mean(-1), alive)
        rel = (sim - sim[:, :1]) - (ref - ref[:, :1])  # root-relative
        self._add("mpjpe", rel.norm(dim=-1).mean(-1), alive)
        self._add("pa_mpjpe", procrustes_error(sim, ref), alive)
        self.history = [*self.history[-2:], (sim.clone(), ref.clone())]
        if len(self.history) >= 2:
            (s1, r1), (s2, r2) = self.history[-2], self.history[-1]
            vel = ((s2 - s1) - (r2 - r1)).norm(dim=-1).mean(-1)
            self._add("vel", vel, alive & (step.step >= 1))
        if len(self.history) == 3:
            (s0, r0), (s1, r1), (s2, r2) = self.history
            acc = ((s2 - 2 * s1 + s0) - (r2 - 2 * r1 + r0)).norm(dim=-1).mean(-1)
            self._add("accel", acc, alive & (step.step >= 2))

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        k = batch.runs
        ok = ~self.failed[:k]
        out: dict[str, np.ndarray] = {"phc_success": ok.double().numpy()}
        for key in ERRORS:
            mean = self.sums[key][:k] / self.counts[key][:k].clamp_min(1)
            mean = torch.where(self.counts[key][:k] > 0, mean, torch.nan)
            out[f"phc_{key}"] = mean.numpy()
            out[f"phc_{key}_succ"] = torch.where(ok, mean, torch.nan).numpy()
        return out
