"""Episode bookkeeping shared by the learners: running return and length per environment,
and a window of finished episodes for the progress statistics.

Its checkpoint entries are flat keys of the learner's own state (``episode_return``,
``episode_length``, ``finished_returns``, ``finished_lengths``), so checkpoints written before
this class existed still load.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from typing import Any

import torch


class EpisodeTracker:
    """Per-environment running sums and the last ``window`` finished episodes."""

    def __init__(self, num_envs: int, window: int) -> None:
        self.num_envs = num_envs
        self.episode_return = torch.zeros(num_envs)
        self.episode_length = torch.zeros(num_envs, dtype=torch.long)
        self.finished_returns: deque[float] = deque(maxlen=window)
        self.finished_lengths: deque[float] = deque(maxlen=window)
        self._pending: list[tuple[torch.Tensor, torch.Tensor]] = []

    def step(self, reward: torch.Tensor, done: torch.Tensor) -> None:
        """Add one step's rewards; environments that are ``done`` finish their episode."""
        self.episode_return += reward
        self.episode_length += 1
        if done.any():
            self._pending.append((self.episode_return[done].clone(),
                                  self.episode_length[done].clone()))  # fmt: skip
            self.episode_return[done] = 0.0
            self.episode_length[done] = 0

    def end_rollout(self) -> int:
        """Move the episodes finished since the last call into the window; how many."""
        if not self._pending:
            return 0
        returns = torch.cat([r for r, _ in self._pending])
        self.finished_returns.extend(returns.tolist())
        self.finished_lengths.extend(torch.cat([n for _, n in self._pending]).float().tolist())
        self._pending.clear()
        return int(returns.numel())

    def stats(self) -> dict[str, float]:
        """Mean return and length of the window (empty before any episode finished)."""
        if not self.finished_returns:
            return {}
        return {
            "episode_return": sum(self.finished_returns) / len(self.finished_returns),
            "episode_length": sum(self.finished_lengths) / len(self.finished_lengths),
        }

    def state_dict(self) -> dict[str, Any]:
        return {
            "episode_return": self.episode_return.clone(),
            "episode_length": self.episode_length.clone(),
            "finished_returns": list(self.finished_returns),
            "finished_lengths": list(self.finished_lengths),
        }

    def load_state_dict(self, state: Mapping[str, Any]) -> bool:
        """Restore; False when the checkpoint had another environment count (then only the
        finished-episode window is taken: evaluation with fewer environments)."""
        same = state["episode_return"].shape[0] == self.num_envs
        if same:
            self.episode_return = state["episode_return"].clone()
            self.episode_length = state["episode_length"].clone()
        self.finished_returns.clear()
        self.finished_returns.extend(state["finished_returns"])
        self.finished_lengths.clear()
        self.finished_lengths.extend(state["finished_lengths"])
        return same


def clone_obs(obs: Mapping[str, torch.Tensor] | None) -> dict[str, torch.Tensor] | None:
    """A copy of an observation mapping (checkpoints keep the last one), or None."""
    return None if obs is None else {k: v.clone() for k, v in obs.items()}
