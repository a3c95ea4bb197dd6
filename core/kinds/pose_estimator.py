"""What a kinematic method hands ``retarget eval``: the pose-estimator protocol.

An algorithm that outputs a body instead of actions returns one of these from
``pose_estimator()`` (the ``PoseEstimating`` capability); the evaluator places the character
in its estimate (:mod:`retarget.eval.kinematic`). It lives with the plugin kinds because it
is part of the algorithm contract, so the contract knows nothing of the evaluator built on it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

if TYPE_CHECKING:
    import torch


@runtime_checkable
class PoseEstimator(Protocol):
    """Estimates the body at rows of the environment's motion library.

    ``estimate_rows(rows)`` returns ``(pose, frame)``: ``pose`` has ``root_pos`` (R, 3),
    ``matrices`` (R, J, 3, 3) joint rotations on the canonical skeleton and
    ``contact_logits`` (R, 2), all in the headset's yaw frame; ``frame`` has ``points_out``
    (headset frame -> world) and ``yaw`` (R, 4) wxyz. Causal: only the devices up to each row.
    """

    def estimate_rows(self, rows: torch.Tensor) -> tuple[Any, Any]: ...
