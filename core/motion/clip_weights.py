"""How often each clip is drawn in training, from shell patterns on its file name.

A corpus is rarely balanced the way a policy needs it: 2.5 hours of Bandai Namco motion has as
many gestures as runs, and the fastest runs are where a tracker falls behind. ``motions.weights``
(``{'*_run_*': 3}``) makes the clips whose file name matches a pattern that many times as
likely to start an episode (a clip matching several patterns takes their product; one matching
none keeps 1). Episodes still start on every clip, so nothing is forgotten outright, and the
failure curriculum's uniform share follows the same weights.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from retarget.motion.clip import MotionClip
from retarget.motion.sources import name_matches


def clip_file_name(clip: MotionClip) -> str:
    """The name patterns are matched against: the clip's file name (its start and stop
    variants keep their file's), else the clip's own name."""
    return clip.source.name if clip.source is not None else clip.name


def clip_weights(clips: Sequence[MotionClip], weights: Mapping[str, float]) -> list[float]:
    """One sampling weight per clip. Raises ``ValueError`` naming a pattern that matches no
    clip (a misspelt pattern would otherwise change nothing, silently) and when every clip
    ends up at weight 0."""
    names = [clip_file_name(c) for c in clips]
    out = [1.0] * len(clips)
    for pattern, weight in weights.items():
        hits = [i for i, n in enumerate(names) if name_matches(n, (pattern,))]
        if not hits:
            raise ValueError(f"motions.weights: pattern {pattern!r} matches none of the "
                             f"{len(clips)} clips' file names")  # fmt: skip
        for i in hits:
            out[i] *= float(weight)
    if not any(w > 0 for w in out):
        raise ValueError("motions.weights: every clip has weight 0")
    return out
