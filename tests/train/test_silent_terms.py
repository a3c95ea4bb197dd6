"""The trainer names reward kernels that sit at zero (no gradient), once, early in a run."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import TINY

from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.run_dir import new_run_dir
from retarget.train.runner import Budget, Trainer
from retarget.train.silent_terms import CHECK_AFTER_ITERATIONS, silent_kernels

SAMPLES = 4 * 8  # the tiny recipe's env steps per iteration


def _train(tmp_path: Path, joint_k: str, iterations: int) -> None:
    path = tmp_path / "recipe.yaml"
    path.write_text(TINY.replace("joint_pos: {weight: 4.0, k: 25.0}",
                                 f"joint_pos: {{weight: 4.0, k: {joint_k}}}"))
    resolved = load(str(path), load_plugins(), shorthands={}, assignments=[])
    trainer = Trainer(resolved, new_run_dir(tmp_path, "run"), checkpoint_every=100,
                      tensorboard=False)
    trainer.train(Budget(steps=iterations * SAMPLES))


def test_a_kernel_far_in_its_tail_is_named_with_its_average(tmp_path: Path, capsys) -> None:
    _train(tmp_path, "1.0e+6", CHECK_AFTER_ITERATIONS + 1)
    err = capsys.readouterr().err
    assert "rewards.joint_pos: averages 0.0000 (k=1e+06)" in err
    assert "`reduce: mean`" in err  # the joint term sums by default
    assert err.count("rewards.joint_pos") == 1  # once, not every iteration


def test_a_live_kernel_and_a_short_run_say_nothing(tmp_path: Path, capsys) -> None:
    _train(tmp_path, "1.0e-3", CHECK_AFTER_ITERATIONS)
    assert "rewards.joint_pos" not in capsys.readouterr().err
    _train(tmp_path, "1.0e+6", CHECK_AFTER_ITERATIONS - 1)  # not yet judged
    assert "no learning signal" not in capsys.readouterr().err


@pytest.mark.parametrize(("mean", "named"), [(0.009, True), (0.011, False)])
def test_the_threshold_and_non_kernel_terms(mean: float, named: bool) -> None:
    class Config:
        k = 2.0
        reduce = "mean"

    class Term:
        config = Config()

    class Penalty:
        config = object()  # no k: a fixed penalty, not a kernel

    lines = silent_kernels({"a": Term(), "fail": Penalty()}, {"a": mean, "fail": 0.0})
    assert bool(lines) is named
    assert not any("fail" in line for line in lines)
    if named:
        assert "`reduce: mean`" not in lines[0]  # already a mean: only a smaller k helps
