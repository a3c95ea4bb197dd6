"""The training loop behind ``retarget train``: iterate, log, checkpoint, stop, resume.

Stopping is cooperative: Ctrl-C (SIGINT) or SIGTERM sets a flag that the loop checks after
each iteration, so the checkpoint written on the way out is of a complete iteration. A second
Ctrl-C aborts at once. Checkpoints are written atomically (temp file, fsync, rename), so a run
killed mid-write keeps its previous checkpoint.
"""

from __future__ import annotations

import math
import random
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.errors import RecipeError, SimulationError
from retarget.kinds import Algorithm
from retarget.recipe import ResolvedRecipe, write_lock
from retarget.registry import Registry
from retarget.train.checkpoint import load_checkpoint, save_checkpoint
from retarget.train.logger import MetricsLogger
from retarget.train.run_dir import CHECKPOINTS, RunLock


@dataclass
class Budget:
    """When to stop: total environment steps and/or wall-clock minutes (None: no bound)."""

    steps: int | None = None
    minutes: float | None = None

    def done(self, env_steps: int, elapsed: float) -> bool:
        if self.steps is not None and env_steps >= self.steps:
            return True
        return self.minutes is not None and elapsed >= 60.0 * self.minutes


@dataclass
class Progress:
    """Counters that survive a resume."""

    iteration: int = 0
    env_steps: int = 0
    elapsed: float = 0.0
    last: dict[str, float] = field(default_factory=dict)


def seed_everything(seed: int) -> torch.Generator:
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch.manual_seed(seed)
    return torch.Generator().manual_seed(seed)


class Trainer:
    """Owns the env, the algorithm, the logger and the run directory of one training run."""

    def __init__(
        self,
        resolved: ResolvedRecipe,
        run: Path,
        *,
        num_envs: int | None = None,
        threads: int | None = None,
        checkpoint_every: int = 10,
        tensorboard: bool = True,
        registry: Registry | None = None,
    ) -> None:
        if "algorithm" not in resolved.components:
            raise RecipeError(
                "training needs an algorithm",
                file=resolved.source.path,
                field="algorithm",
                hint="add `algorithm: ppo` to the recipe or pass --algorithm ppo",
            )
        self.resolved, self.run = resolved, run
        self._lock = RunLock(run).acquire()  # one writer per run directory
        self.checkpoint_every = checkpoint_every
        generator = seed_everything(resolved.recipe.seed)
        self.env = env_from_recipe(
            resolved, num_envs=num_envs, threads=threads, registry=registry
        )
        algorithm = resolved.component("algorithm").instantiate()
        assert isinstance(algorithm, Algorithm)
        self.algorithm = algorithm
        if registry is not None:
            self.algorithm.connect(registry)
        self.algorithm.setup(self.env, generator)
        self.progress = Progress()
        self.logger = MetricsLogger(run, tensorboard=tensorboard)
        write_lock(resolved, run)
        self._stop_requests = 0
        self._saving = False

    # ------------------------------------------------------------------ checkpoints

    def state(self) -> dict[str, Any]:
        return {
            "algorithm": self.algorithm.state_dict(),
            "env": self.env.state_dict(),
            "progress": vars(self.progress).copy(),
            "rng": {
                "torch": torch.get_rng_state(),
                "numpy": np.random.get_state(),
                "python": random.getstate(),
            },
        }

    def _save_uninterrupted(self) -> Path:
        """:meth:`save` with Ctrl-C/SIGTERM deferred: a stop pressed while the file is written
        is honoured after it, so the last checkpoint is never the one that gets lost."""
        self._saving = True
        try:
            return self.save()
        finally:
            self._saving = False

    def save(self) -> Path:
        path = self.run / CHECKPOINTS / f"ckpt-{self.progress.iteration:07d}.pt"
        save_checkpoint(path, self.state())
        return path

    def restore(self, path: Path) -> None:
        state = load_checkpoint(path)
        self.algorithm.load_state_dict(state["algorithm"])
        self.env.load_state_dict(state["env"])
        self.progress = Progress(**state["progress"])
        self.logger.drop_after(self.progress.iteration)
        torch.set_rng_state(state["rng"]["torch"])
        np.random.set_state(state["rng"]["numpy"])
        random.setstate(state["rng"]["python"])

    # ------------------------------------------------------------------ loop

    def _termination_shares(self, before: dict[str, int]) -> dict[str, float]:
        """Which termination ended the episodes of the last iteration (share of each)."""
        after = self.env.termination_counts
        delta = {name: after[name] - before.get(name, 0) for name in after}
        total = sum(delta.values())
        return {f"end_{k}": v / total for k, v in delta.items()} if total else {}

    def _request_stop(self, signum: int, frame: FrameType | None) -> None:
        self._stop_requests += 1
        if self._saving:  # a checkpoint being written is finished first, whatever is pressed
            print("\nwriting the checkpoint; it is finished first", file=sys.stderr, flush=True)
            return
        if self._stop_requests > 1:
            raise KeyboardInterrupt
        self.stop_reason = "interrupted"
        print("\nstopping after this iteration (a checkpoint is written; Ctrl-C again aborts)",
              file=sys.stderr, flush=True)  # fmt: skip

    def _check_finite(self, stats: dict[str, float]) -> None:
        """Stop at the first non-finite statistic (a loss, a return): running on would only
        overwrite good checkpoints with NaN weights."""
        for key, value in stats.items():
            if not math.isfinite(float(value)):
                raise SimulationError(
                    f"training went non-finite at iteration {self.progress.iteration + 1}: "
                    f"{key} = {value}",
                    file=str(self.run),
                    hint="the checkpoints written so far are intact; resume from the last one "
                    "with a lower learning rate, or check the reward terms",
                )

    def train(self, budget: Budget, on_iteration: Callable[[Progress], None] | None = None) -> Path:
        """Run until the budget is spent or a stop is requested; returns the last checkpoint."""
        self.stop_reason = "budget"
        previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        for sig in previous:
            signal.signal(sig, self._request_stop)
        last = None
        try:
            start = time.perf_counter() - self.progress.elapsed
            while not budget.done(self.progress.env_steps, self.progress.elapsed):
                before = self.env.total_steps
                ends_before = self.env.termination_counts
                stats = self.algorithm.train_iteration(self.env)
                self._check_finite(stats)
                stats.update(self._termination_shares(ends_before))
                p = self.progress
                p.iteration += 1
                stepped = self.env.total_steps - before
                # an algorithm that learns from the library without stepping (a pose
                # estimator) reports the samples it used instead
                p.env_steps += stepped if stepped else int(stats.pop("samples", 0))
                p.elapsed = time.perf_counter() - start
                p.last = {k: float(v) for k, v in stats.items()}
                p.last["steps_per_s_total"] = p.env_steps / max(p.elapsed, 1e-9)
                self.logger.log(
                    p.env_steps, {"iteration": p.iteration, "elapsed_s": p.elapsed, **p.last}
                )
                if on_iteration is not None:
                    on_iteration(p)
                if self._stop_requests:
                    break
                if p.iteration % self.checkpoint_every == 0:
                    last = self._save_uninterrupted()
            last = self._save_uninterrupted()
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            self.logger.close()
            self._lock.release()
        return last
