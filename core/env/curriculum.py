"""Where episodes start: the motion sampled by recent failure, with a uniform share.

On a large corpus most frames are easy and a few (turns, stops, fast arm swings) are where the
policy falls; sampling start frames uniformly spends most samples on what it already does.
Like PHC's hard-sequence mining and BeyondMimic's adaptive bins, the library is cut into
segments of ``bin_seconds`` and each failure counts against the segment it happened in (and,
at half weight, the one before it, so episodes start a little ahead of the fall). Counts decay
with a half-life in environment steps, so a mastered segment fades. A start is drawn from the
failure counts with probability ``1 - uniform`` and frame-uniformly otherwise (the library's
clip weights apply), so every frame keeps being visited. All of it is index arithmetic on
``(S,)`` tensors: no loop per environment.
"""

from __future__ import annotations

import torch

from retarget.motion.library import MotionLibrary
from retarget.settings.env import CurriculumOptions


class FailureCurriculum:
    """Segment failure counts of one library and the start sampler they give."""

    def __init__(self, library: MotionLibrary, options: CurriculumOptions, num_envs: int) -> None:
        self.options = options
        bin_frames = max(1, round(options.bin_seconds * library.fps))
        counts = (library.length + bin_frames - 1) // bin_frames  # segments per clip
        self.clip_of = torch.repeat_interleave(torch.arange(library.num_clips), counts)
        first = torch.cumsum(counts, 0) - counts  # first segment of each clip
        index = torch.arange(len(self.clip_of)) - first[self.clip_of]
        self.first_frame = index * bin_frames
        self.frames = torch.minimum(library.length[self.clip_of] - self.first_frame,
                                    torch.tensor(bin_frames))  # fmt: skip
        self.first_segment = first
        self.length = library.length
        self.bin_frames = bin_frames
        clip_weight = library.weights / library.weights.sum()
        share = self.frames.double() / library.length[self.clip_of].double()
        self.uniform_p = clip_weight[self.clip_of] * share
        self.failures = torch.zeros(len(self.clip_of), dtype=torch.float64)
        self.decay = 0.5 ** (num_envs / options.half_life_steps)

    @property
    def num_segments(self) -> int:
        return int(self.clip_of.numel())

    def segment(self, clip: torch.Tensor, frame: torch.Tensor) -> torch.Tensor:
        return self.first_segment[clip] + frame // self.bin_frames

    def record(self, clip: torch.Tensor, frame: torch.Tensor, failed: torch.Tensor) -> None:
        """One control step: decay the counts, add this step's failures."""
        self.failures.mul_(self.decay)
        if not bool(failed.any()):
            return
        c, f = clip[failed], frame[failed]
        seg = self.segment(c, f)
        self.failures.index_add_(0, seg, torch.ones(seg.shape, dtype=torch.float64))
        earlier = f >= self.bin_frames  # the segment before, inside the same clip
        half = torch.full((int(earlier.sum()),), 0.5, dtype=torch.float64)
        self.failures.index_add_(0, seg[earlier] - 1, half)

    def probabilities(self) -> torch.Tensor:
        total = float(self.failures.sum())
        if total <= 0.0:
            return self.uniform_p
        u = self.options.uniform
        return u * self.uniform_p + (1.0 - u) * self.failures / total

    def sample(
        self, n: int, generator: torch.Generator, *, margin: int = 0
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """``n`` (clip, frame) starts: a segment by :meth:`probabilities`, then a frame in
        it, kept ``margin`` frames before its clip's end."""
        seg = torch.multinomial(self.probabilities(), n, replacement=True, generator=generator)
        u = torch.rand(n, generator=generator, dtype=torch.float64)
        inside = (u * self.frames[seg]).long().clamp(max=self.bin_frames - 1)
        frame = self.first_frame[seg] + inside
        clip = self.clip_of[seg]
        last = torch.clamp(self.length[clip] - 1 - margin, min=0)
        return clip, torch.minimum(frame, last)

    def hard_share(self, top: float = 0.1) -> float:
        """Share of the failure mass on the hardest ``top`` of segments (a log figure: 0.1 is
        failures spread evenly, near 1 is a few segments where all falls happen)."""
        total = float(self.failures.sum())
        if total <= 0.0:
            return 0.0
        k = max(1, int(top * self.num_segments))
        return float(torch.topk(self.failures, k).values.sum()) / total

    def state_dict(self) -> dict[str, torch.Tensor]:
        return {"failures": self.failures.clone()}

    def load_state_dict(self, state: dict) -> None:
        failures = state.get("failures")
        if failures is not None and failures.shape == self.failures.shape:
            self.failures = failures.clone().double()
