"""Training callbacks in a real run: the events logger writes every event as strict JSON, and
a callback that raises is switched off with a warning naming it while training finishes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import TINY

import retarget
from retarget.recipe import load
from retarget.registry import Entry, Registry
from retarget.registry.loader import load_plugins
from retarget.train.run_dir import new_run_dir
from retarget.train.runner import Budget, CallbackWarning, Trainer

SAMPLES = 4 * 8  # num_envs x rollout_steps of the tiny recipe


class Broken(retarget.Callback):
    """Raises on every iteration (a logging service that is down)."""

    name = "broken_logger"
    calls = 0

    def on_iteration(self, iteration, env_steps, stats) -> None:
        Broken.calls += 1
        raise ConnectionError("service unreachable")


def _registry() -> Registry:
    registry = load_plugins()
    registry.add(Entry(kind="callback", name="broken_logger", cls=Broken, plugin="tests",
                       distribution="tests", version="0"))  # fmt: skip
    return registry


def test_events_log_and_a_failing_callback(tmp_path: Path) -> None:
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY + "callbacks: [events, broken_logger]\n")
    registry = _registry()
    resolved = load(str(recipe), registry, shorthands={}, assignments=[])
    run = new_run_dir(tmp_path / "runs", "cb")
    t = Trainer(resolved, run, checkpoint_every=2, tensorboard=False, registry=registry)
    with pytest.warns(CallbackWarning, match="broken_logger.*on_iteration.*unreachable"):
        last = t.train(Budget(steps=3 * SAMPLES))
    assert Broken.calls == 1  # switched off after its first failure
    assert last.exists() and t.progress.iteration == 3
    events = [json.loads(line) for line in (run / "events.jsonl").read_text().splitlines()]
    kinds = [e["event"] for e in events]
    assert kinds == ["start", "iteration", "iteration", "checkpoint", "iteration",
                     "checkpoint", "end"]  # fmt: skip
    assert events[0]["resumed"] is False and events[0]["recipe"]["character"]["type"]
    assert [e["iteration"] for e in events if e["event"] == "iteration"] == [1, 2, 3]
    assert events[-1] == {**events[-1], "reason": "budget", "last_checkpoint": str(last)}
    assert all(isinstance(v, float | None) for v in events[1]["stats"].values())
