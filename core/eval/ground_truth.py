"""Measuring against the true motion when the reference a policy follows was estimated.

In a two-stage tracker (KinPoly-v in SimXR's comparison) a pose estimator turns the devices
into a full body and a full-body imitator follows that estimate. The environment's reference
then *is* the estimate, so the metrics must read another one: the true motion, on the same
rows (the estimate has one frame per true frame). :class:`GroundTruth` swaps the reference of
each step context for the truth before the metric probe sees it; what the policy observed is
unchanged.
"""

from __future__ import annotations

from dataclasses import replace

import torch

from retarget.errors import RetargetError
from retarget.kinds.state import ReferenceBatch, StepContext


class GroundTruth:
    """The true reference of an env built from the same motions as the estimated one."""

    def __init__(self, truth_env, estimated_env) -> None:
        a, b = truth_env.library, estimated_env.library
        if a.num_clips != b.num_clips or not torch.equal(a.length, b.length):
            raise RetargetError(
                "the estimated motions do not line up with the true ones (clips or frames "
                "differ)", hint="use one control rate for the estimator and the tracker",
            )  # fmt: skip
        self.library, self.reference = truth_env.library, truth_env.reference

    def relabel(self, ctx: StepContext) -> StepContext:
        rows = ctx.ref.rows
        if rows is None:
            raise RetargetError("the step context has no reference rows to relabel")
        lib = self.library
        clip = torch.searchsorted(lib.start, rows, right=True) - 1
        frame = rows - lib.start[clip]
        labels = self.reference.scene_contacts
        ref = ReferenceBatch(
            pose=self.reference.pose(rows),
            devices=lib.devices[lib.rows(clip, frame, ctx.ref.window_offsets)],
            window_offsets=ctx.ref.window_offsets, contacts=lib.contacts[rows], rows=rows,
            scene_contacts=labels[rows] if labels is not None else None,
        )  # fmt: skip
        return replace(ctx, ref=ref)
