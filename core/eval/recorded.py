"""A run driven by recorded device streams instead of motion capture, and how well it follows.

This is what a VR user gets: ``retarget play --input`` and a live session (``retarget serve``)
start the avatar standing (the idle clip) and hand the policy the person's headset and
controllers, calibrated to the character's start (:func:`retarget.motion.device_stream.align_to`:
placed, turned and, for runs whose devices are at the character's size, scaled by the standing
headset height). Held-out evaluation (``retarget eval``) instead feeds devices taken from the
retargeted reference itself, exact to the millimetre; a policy can follow those and still lose
a person whose headset sits a few centimetres higher. :func:`drive_recordings` builds the
first situation for a batch of streams (environment ``k`` plays stream ``k``) and
:func:`follow` measures it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from retarget.motion.device_recording import DeviceRecording
    from retarget.registry import Registry
    from retarget.train.load import LoadedRun

LOST_AT = 0.5
"""SimXR's failure rule: the avatar's head farther than this from the headset, metres."""


@dataclass
class RecordedDrive:
    """A loaded run whose environment ``k`` plays stream ``k`` from frame ``lead`` on."""

    loaded: LoadedRun
    lead: int
    """Frames of standing before each stream's first sample (the sensors' history)."""
    lengths: list[int]
    """Control steps of each stream."""
    rows: list[np.ndarray]
    """Library rows holding each stream's samples."""


def drive_recordings(
    run: str | Path,
    registry: Registry,
    recordings: Sequence[DeviceRecording],
    *,
    height_offset: float = 0.0,
    changes: dict | None = None,
) -> RecordedDrive:
    """The run with one environment per recording, each over its own standing idle clip whose
    device rows are the recording resampled to the control rate and calibrated to the
    character's start (as ``play --input`` and ``serve`` do). ``height_offset`` (m) then moves
    every device up (or down): a headset that sits higher than calibrated. Raises
    ``ValueError`` (from the calibration) when a recording does not start with a standing user.
    """
    import torch

    from retarget.motion.device_stream import align_to, resample_stream, resample_tracked
    from retarget.motion.procedural import idle_clip
    from retarget.train.load import load_run, locked_recipe
    from retarget.train.run_dir import resolve_run

    changes = dict(changes or {})
    resolved = locked_recipe(resolve_run(run), registry, **changes)[0]
    hz = resolved.recipe.sim.control_hz
    streams = [resample_stream(rec, hz) for rec in recordings]
    # the sensors' history before the first sample is the standing body, as in a live
    # session (retarget serve), which starts at the same frame of the same idle clip; the
    # history is read from a bound environment (a sensor such as estimated_body knows its
    # window only once bound to the character)
    probe = load_run(run, registry, num_envs=1, clips=[idle_clip(1.0)], **changes)
    lead = max(1, -min(probe.env.window_offsets))
    del probe
    seconds = (lead + max(len(s) for s in streams)) / hz + 1.0
    clips = [idle_clip(seconds) for _ in streams]
    loaded = load_run(run, registry, num_envs=len(streams), clips=clips, **changes)
    lib = loaded.env.library
    scale = loaded.env.options.devices == "character"
    rows = []
    for k, stream in enumerate(streams):
        first = int(lib.start[k]) + lead
        aligned = align_to(stream, lib.devices[first, 0].double().numpy(), scale=scale)
        aligned[..., 2] += height_offset
        at = first + np.arange(len(stream))
        lib.devices[torch.as_tensor(at)] = torch.as_tensor(aligned, dtype=lib.devices.dtype)
        end = int(lib.start[k]) + int(lib.length[k])
        lib.devices[at[-1] + 1 : end] = lib.devices[int(at[-1])]  # the user stands still
        tracked = torch.as_tensor(resample_tracked(recordings[k], hz))
        lib.devices_tracked[torch.as_tensor(at)] = tracked
        lib.devices_tracked[at[-1] + 1 : end] = tracked[-1]
        rows.append(at)
    return RecordedDrive(loaded, lead, [len(s) for s in streams], rows)


def follow(
    drive: RecordedDrive, policy: Callable | None = None, on_step: Callable | None = None
) -> list[np.ndarray]:
    """Roll every environment from its stream's first sample to its last with the run's policy
    (or ``policy``); each environment's head-to-headset distance per step, metres."""
    import torch

    from retarget.eval.metrics import head_to_headset
    from retarget.kinds.capabilities import Acting, require

    env = drive.loaded.env
    act = policy or require(drive.loaded.algorithm, Acting).act
    head, mount = env.layout.site("head"), env.headset_mount
    n = env.num_envs
    obs = env.place(torch.arange(n), torch.full((n,), drive.lead))
    steps = max(drive.lengths) - 1
    gaps = np.zeros((n, steps))
    with torch.no_grad():
        for t in range(steps):
            obs, *_ = env.step(act(obs))
            gaps[:, t] = head_to_headset(env.last_context, head, mount).numpy()
            if on_step is not None:
                on_step(t)
    return [gaps[k, : length - 1] for k, length in enumerate(drive.lengths)]


def follow_figures(gaps: np.ndarray, hz: float, lost_at: float = LOST_AT) -> dict[str, float]:
    """One stream's figures: mean and largest head-to-headset distance (cm), whether the
    avatar followed to the end, and when it first lost the headset (s; the stream's length
    when it never did)."""
    lost = np.flatnonzero(gaps > lost_at)
    return {
        "gap_cm": float(100 * gaps.mean()),
        "max_gap_cm": float(100 * gaps.max()),
        "followed": float(lost.size == 0),
        "lost_at_s": float((lost[0] if lost.size else len(gaps)) / hz),
        "seconds": float(len(gaps) / hz),
    }
