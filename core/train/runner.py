"""The training loop behind ``retarget train``: iterate, log, checkpoint, stop, resume.

Stopping is cooperative: Ctrl-C (SIGINT) or SIGTERM sets a flag that the loop checks after
each iteration, so the checkpoint written on the way out is of a complete iteration. A second
Ctrl-C aborts at once. Checkpoints are written atomically (temp file, fsync, rename), so a run
killed mid-write keeps its previous checkpoint.

Under torchrun every rank runs this loop in step with the others: stopping (budget, Ctrl-C, a
non-finite statistic) is decided together, environment steps are counted over all ranks, and
rank 0 writes the checkpoint holding every rank's state (its own at the top level, so eval,
play and export read a distributed run like any other; the others under ``ranks``).
"""

from __future__ import annotations

import os
import random
import signal
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import FrameType, MappingProxyType
from typing import Any

import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.errors import RecipeError, SimulationError
from retarget.kinds import Algorithm, Callback
from retarget.kinds.capabilities import DataParallel, require
from retarget.kinds.iteration import RL_HEADLINE, IterationResult, as_result
from retarget.recipe import ResolvedRecipe, write_lock
from retarget.registry import Registry
from retarget.train.checkpoint import load_checkpoint, save_checkpoint
from retarget.train.distributed import SINGLE, Comm
from retarget.train.logger import MetricsLogger
from retarget.train.run_dir import CHECKPOINTS, RunLock
from retarget.train.silent_terms import CHECK_AFTER_ITERATIONS, silent_kernels


class CallbackWarning(UserWarning):
    """A training callback failed and was switched off."""


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


def _with_sizes(
    resolved: ResolvedRecipe, num_envs: int | None, threads: int | None
) -> ResolvedRecipe:
    """``resolved`` with the environment count and physics threads a trainer was given, so the
    locked recipe builds the same env again on resume."""
    recipe, update = resolved.recipe, {}
    if num_envs is not None:
        update["env"] = recipe.env.model_copy(update={"num_envs": num_envs})
    if threads is not None:
        update["sim"] = recipe.sim.model_copy(update={"threads": threads})
    return replace(resolved, recipe=recipe.model_copy(update=update)) if update else resolved


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
        comm: Comm = SINGLE,
    ) -> None:
        if "algorithm" not in resolved.components:
            raise RecipeError(
                "training needs an algorithm",
                file=resolved.source.path,
                field="algorithm",
                hint="add `algorithm: ppo` to the recipe or pass --algorithm ppo",
            )
        resolved = _with_sizes(resolved, num_envs, threads)  # the lock records what runs
        self.resolved, self.run, self.comm = resolved, run, comm
        algorithm = resolved.component("algorithm").instantiate()
        assert isinstance(algorithm, Algorithm)
        if comm.distributed and not isinstance(algorithm, DataParallel):
            raise RecipeError(
                f"algorithm '{algorithm.name}' does not train data-parallel",
                file=resolved.source.path,
                field="algorithm",
                hint="run it as one process (without torchrun), or use ppo or dagger",
            )
        # one writer per run directory: rank 0 of a distributed run
        self._lock = RunLock(run).acquire() if comm.main else None
        self.checkpoint_every = checkpoint_every
        seed = resolved.recipe.seed + comm.rank  # each rank its own episodes and noise
        generator = seed_everything(seed)
        if threads is None and comm.local_size > 1 and resolved.recipe.sim.threads == 0:
            threads = max(1, (os.cpu_count() or 1) // comm.local_size)  # share the cores
        self.env = env_from_recipe(
            resolved, num_envs=num_envs, threads=threads, registry=registry, seed=seed
        )
        self.algorithm = algorithm
        algorithm.comm = comm
        if registry is not None:
            self.algorithm.connect(registry)
        self.algorithm.setup(self.env, generator)
        self.progress = Progress()
        self.headline: tuple[str, ...] = RL_HEADLINE
        """The progress bar's figures, as the last iteration named them."""
        self.logger = MetricsLogger(run, tensorboard=tensorboard) if comm.main else None
        if comm.main:
            write_lock(resolved, run)
        self._stop_requests = 0
        self._saving = False
        self.callbacks: list[Callback] = (
            [c.instantiate() for c in resolved.of_kind("callback")] if comm.main else []
        )  # fmt: skip

    # ------------------------------------------------------------------ callbacks

    def _notify(self, event: str, *args: Any) -> None:
        """Tell every callback of ``event``; one that raises is warned about by name and
        switched off (a logger that fails never stops the training)."""
        for cb in list(self.callbacks):
            try:
                getattr(cb, event)(*args)
            except Exception as exc:
                self.callbacks.remove(cb)
                warnings.warn(f"callback '{cb.name}' raised in {event} ({type(exc).__name__}: "
                              f"{exc}); it is switched off for the rest of this run",
                              CallbackWarning, stacklevel=2)  # fmt: skip

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
        """Write the checkpoint of this iteration (every rank takes part; rank 0 writes)."""
        path = self.run / CHECKPOINTS / f"ckpt-{self.progress.iteration:07d}.pt"
        states = self.comm.gather(self.state())
        if states is not None:
            state = states[0]
            if len(states) > 1:
                state["world_size"] = len(states)
                state["ranks"] = [{k: s[k] for k in ("algorithm", "env", "rng")}
                                  for s in states[1:]]  # fmt: skip
            save_checkpoint(path, state)
            self._notify("on_checkpoint", path, self.progress.iteration)
        self.comm.barrier()  # no rank runs ahead of a checkpoint still being written
        return path

    def restore(self, path: Path) -> None:
        """Continue from ``path``. A rank the checkpoint holds state for takes it up exactly;
        one it does not (more ranks than it was saved with) takes rank 0's weights and
        statistics, and keeps its own fresh environments and randomness."""
        state = load_checkpoint(path)
        rank = self.comm.rank
        ranks = state.get("ranks", [])
        own = state if rank == 0 else (ranks[rank - 1] if rank <= len(ranks) else None)
        self.progress = Progress(**state["progress"])
        if self.logger is not None:
            self.logger.drop_after(self.progress.iteration)
        if own is None:
            self.algorithm.load_state_dict(state["algorithm"])
            rank_seed = self.resolved.recipe.seed + rank
            require(self.algorithm, DataParallel).fresh_rank(
                torch.Generator().manual_seed(rank_seed)
            )
            return
        self.algorithm.load_state_dict(own["algorithm"])
        self.env.load_state_dict(own["env"])
        torch.set_rng_state(own["rng"]["torch"])
        np.random.set_state(own["rng"]["numpy"])
        random.setstate(own["rng"]["python"])

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

    def _check_finite(self, result: IterationResult) -> None:
        """Stop at the first non-finite statistic (a loss, a return): running on would only
        overwrite good checkpoints with NaN weights. Every rank stops when one sees it."""
        bad = list(result.non_finite().items())
        if self.comm.any(bool(bad)):
            what = f"{bad[0][0]} = {bad[0][1]}" if bad else "on another rank"
            raise SimulationError(
                f"training went non-finite at iteration {self.progress.iteration + 1}: {what}",
                file=str(self.run),
                hint="the checkpoints written so far are intact; resume from the last one "
                "with a lower learning rate, or check the reward terms",
            )

    def _report_silent_terms(self) -> None:
        """Name, once per process, the reward kernels that averaged about zero so far: a
        reinforcement learner gets no gradient from them (:mod:`retarget.train.silent_terms`)."""
        manager = getattr(self.env, "rewards", None)
        if manager is None or not self.algorithm.learns_from_reward or not self.comm.main:
            return
        lines = silent_kernels(manager.terms, manager.mean_values())
        if lines:
            print("reward terms that give no learning signal here:\n  " + "\n  ".join(lines),
                  file=sys.stderr, flush=True)

    def train(self, budget: Budget, on_iteration: Callable[[Progress], None] | None = None) -> Path:
        """Run until the budget is spent or a stop is requested; returns the last checkpoint."""
        self.stop_reason = "budget"
        previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        for sig in previous:
            signal.signal(sig, self._request_stop)
        last, saved_at = None, -1
        if self.callbacks:
            recipe = self.resolved.recipe.model_dump(mode="json")
            self._notify("on_train_start", self.run, recipe, self.progress.iteration > 0)
        ended = "error"
        try:
            if self.env.device_noise is not None:  # training alone sees the devices' noise
                self.env.device_noise.active = True
            start = time.perf_counter() - self.progress.elapsed
            first_iteration = self.progress.iteration
            while not self.comm.any(budget.done(self.progress.env_steps, self.progress.elapsed)):
                before = self.env.total_steps
                ends_before = self.env.termination_counts
                assist = self.env.root_assist
                if assist is not None:  # training alone gets the annealed root assist
                    assist.scale = assist.options.scale_at(self.progress.env_steps)
                result = as_result(self.algorithm.train_iteration(self.env))
                self._check_finite(result)
                self.headline = result.headline
                stats = dict(result.stats)
                if assist is not None:
                    stats["root_assist"] = assist.scale
                if self.env.curriculum is not None:
                    stats["curriculum_hard_share"] = self.env.curriculum.hard_share()
                stats.update(self._termination_shares(ends_before))
                p = self.progress
                p.iteration += 1
                if p.iteration - first_iteration == CHECK_AFTER_ITERATIONS:
                    self._report_silent_terms()
                stepped = self.env.total_steps - before
                # an algorithm that learns from the library without stepping (a pose
                # estimator) reports the samples it used instead
                local = stepped if stepped else int(result.samples or 0)
                p.env_steps += int(self.comm.total(local))
                p.elapsed = time.perf_counter() - start
                p.last = {k: float(v) for k, v in stats.items()}
                p.last["steps_per_s_total"] = p.env_steps / max(p.elapsed, 1e-9)
                if self.logger is not None:
                    self.logger.log(
                        p.env_steps, {"iteration": p.iteration, "elapsed_s": p.elapsed, **p.last}
                    )
                if self.callbacks:
                    self._notify("on_iteration", p.iteration, p.env_steps,
                                 MappingProxyType(dict(p.last, elapsed_s=p.elapsed)))
                if on_iteration is not None:
                    on_iteration(p)
                if self.comm.any(bool(self._stop_requests)):
                    if not self._stop_requests:
                        self.stop_reason = "interrupted"  # another rank was asked to stop
                    break
                if p.iteration % self.checkpoint_every == 0:
                    last = self._save_uninterrupted()
                    saved_at = p.iteration
            if last is None or saved_at != self.progress.iteration:  # never the same one twice
                last = self._save_uninterrupted()
            ended = self.stop_reason
        finally:
            if self.env.device_noise is not None:  # whatever uses this env next sees no noise
                self.env.device_noise.active = False
            self._notify("on_train_end", ended, last)
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            if self.logger is not None:
                self.logger.close()
            if self._lock is not None:
                self._lock.release()
        return last
