"""The metrics ``retarget eval`` reports: tracking errors (QuestEnvSim, SimXR), smoothness,
success rates, falls and feet hitting props. Each is a :class:`~retarget.eval.terms.MetricTerm`."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import torch

from retarget.eval.phc import PhcProtocol
from retarget.eval.prop_hits import foot_geoms, foot_prop_hits, prop_geoms
from retarget.eval.terms import Column, EvalBatch, EvalStep, MetricTerm
from retarget.kinds import Termination

MM, CM, DEG = 1000.0, 100.0, 180.0 / np.pi


class StepMean(MetricTerm):
    """The mean over a run's tracked steps of one per-step value of
    :class:`~retarget.eval.metrics.StepMetrics` (missing values count as 0)."""

    def __init__(self, key: str, label: str, scale: float = 1.0) -> None:
        self.key = key
        self.columns = (Column(key, label, scale),)

    def start(self, n: int) -> None:
        self.sum = torch.zeros(n)

    def update(self, step: EvalStep) -> None:
        value = getattr(step.metrics, self.key)
        if value is not None:
            self.sum += torch.where(step.ok, torch.nan_to_num(value), 0.0)

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        k = batch.runs
        return {self.key: (self.sum[:k] / batch.tracked.clamp_min(1)[:k]).numpy()}


class Jerk(MetricTerm):
    """Mean norm of the third difference of body positions over tracked steps (km/s^3)."""

    columns = (Column("jerk", "jerk_km_s3", 1e-3),)

    def start(self, n: int) -> None:
        self.sum = torch.zeros(n)
        self.history: list[torch.Tensor] = []

    def update(self, step: EvalStep) -> None:
        self.history = [*self.history[-3:], step.ctx.sim.body_pos.clone()]
        if len(self.history) == 4:
            h = self.history
            d3 = h[3] - 3 * h[2] + 3 * h[1] - h[0]
            jerk = d3.norm(dim=-1).mean(-1) / step.ctx.dt**3
            self.sum += torch.where(step.ok, jerk, 0.0)

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        k = batch.runs
        return {"jerk": (self.sum[:k] / (batch.tracked[:k] - 3).clamp_min(1)).numpy()}


class PenetrationMax(MetricTerm):
    """The deepest overlap with the scene of any tracked step; over runs, the worst run."""

    columns = (Column("penetration_max", "penetration_max_mm", MM, reduce="max"),)

    def start(self, n: int) -> None:
        self.worst = torch.zeros(n)

    def update(self, step: EvalStep) -> None:
        deepest = step.metrics.penetration_max
        if deepest is not None:
            self.worst = torch.maximum(self.worst, torch.where(step.ok, deepest, 0.0))

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        return {"penetration_max": self.worst[: batch.runs].numpy()}


class Success(MetricTerm):
    """QuestEnvSim's success: the run tracked (mean device error under the failure distance)
    for 20 s / 30 s, or to its end when shorter; and the tracked share of its frames."""

    columns = (
        Column("success_20s", "success_20s"),
        Column("success_30s", "success_30s"),
        Column("frames_ok", "success_frame"),
        Column("seconds", "longest_run_s", reduce="max"),  # shorter than 20 s: "to the end"
    )

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        k, dt = batch.runs, batch.dt
        failed, avail = batch.failed_at[:k], batch.available[:k].float()
        return {
            "success_20s": (failed >= torch.clamp(avail, max=20 / dt)).numpy(),
            "success_30s": (failed >= torch.clamp(avail, max=30 / dt)).numpy(),
            "frames_ok": (torch.minimum(failed, avail) / avail.clamp_min(1)).numpy(),
        }


class HeadSuccess(MetricTerm):
    """SimXR's success: the simulated head never farther than ``distance`` from the headset."""

    columns = (Column("success_simxr", "success_simxr"),)

    def __init__(self, distance: float) -> None:
        self.distance = distance

    def start(self, n: int) -> None:
        self.failed = torch.zeros(n, dtype=torch.bool)

    def update(self, step: EvalStep) -> None:
        self.failed |= step.alive & (step.metrics.head_to_headset > self.distance)

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        return {"success_simxr": (~self.failed[: batch.runs]).numpy()}


class Falls(MetricTerm):
    """Falls per minute: steps where ``fall`` (a bound termination) starts to hold. Counted
    over every step of a run, since a fall is a physical event, not a tracking error."""

    columns = (Column("falls", "falls_per_min", reduce="rate", per="seconds", factor=60.0),)

    def __init__(self, fall: Termination | None) -> None:
        self.fall = fall

    def start(self, n: int) -> None:
        self.count = torch.zeros(n)
        self.down = torch.zeros(n, dtype=torch.bool)

    def update(self, step: EvalStep) -> None:
        if self.fall is not None:
            now = self.fall.check(step.ctx) & step.alive
            self.count += (now & ~self.down).float()
            self.down = now

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        return {"falls": self.count[: batch.runs].numpy()}


class PropHits(MetricTerm):
    """Feet on a prop's top or against its side (:mod:`retarget.eval.prop_hits`): the share of
    steps, and per minute the hits that begin (a side hit held five steps is one stumble)."""

    SIDES = ("top", "side")
    columns = tuple(
        col
        for side in SIDES
        for col in (
            Column(f"box_{side}_steps", f"box_{side}_fraction", reduce="rate", per="steps"),
            Column(
                f"box_{side}_events", f"box_{side}_per_min", reduce="rate", factor=60.0
            ),
        )
    )

    def __init__(self, env, props: np.ndarray) -> None:
        self.env, self.props = env, props
        self.model = env.world.model
        self.feet = foot_geoms(self.model, env.layout)

    def start(self, n: int) -> None:
        self.steps = {s: torch.zeros(n) for s in self.SIDES}
        self.events = {s: torch.zeros(n) for s in self.SIDES}
        self.before = {s: torch.zeros(n, dtype=torch.bool) for s in self.SIDES}

    def update(self, step: EvalStep) -> None:
        model, feet, props = self.model, self.feet, self.props
        found = self.env.sim.each_env(lambda d: foot_prop_hits(model, d, feet, props))
        for j, side in enumerate(self.SIDES):
            now = torch.tensor([h[j] for h in found]) & step.alive
            self.steps[side] += now.float()
            self.events[side] += (now & ~self.before[side]).float()
            self.before[side] = now

    def finish(self, batch: EvalBatch) -> Mapping[str, np.ndarray]:
        k = batch.runs
        out = {}
        for side in self.SIDES:
            out[f"box_{side}_steps"] = self.steps[side][:k].numpy()
            out[f"box_{side}_events"] = self.events[side][:k].numpy()
        return out


JOINT_MEANS = {"g_mpjpe", "mpjpe", "pa_mpjpe", "mpjre", "mpjve"}


def standard_terms(
    env, *, has_joints: bool, head_distance: float, fall: Termination | None,
    stepped: bool = True,
) -> list[MetricTerm]:  # fmt: skip
    """The report's terms, in the order its columns are printed. ``stepped=False`` (a
    kinematic method: nothing is simulated) leaves out the terms that read the simulation's
    contact list (feet hitting props)."""
    means = [
        ("hmd_pos", "headset_cm", CM),
        ("hmd_rot", "headset_deg", DEG),
        ("controller_pos", "controller_cm", CM),
        ("feet_pos", "feet_cm", CM),
        ("head_to_headset", "head_to_headset_cm", CM),
        ("hand_gap", "hands_to_controllers_cm", CM),
        ("g_mpjpe", "g_mpjpe_mm", MM),
        ("mpjpe", "mpjpe_mm", MM),
        ("pa_mpjpe", "pa_mpjpe_mm", MM),
        ("mpjre", "mpjre_deg", DEG),
        ("mpjve", "mpjve_mm_per_frame", MM),
        ("skate", "foot_skate_mm", MM),
    ]
    after = [
        ("contact_agree", "contact_agreement", 1.0),
        ("scene_contact_agree", "scene_contact_agreement", 1.0),
        ("penetration_mean", "penetration_mean_mm", MM),
    ]

    def mean_terms(rows):
        return [StepMean(*row) for row in rows if has_joints or row[0] not in JOINT_MEANS]

    terms: list[MetricTerm] = [
        *mean_terms(means),
        Jerk(),
        *mean_terms(after),
        PenetrationMax(),
        Success(),
        HeadSuccess(head_distance),
        Falls(fall),
        PhcProtocol(),
    ]
    props = prop_geoms(env.world.model)
    if props.any() and stepped:
        terms.append(PropHits(env, props))
    return terms
