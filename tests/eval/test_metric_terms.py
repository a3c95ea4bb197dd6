"""Metric terms: a new metric is one class, reported with its declared aggregation."""

from __future__ import annotations

from dataclasses import replace

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


def test_ctrl_c_keeps_the_clips_that_finished(monkeypatch) -> None:
    clips = [replace(idle_clip(1.0), name=f"idle{i}") for i in range(3)]
    env = RetargetEnv(Human(), clips, options=EnvOptions(num_envs=2))
    calls = []

    def policy(obs):
        calls.append(1)
        if len(calls) > 40:  # Ctrl-C while the third batch is stepped
            raise KeyboardInterrupt
        return torch.zeros(2, env.action_dim)

    seen = []
    report = evaluate(env, policy, EvalSettings(every=18, max_seconds=0.5),
                      on_batch=lambda *done: seen.append(done))  # fmt: skip
    assert report["interrupted"] is True
    assert seen and seen[-1][2] == len(report["clips"]) >= 1  # the finished clips are kept
    assert len(report["clips"]) < 3 and report["overall"]["runs"] == 2 * len(report["clips"])


def test_the_table_fits_120_columns_and_says_when_clips_are_short() -> None:
    from rich.console import Console

    from retarget.cli.eval_cmd import table

    metrics = {"headset_cm": 12.3456, "success_20s": 0.5, "success_30s": 0.5,
               "longest_run_s": 8.0, "mpjpe_mm": 123.0, "falls_per_min": 0.25, "runs": 12}
    report = {
        "clips": {"a_very_long_clip_name_from_some_mocap_set_01.bvh": metrics,
                  "walk.bvh": {**metrics, "longest_run_s": 25.0}},
        "overall": {**metrics, "longest_run_s": 25.0},
    }  # fmt: skip
    console = Console(width=120, record=True)
    console.print(table(report))
    text = console.export_text()
    assert max(len(line) for line in text.splitlines()) <= 120
    assert "…ocap_set_01.bvh" in text  # the end of a long name, which tells clips apart
    rows = {line.split()[0]: line for line in text.splitlines() if line.strip()}
    assert "<20s" in rows["…ocap_set_01.bvh"] and "<30s" in rows["…ocap_set_01.bvh"]
    assert "<20s" not in rows["walk.bvh"] and "<30s" in rows["walk.bvh"]
    assert "…" not in "".join(text.splitlines()[1:3])  # no header is cut


def test_the_scene_table_fits_120_columns_too() -> None:
    from rich.console import Console

    from retarget.cli.eval_cmd import COLUMNS, table

    metrics = {key: 123.456 for key, _, _ in COLUMNS} | {"runs": 1000}
    report = {"clips": {"sit_down_on_the_couch_07": metrics}, "overall": metrics}
    console = Console(width=120, record=True)
    console.print(table(report))
    text = console.export_text()
    assert max(len(line) for line in text.splitlines()) <= 120
    assert "…" not in "".join(text.splitlines()[1:3]) and "box" in text


def test_limb_errors_are_reported_for_hands_and_feet() -> None:
    env = RetargetEnv(Human(), [idle_clip(2.0)], options=EnvOptions(num_envs=2))
    report = evaluate(env, lambda obs: torch.zeros(2, env.action_dim),
                      EvalSettings(every=20, max_seconds=0.5))  # fmt: skip
    overall = report["overall"]
    assert 0.0 <= overall["feet_cm"] < 30.0 and 0.0 <= overall["controller_cm"] < 60.0
    assert list(overall).index("feet_cm") == list(overall).index("controller_cm") + 1
    # the human character holds its hands at the controllers of the clip it stands in
    assert 0.0 < overall["hands_to_controllers_cm"] < 60.0
    assert 0.0 < overall["head_to_headset_cm"] < 60.0
