"""PPO with collection and update overlapped: the update on one rollout runs in a thread
while the environments collect the next one (``algorithm.overlap: true``).

On a CPU the two halves of an iteration use the cores differently: MuJoCo's physics spreads
over every thread it is given, but the rest of an environment step (reference lookup,
sensors, rewards, many small torch calls) runs on one core, and the update waits for all of
it. Run side by side, the update's matrix products fill the core the environment's Python
leaves idle: 1,470-1,500 instead of 1,300 env steps/s for the human on 2 cores.

The price is one update of policy lag: the rollout collected during update ``k`` comes from
the weights before it (a frozen acting copy), so update ``k+1`` starts one step away from the
policy that collected its data. Clipping the ratio around that stale behaviour policy, as
plain PPO would, learned clearly less per sample (return 60 against 68 after 400 k steps);
the update therefore uses the decoupled objective (``PPOLearner.update(proximal=True)``:
clipped around the policy the update starts from, importance-weighted to the behaviour
policy), which brought it to 65 (``benchmarks/results/scale_2026-12-02.md``). On few cores
two torchrun ranks are still the faster way to a given return; this stays an option.

Statistics stay exact: observation and return statistics of a rollout are merged after the
concurrent update, and the update's minibatch order draws from its own generator, so a run
repeats bit for bit and a resume continues the pipeline (the rollout waiting for its update
is in the checkpoint).
"""

from __future__ import annotations

import copy
import threading
import time
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import torch

from retarget.learn.storage import RolloutStorage
from retarget.learn.threads import torch_threads

if TYPE_CHECKING:
    from retarget.kinds import VecEnv

_SAVED = ("actions", "log_probs", "values", "advantages", "returns")
"""What an update reads from a rollout (with the observations)."""


class OverlapState:
    """The pipeline of one overlapped PPO run: the rollout awaiting its update, the buffer
    the next one is collected into, the acting copy of the networks, the update's generator."""

    def __init__(self, learner: Any) -> None:
        """``learner``: the :class:`~retarget.learn.ppo.PPOLearner` that owns this pipeline
        (not named as a type: ``ppo`` imports this module, and this one stays below it)."""
        self.learner = ppo = learner
        self.spare = self._new_storage()
        self.ready: RolloutStorage | None = None
        seed = torch.randint(0, 2**62, (1,), generator=ppo.generator).item()
        self.generator = torch.Generator().manual_seed(int(seed))
        self.nets: Any = None

    def _new_storage(self) -> RolloutStorage:
        ppo = self.learner
        dims = {k: v.shape[-1] for k, v in ppo.storage.obs.items()}
        return RolloutStorage(ppo.config.rollout_steps, ppo.num_envs, dims, ppo.action_dim)

    def _sync_nets(self) -> None:
        """The acting copy takes the learner's current weights and statistics."""
        ppo = self.learner
        if self.nets is None:
            self.nets = SimpleNamespace(
                actor=copy.deepcopy(ppo.actor), critic=copy.deepcopy(ppo.critic),
                obs_norm=copy.deepcopy(ppo.obs_norm), value_norm=copy.deepcopy(ppo.value_norm),
            )  # fmt: skip
            return
        for name in ("actor", "critic", "obs_norm", "value_norm"):
            getattr(self.nets, name).load_state_dict(getattr(ppo, name).state_dict())

    def iteration(self, env: VecEnv) -> dict[str, float]:
        """Update on the waiting rollout while collecting the next; the first iteration of a
        run (or of a resume without a waiting rollout) collects one to start with."""

        ppo, c = self.learner, self.learner.config
        samples = c.rollout_steps * ppo.num_envs
        t0 = time.perf_counter()
        if self.ready is None:
            with torch_threads(c.collect_threads):
                ppo.collect(env, storage=ppo.storage)
            self.ready = ppo.storage
        start = time.perf_counter()
        self._sync_nets()
        explained = _explained_variance(self.ready)
        result: dict[str, Any] = {}

        def learn() -> None:
            try:
                t = time.perf_counter()
                result["stats"] = ppo.update(self.ready, self.generator, proximal=True)
                result["seconds"] = time.perf_counter() - t
            except BaseException as exc:  # re-raised in the caller's thread
                result["error"] = exc

        with torch_threads(1):  # one torch thread beside the physics threads
            worker = threading.Thread(target=learn, name="ppo-update", daemon=True)
            worker.start()
            t1 = time.perf_counter()
            stats = ppo.collect(env, nets=self.nets, storage=self.spare, absorb=False)
            t2 = time.perf_counter()
            worker.join()
        if "error" in result:
            raise result["error"]
        ppo.absorb()  # the new rollout's statistics, now that the update is done
        stats.update(result["stats"])
        self.ready, self.spare = self.spare, self.ready
        ppo.iteration += 1
        ppo.env_steps += samples
        stats["explained_variance"] = explained
        stats["action_std"] = float(ppo.actor.std().mean())
        stats["collect_steps_per_s"] = samples / max(t2 - t1, 1e-9)
        stats["update_samples_per_s"] = samples / max(result["seconds"], 1e-9)
        stats["collect_seconds"] = t2 - t1
        stats["update_seconds"] = result["seconds"]
        stats["overlap_wait_seconds"] = time.perf_counter() - t2  # the update outlasting it
        stats["startup_seconds"] = start - t0
        stats.update(ppo.episodes.stats())
        return stats

    # ------------------------------------------------------------------ checkpoints

    def state_dict(self) -> dict[str, Any]:
        ready = self.ready
        saved = None
        if ready is not None:
            saved = {k: getattr(ready, k).clone() for k in _SAVED}
            saved["obs"] = {k: v.clone() for k, v in ready.obs.items()}
        return {"ready": saved, "generator": self.generator.get_state()}

    def load_state_dict(self, state: dict[str, Any] | None) -> None:
        """Restore the pipeline; a rollout of another shape (another environment count) is
        dropped and the next iteration collects a fresh one."""
        self.nets = None
        self.ready = None
        if not state:
            return
        self.generator.set_state(state["generator"])
        saved = state.get("ready")
        ppo = self.learner
        if saved is None or saved["actions"].shape != ppo.storage.actions.shape:
            return
        for k in _SAVED:
            getattr(ppo.storage, k).copy_(saved[k])
        for k, v in saved["obs"].items():
            ppo.storage.obs[k].copy_(v)
        self.ready = ppo.storage
        if self.spare is ppo.storage:  # the buffers swap every iteration
            self.spare = self._new_storage()


def _explained_variance(storage: RolloutStorage) -> float:
    returns, values = storage.returns, storage.values
    var = float(returns.var())
    return float(1.0 - (returns - values).var() / var) if var > 1e-12 else 0.0
