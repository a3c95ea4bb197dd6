"""Metric terms: a new metric is one class, reported with its declared aggregation."""

from __future__ import annotations

import numpy as np
import torch

from retarget.env import EnvOptions, RetargetEnv
from retarget.eval import EvalSettings, evaluate
from retarget.eval.terms import Column, MetricTerm, summarise
from retarget.motion.procedural import idle_clip
from retarget.plugins.characters.human import Human


class RootHeight(MetricTerm):
    """Highest root of a run (cm) and the steps counted, pooled per second."""

    columns = (
        Column("root_top", "root_top_cm", 100.0, reduce="max"),
        Column("counted", "counted_per_s", reduce="rate", per="seconds"),
    )

    def start(self, n: int) -> None:
        self.top = torch.zeros(n)
        self.count = torch.zeros(n)

    def update(self, step) -> None:
        self.top = torch.maximum(self.top, step.ctx.sim.qpos[:, 2].float())
        self.count += step.alive.float()

    def finish(self, batch):
        k = batch.runs
        return {"root_top": self.top[:k].numpy(), "counted": self.count[:k].numpy()}


def test_an_added_term_is_reported_after_the_standard_ones() -> None:
    env = RetargetEnv(Human(), [idle_clip(2.0)], options=EnvOptions(num_envs=2))
    policy = lambda obs: torch.zeros(2, env.action_dim)  # noqa: E731
    report = evaluate(env, policy, EvalSettings(every=20, max_seconds=0.5), terms=[RootHeight()])
    overall = report["overall"]
    labels = list(overall)
    assert labels.index("root_top_cm") > labels.index("falls_per_min")
    assert 50 < overall["root_top_cm"] < 200  # a standing human's pelvis, in cm
    hz = 1 / env.sim.settings.control_dt
    assert abs(overall["counted_per_s"] - hz) < 1e-6 * hz  # every step of every second counted


def test_summarise_means_maxima_and_pooled_rates() -> None:
    per_run = {
        "a": np.array([1.0, np.nan, 3.0]),
        "b": np.array([1.0, 5.0, 2.0]),
        "events": np.array([1.0, 0.0, 2.0]),
        "seconds": np.array([30.0, 60.0, 90.0]),
    }
    cols = [
        Column("a", "a_mean", 10.0),
        Column("b", "b_max", reduce="max"),
        Column("events", "per_min", reduce="rate", factor=60.0),
    ]
    out = summarise(cols, per_run, np.array([True, True, True]))
    assert out == {"a_mean": 20.0, "b_max": 5.0, "per_min": 1.0}
    assert summarise(cols, per_run, np.array([True, False, False]))["per_min"] == 2.0
