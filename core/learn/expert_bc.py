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

from retarget.kinds.tracking_env import TrackingEnv
from retarget.learn.config import DaggerConfig
from retarget.learn.dagger import DaggerLearner

FAILED_AT_M = 0.5
"""Mean body distance (m) from the reference at which PHC counts a frame failed: the expert's
path is cloned only up to its first such frame (after it, the planner tracks a fallen body)."""


def tracked_part(data: Mapping[str, np.ndarray], threshold: float = FAILED_AT_M
                 ) -> dict[str, np.ndarray]:  # fmt: skip
    """One planned clip cut before its first failed frame: path rows up to it, and the beam
    members whose segment ends before it. A clip without body positions is kept whole."""
    body, ref = data.get("body_pos"), data.get("ref_body_pos")
    frames = len(data["qpos"])
    if body is None or ref is None or body.shape != ref.shape or body.ndim != 3:
        return dict(data)
    over = np.flatnonzero(np.linalg.norm(body - ref, axis=-1).mean(-1) > threshold)
    cut = max(int(over[0]) if over.size else frames, 1)  # frames kept
    if cut == frames:
        return dict(data)
    out = dict(data)
    out["qpos"], out["qvel"] = data["qpos"][:cut], data["qvel"][:cut]
    out["actions"] = data["actions"][: cut - 1]
    keep = data["demo_frame"] + data["demo_steps"] <= cut - 1
    for key, arr in data.items():
        if key.startswith("demo_"):
            out[key] = arr[keep]
    return out


class ExpertWindows:
    """Every replayable window of an expert directory, for one environment's library.

    The clips are concatenated once into flat arrays, so drawing ``n`` windows is a few
    fancy-indexing operations whatever ``n`` is (no loop over windows or environments)."""

    def __init__(self, clips: Sequence[Mapping[str, np.ndarray]], fields: Sequence[str]) -> None:
        if not clips:
            raise ValueError("an expert needs at least one clip")
        self.fields = tuple(fields)
        self.frames = np.array([len(c["qpos"]) for c in clips])
        if (self.frames - 1).sum() < 1:
            raise ValueError("the expert's clips hold no tracked step (each failed at its "
                             "first frame)")
        self.demos = np.array([len(c["demo_frame"]) for c in clips])
        self.nu = int(clips[0]["actions"].shape[1])
        self.frame_start = np.concatenate([[0], np.cumsum(self.frames)[:-1]])
        self.action_start = np.concatenate([[0], np.cumsum(self.frames - 1)[:-1]])
        self.qpos = np.concatenate([c["qpos"] for c in clips])
        self.qvel = np.concatenate([c["qvel"] for c in clips])
        self.actions = np.concatenate([c["actions"] for c in clips]).astype(np.float32)
        self.path_p = (self.frames - 1) / max(int((self.frames - 1).sum()), 1)
        self.demo_clip = np.repeat(np.arange(len(clips)), self.demos)
        if self.demos.sum():
            cat = {k: np.concatenate([c[k] for c in clips if len(c["demo_frame"])])
                   for k in ("demo_frame", "demo_steps", "demo_state_qpos", "demo_state_qvel",
                             "demo_prev_action", "demo_actions")}  # fmt: skip
            self.demo = cat
        else:
            self.demo = {}

    def draw(self, n: int, rng: np.random.Generator, demo_share: float, length: int
             ) -> dict[str, np.ndarray]:  # fmt: skip
        """``n`` windows as arrays (``clip``, ``frame``, ``qpos``, ``qvel``, ``prev``,
        ``actions`` padded to ``width(length)`` steps, ``steps``): beam members with
        probability ``demo_share``, else best-path pieces of up to ``length`` steps
        starting at a uniform frame."""
        width = self.width(length)
        demo = (rng.random(n) < demo_share) if self.demo else np.zeros(n, dtype=bool)
        clip = rng.choice(len(self.frames), size=n, p=self.path_p)
        frame = (rng.random(n) * (self.frames[clip] - 1)).astype(np.int64)
        steps = np.minimum(length, self.frames[clip] - 1 - frame)
        at = self.action_start[clip] + frame
        qpos = self.qpos[self.frame_start[clip] + frame]
        qvel = self.qvel[self.frame_start[clip] + frame]
        prev = np.where((frame > 0)[:, None], self.actions[np.maximum(at - 1, 0)], 0.0)
        cols = np.arange(width)
        rows = np.minimum(at[:, None] + cols[None], len(self.actions) - 1)
        actions = np.where((cols[None] < steps[:, None])[..., None], self.actions[rows], 0.0)
        if demo.any():
            pick = rng.integers(len(self.demo_clip), size=int(demo.sum()))
            d = self.demo
            clip[demo] = self.demo_clip[pick]
            frame[demo] = d["demo_frame"][pick]
            steps[demo] = d["demo_steps"][pick]
            qpos[demo] = d["demo_state_qpos"][pick]
            qvel[demo] = d["demo_state_qvel"][pick]
            prev[demo] = d["demo_prev_action"][pick]
            seg = d["demo_actions"][pick]
            actions[demo] = 0.0
            actions[demo, : seg.shape[1]] = seg
        return {"clip": clip, "frame": frame, "qpos": qpos, "qvel": qvel,
                "prev": prev.astype(np.float32), "actions": actions.astype(np.float32),
                "steps": steps}  # fmt: skip

    def width(self, length: int) -> int:
        """Steps a drawn window can hold: the longer of a path piece and a beam segment."""
        return max(length, self.demo["demo_actions"].shape[1] if self.demo else 0, 1)


class ExpertBCLearner(DaggerLearner):
    """DAgger's student network, normaliser, buffer and update, fed by expert replays instead
    of a teacher's labels (so a cloned student fine-tunes with PPO ``--init-from`` like a
    distilled one)."""

    def __init__(self, config: DaggerConfig, obs_dims: Mapping[str, int], action_dim: int,
                 num_envs: int, windows: ExpertWindows | None, demo_share: float,
                 generator: torch.Generator | None = None, residual: slice | None = None
                 ) -> None:  # fmt: skip
        super().__init__(config, obs_dims, action_dim, num_envs, generator, residual=residual)
        self.windows = windows
        self.demo_share = demo_share
        seed = int(torch.randint(0, 2**62, (1,), generator=self.generator).item())
        self.rng = np.random.default_rng(seed)
        self._reset_cursor()
        self.teacher = torch.nn.Identity()  # labels come from the replay

    def _reset_cursor(self) -> None:
        """No window yet: every environment draws one at the next step."""
        self.window: np.ndarray | None = None  # (num_envs, width, nu) the replayed actions
        self.at = np.zeros(self.num_envs, dtype=np.int64)
        self.steps = np.zeros(self.num_envs, dtype=np.int64)

    def _place(self, env: Any, ids: np.ndarray) -> None:
        if self.windows is None:
            raise RuntimeError("ExpertBCLearner.windows must be set before training")
        drawn = self.windows.draw(len(ids), self.rng, self.demo_share, self.config.rollout_steps)
        if self.window is None:
            width = self.windows.width(self.config.rollout_steps)
            self.window = np.zeros((self.num_envs, width, self.windows.nu), np.float32)
        self.window[ids] = drawn["actions"]
        self.at[ids] = 0
        self.steps[ids] = drawn["steps"]
        if not isinstance(env, TrackingEnv):  # a plain VecEnv: stepped from where it is
            return
        env.place_state(torch.from_numpy(ids), torch.from_numpy(drawn["clip"]),
                        torch.from_numpy(drawn["frame"]), drawn["qpos"], drawn["qvel"],
                        torch.from_numpy(drawn["prev"]))  # fmt: skip

    @torch.no_grad()
    def collect(self, env: Any) -> dict[str, float]:
        c = self.config
        key = self.actor_key
        pending_rows: list[torch.Tensor] = []
        gap = 0.0
        envs = np.arange(self.num_envs)
        for _ in range(c.rollout_steps):
            stale = np.flatnonzero(self.at >= self.steps)
            if stale.size:
                self._place(env, stale)
            if isinstance(env, TrackingEnv):
                obs = env.observe_now([key])[key].float()
            else:
                if self.last_obs is None:
                    self.last_obs = {k: v.float() for k, v in env.reset().items()}
                obs = self.last_obs[key]
            assert self.window is not None
            label = torch.from_numpy(self.window[envs, self.at])
            if int(self.obs_norm.normalizer(key).count) == 0:  # the first batch sets the scale
                self.obs_norm.update({key: obs})
            else:
                pending_rows.append(obs)
            gap += float((self.mean(obs).clamp(-1, 1) - label).square().mean())
            self._store(obs, label)
            next_obs, reward, terminated, truncated, _ = env.step(label)
            self.last_obs = {k: v.float() for k, v in next_obs.items()}
            ended = (terminated.bool() | truncated.bool())
            self.episodes.step(reward.float(), ended)
            self.at += 1
            self.at[ended.numpy()] = self.steps[ended.numpy()]  # an ended episode: new window
        if pending_rows:
            self.obs_norm.update({key: torch.cat(pending_rows)})
        return {"action_gap": gap / c.rollout_steps,
                "episodes_finished": float(self.episodes.end_rollout())}  # fmt: skip

    def fresh_rank(self, generator: torch.Generator) -> None:
        super().fresh_rank(generator)
        self._reset_cursor()

    def state_dict(self) -> dict[str, Any]:
        state = super().state_dict()
        state["replay_rng"] = json.dumps(self.rng.bit_generator.state)  # 128-bit ints
        return state

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        super().load_state_dict(state)
        if "replay_rng" in state:
            self.rng.bit_generator.state = json.loads(state["replay_rng"])
        self._reset_cursor()  # a resumed run starts new windows
