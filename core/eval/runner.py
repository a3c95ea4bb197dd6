"""Running a policy from every k-th reference frame and aggregating the metrics.

As in QuestEnvSim, every clip is evaluated from many starting frames (every ``every``-th),
each run lasting until its clip ends or ``max_seconds``. Runs are batched over the env's
environments. Terminations other than the clip end are off: a run is followed through a
failure, and the failure rules below decide what counts.

What is measured are metric terms (:mod:`retarget.eval.terms`): the standard ones
(:mod:`retarget.eval.standard`) and any a caller adds. Feet hitting props are reported only
for scenes with props; falls and prop hits count over every step of a run (physical events,
not tracking errors), tracking errors only until the run fails.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from retarget.env import RetargetEnv
from retarget.eval.ground_truth import GroundTruth
from retarget.eval.kinematic import KinematicRollout
from retarget.eval.metrics import MetricProbe
from retarget.eval.standard import standard_terms
from retarget.eval.terms import EvalBatch, EvalStep, MetricTerm, summarise
from retarget.kinds import StepNeeds, Termination

Policy = Callable[[Mapping[str, torch.Tensor]], torch.Tensor]


@dataclass(frozen=True)
class EvalSettings:
    every: int = 30  # start a run every this many frames of each clip
    max_seconds: float = 30.0
    fail_distance: float = 0.8  # QuestEnvSim: mean headset/controller error above this fails
    head_distance: float = 0.5  # SimXR: head farther than this from the headset fails


def _starts(env: RetargetEnv, every: int) -> tuple[np.ndarray, np.ndarray]:
    lengths = env.library.length.numpy()
    clips, frames = [], []
    for c, n in enumerate(lengths):
        f = np.arange(0, max(int(n) - 2, 1), every)
        clips.append(np.full(len(f), c))
        frames.append(f)
    return np.concatenate(clips), np.concatenate(frames)


def evaluate(
    env: RetargetEnv,
    policy: Policy,
    settings: EvalSettings | None = None,
    on_batch: Callable[[int, int, int, int], None] | None = None,
    fall: Termination | None = None,
    terms: Sequence[MetricTerm] = (),
    kinematic: KinematicRollout | None = None,
    truth: GroundTruth | None = None,
) -> dict:
    """Metrics per clip and overall (JSON-ready dict); ``fall`` (a bound termination) counts
    falls per minute; ``terms`` are metrics reported after the standard ones.

    ``kinematic`` (a pose estimator's :class:`~retarget.eval.kinematic.KinematicRollout`)
    places the character in the estimate each frame instead of stepping ``policy`` (which is
    then unused), so both kinds of method get the same table. ``truth`` measures against the
    true motion when the env's reference is itself an estimate (a two-stage tracker).

    ``on_batch(runs_done, runs, clips_done, clips)`` follows progress. Ctrl-C stops after the
    batch being stepped: the report then holds the clips whose runs all finished, and
    ``interrupted: true``.
    """
    cfg = settings or EvalSettings()
    env.gather(StepNeeds(scene_contacts=True))  # the scene contact agreement reads them
    probe = MetricProbe(env.layout, env.headset_mount)
    has_joints = probe.joints is not None
    every = [
        *standard_terms(env, has_joints=has_joints, head_distance=cfg.head_distance, fall=fall,
                        stepped=kinematic is None),
        *terms,
    ]
    clips, frames = _starts(env, cfg.every)
    runs = len(clips)
    per_run: dict[str, np.ndarray] = {}
    wall, simulated = 0.0, 0.0
    n = env.num_envs
    ends = {int(c): int(np.flatnonzero(clips == c).max()) + 1 for c in np.unique(clips)}
    interrupted = False
    for begin in range(0, runs, n):
        idx = np.arange(begin, min(begin + n, runs))
        try:
            result, seconds = _run_batch(
                env, policy, probe, every, cfg, clips, frames, idx, kinematic, truth
            )
        except KeyboardInterrupt:  # keep what is finished; the batch being stepped is lost
            interrupted = True
            break
        wall += seconds
        simulated += float(result["seconds"].sum())
        for key, value in result.items():
            per_run[key] = np.concatenate([per_run.get(key, np.zeros(0)), value.astype(float)])
        if on_batch is not None:
            done = int(idx[-1]) + 1
            on_batch(done, runs, sum(end <= done for end in ends.values()), len(ends))
    finished = len(per_run.get("seconds", ()))
    complete = [c for c, end in ends.items() if end <= finished]  # every run of the clip done
    columns = [col for term in every for col in term.columns]
    keep = np.isin(clips[:finished], complete)
    report = _aggregate(
        env, clips[:finished][keep], {k: v[keep] for k, v in per_run.items()}, columns,
        wall, simulated,
    )  # fmt: skip
    if interrupted:
        report["interrupted"] = True
    return report


def _run_batch(env, policy, probe, every, cfg, clips, frames, idx, kinematic=None, truth=None):
    """Step the runs ``idx`` together; their per-run values and the wall time it took."""
    n, dt = env.num_envs, env.sim.settings.control_dt
    max_steps = round(cfg.max_seconds / dt)
    pad = n - len(idx)
    c = torch.as_tensor(np.concatenate([clips[idx], np.full(pad, clips[idx[0]])]))
    f = torch.as_tensor(np.concatenate([frames[idx], np.full(pad, frames[idx[0]])]))
    available = torch.clamp(env.library.length[c] - 1 - f, max=max_steps)
    tracked = torch.zeros(n)
    failed_at = torch.full((n,), float(max_steps + 1))
    for term in every:
        term.start(n)
    obs = env.place(c, f) if kinematic is None else None
    t0 = time.perf_counter()
    with torch.no_grad():
        for step in range(int(available.max())):
            if kinematic is None:
                obs, *_ = env.step(policy(obs))
                ctx = env.last_context
                deepest, mean = env.sim.penetration()
                pen = (torch.from_numpy(deepest).float(), torch.from_numpy(mean).float())
            else:
                ctx = kinematic.context(c, f + step + 1, step + 1)
                pen = kinematic.penetration_at(c, f + step + 1)
            if truth is not None:
                ctx = truth.relabel(ctx)
            m = probe(ctx, pen)
            alive = step < available
            ok = alive & (step < failed_at)
            newly = ok & (m.device_mean > cfg.fail_distance)
            failed_at = torch.where(newly, torch.full_like(failed_at, step), failed_at)
            ok &= ~newly
            tracked += ok.float()
            seen = EvalStep(ctx=ctx, metrics=m, step=step, alive=alive, ok=ok)
            for term in every:
                term.update(seen)
    seconds = time.perf_counter() - t0
    k = len(idx)
    batch = EvalBatch(runs=k, available=available, failed_at=failed_at, tracked=tracked, dt=dt)
    avail = available[:k].float()
    result = {"seconds": (avail * dt).numpy(), "steps": avail.numpy()}
    for term in every:
        result.update(term.finish(batch))
    return result, seconds


def _aggregate(env, clips, per_run, columns, wall, simulated) -> dict:
    def summary(mask: np.ndarray) -> dict[str, float]:
        return {**summarise(columns, per_run, mask), "runs": int(mask.sum())}

    per_clip = {env.library.names[c]: summary(clips == c) for c in np.unique(clips)}
    if not len(clips):  # interrupted before any clip finished
        return {"overall": {"runs": 0, "real_time_factor": 0.0}, "clips": {}}
    overall = summary(np.ones(len(clips), dtype=bool))
    overall["real_time_factor"] = simulated / max(wall, 1e-9)
    return {"overall": overall, "clips": per_clip}
