"""Behaviour cloning from a tracking expert (``retarget expert``): a policy learns the
expert's actions on the states the expert planned from.

The expert's states are replayed in the training environment itself, so the student sees
exactly the observations its sensors give there (headset, controllers, proprioception),
with no model of them: every environment is put into a recorded state
(:meth:`RetargetEnv.place_state`) and stepped with the expert's recorded actions, which
reproduce the recorded path (the physics is deterministic). Two kinds of windows are
replayed: pieces of the best path, and the beam's other members (the planner's own sampled
deviations around it, which show the student states off the best path and how the expert
got back). Each environment step is one supervised sample: far cheaper than a reward's.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import torch

from retarget.learn.config import DaggerConfig
from retarget.learn.dagger import DaggerLearner


class ExpertWindows:
    """Every replayable window of an expert directory, for one environment's library."""

    def __init__(self, clips: Sequence[Mapping[str, np.ndarray]], fields: Sequence[str]) -> None:
        self.clips = list(clips)
        self.fields = tuple(fields)
        self.frames = np.array([len(c["qpos"]) for c in self.clips])
        self.demos = np.array([len(c["demo_frame"]) for c in self.clips])

    def draw(self, n: int, rng: np.random.Generator, demo_share: float, length: int
             ) -> list[dict[str, Any]]:  # fmt: skip
        """``n`` windows: beam members with probability ``demo_share``, else best-path
        pieces of up to ``length`` steps starting at a uniform frame."""
        out = []
        weights = self.frames - 1
        has_demos = self.demos.sum() > 0
        for _ in range(n):  # a handful per step: the windows that ended
            if has_demos and rng.random() < demo_share:
                clip = int(rng.choice(len(self.clips), p=self.demos / self.demos.sum()))
                c, row = self.clips[clip], int(rng.integers(self.demos[clip]))
                steps = int(c["demo_steps"][row])
                out.append({
                    "clip": clip, "frame": int(c["demo_frame"][row]),
                    "qpos": c["demo_state_qpos"][row], "qvel": c["demo_state_qvel"][row],
                    "prev": c["demo_prev_action"][row], "actions": c["demo_actions"][row, :steps],
                })  # fmt: skip
                continue
            clip = int(rng.choice(len(self.clips), p=weights / weights.sum()))
            c = self.clips[clip]
            f = int(rng.integers(self.frames[clip] - 1))
            end = min(f + length, self.frames[clip] - 1)
            prev = c["actions"][f - 1] if f > 0 else np.zeros(c["actions"].shape[1])
            out.append({"clip": clip, "frame": f, "qpos": c["qpos"][f], "qvel": c["qvel"][f],
                        "prev": prev, "actions": c["actions"][f:end]})  # fmt: skip
        return out


class ExpertBCLearner(DaggerLearner):
    """DAgger's student network, normaliser, buffer and update, fed by expert replays instead
    of a teacher's labels (so a cloned student fine-tunes with PPO ``--init-from`` like a
    distilled one)."""

    def __init__(self, config: DaggerConfig, obs_dims: Mapping[str, int], action_dim: int,
                 num_envs: int, windows: ExpertWindows | None, demo_share: float,
                 generator: torch.Generator | None = None) -> None:  # fmt: skip
        super().__init__(config, obs_dims, action_dim, num_envs, generator)
        self.windows = windows
        self.demo_share = demo_share
        seed = int(torch.randint(0, 2**62, (1,), generator=self.generator).item())
        self.rng = np.random.default_rng(seed)
        self.cursor: list[dict[str, Any] | None] = [None] * num_envs
        self.teacher = torch.nn.Identity()  # labels come from the replay

    def _place(self, env: Any, ids: list[int]) -> None:
        if self.windows is None:
            raise RuntimeError("ExpertBCLearner.windows must be set before training")
        drawn = self.windows.draw(len(ids), self.rng, self.demo_share, self.config.rollout_steps)
        for i, w in zip(ids, drawn, strict=True):
            w["at"] = 0
            self.cursor[i] = w
        if not hasattr(env, "place_state"):  # a plain VecEnv: stepped from where it is
            return
        env.place_state(
            torch.tensor(ids),
            torch.tensor([w["clip"] for w in drawn]),
            torch.tensor([w["frame"] for w in drawn]),
            np.stack([w["qpos"] for w in drawn]),
            np.stack([w["qvel"] for w in drawn]),
            torch.from_numpy(np.stack([w["prev"] for w in drawn])).float(),
        )

    @torch.no_grad()
    def collect(self, env: Any) -> dict[str, float]:
        c = self.config
        key = self.actor_key
        pending_rows: list[torch.Tensor] = []
        gap = 0.0
        for _ in range(c.rollout_steps):
            stale = [i for i, w in enumerate(self.cursor)
                     if w is None or w["at"] >= len(w["actions"])]  # fmt: skip
            if stale:
                self._place(env, stale)
            if hasattr(env, "observe_now"):
                obs = env.observe_now([key])[key].float()
            else:
                if self.last_obs is None:
                    self.last_obs = {k: v.float() for k, v in env.reset().items()}
                obs = self.last_obs[key]
            label = torch.from_numpy(np.stack(
                [w["actions"][w["at"]] for w in self.cursor])).float()  # fmt: skip
            if int(self.obs_norm.groups[key].count) == 0:  # the first batch sets the scale
                self.obs_norm.update({key: obs})
            else:
                pending_rows.append(obs)
            gap += float((self.actor(self._normalized(obs)).clamp(-1, 1) - label).square().mean())
            self._store(obs, label)
            next_obs, reward, terminated, truncated, _ = env.step(label)
            self.last_obs = {k: v.float() for k, v in next_obs.items()}
            ended = (terminated.bool() | truncated.bool()).tolist()
            self.episodes.step(reward.float(), terminated.bool() | truncated.bool())
            for i, w in enumerate(self.cursor):
                w["at"] += 1
                if ended[i]:
                    self.cursor[i] = None
        if pending_rows:
            self.obs_norm.update({key: torch.cat(pending_rows)})
        return {"action_gap": gap / c.rollout_steps,
                "episodes_finished": float(self.episodes.end_rollout())}  # fmt: skip

    def fresh_rank(self, generator: torch.Generator) -> None:
        super().fresh_rank(generator)
        self.cursor = [None] * self.num_envs

    def state_dict(self) -> dict[str, Any]:
        state = super().state_dict()
        state["replay_rng"] = json.dumps(self.rng.bit_generator.state)  # 128-bit ints
        return state

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        super().load_state_dict(state)
        if "replay_rng" in state:
            self.rng.bit_generator.state = json.loads(state["replay_rng"])
        self.cursor = [None] * self.num_envs  # a resumed run starts new windows
