"""Running a policy from every k-th reference frame and aggregating the metrics.

As in QuestEnvSim, every clip is evaluated from many starting frames (every ``every``-th),
each run lasting until its clip ends or ``max_seconds``. Runs are batched over the env's
environments. Terminations other than the clip end are off: a run is followed through a
failure, and the failure rules below decide what counts.

Feet hitting props (:mod:`retarget.eval.prop_hits`) are counted over every step of a run, like
falls (they are physical events, not tracking errors): the share of steps with a foot on a
prop's top or against its side, and per minute the hits that begin (a side hit held for five
steps is one stumble). They are reported only for scenes with props.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import torch

from retarget.env import RetargetEnv
from retarget.eval.metrics import MetricProbe
from retarget.eval.prop_hits import foot_geoms, foot_prop_hits, prop_geoms
from retarget.kinds import Termination

Policy = Callable[[Mapping[str, torch.Tensor]], torch.Tensor]


@dataclass(frozen=True)
class EvalSettings:
    every: int = 30  # start a run every this many frames of each clip
    max_seconds: float = 30.0
    fail_distance: float = 0.8  # QuestEnvSim: mean headset/controller error above this fails
    head_distance: float = 0.5  # SimXR: head farther than this from the headset fails


MEAN_KEYS = (
    "hmd_pos",
    "hmd_rot",
    "controller_pos",
    "g_mpjpe",
    "mpjpe",
    "pa_mpjpe",
    "mpjre",
    "mpjve",
    "skate",
    "contact_agree",
    "scene_contact_agree",
    "penetration_mean",
)


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
    on_batch: Callable[[int, int], None] | None = None,
    fall: Termination | None = None,
) -> dict:
    """Metrics per clip and overall (JSON-ready dict); ``fall`` (a bound termination) counts
    falls per minute."""
    cfg = settings or EvalSettings()
    probe = MetricProbe(env.layout)
    dt = env.sim.settings.control_dt
    clips, frames = _starts(env, cfg.every)
    runs = len(clips)
    max_steps = round(cfg.max_seconds / dt)
    per_run: dict[str, np.ndarray] = {}
    model = env.world.model
    props = prop_geoms(model)
    feet = foot_geoms(model, env.layout) if props.any() else props
    wall, simulated = 0.0, 0.0
    for begin in range(0, runs, env.num_envs):
        idx = np.arange(begin, min(begin + env.num_envs, runs))
        pad = env.num_envs - len(idx)
        c = torch.as_tensor(np.concatenate([clips[idx], np.full(pad, clips[idx[0]])]))
        f = torch.as_tensor(np.concatenate([frames[idx], np.full(pad, frames[idx[0]])]))
        available = torch.clamp(env.library.length[c] - 1 - f, max=max_steps)
        n = env.num_envs
        sums = {k: torch.zeros(n) for k in MEAN_KEYS}
        tracked = torch.zeros(n)
        failed_at = torch.full((n,), float(max_steps + 1))
        simxr_fail = torch.zeros(n, dtype=torch.bool)
        jerk_sum = torch.zeros(n)
        pen_worst = torch.zeros(n)
        down = torch.zeros(n, dtype=torch.bool)
        falls = torch.zeros(n)
        history: list[torch.Tensor] = []
        hit_steps = {side: torch.zeros(n) for side in ("top", "side")}
        hit_events = {side: torch.zeros(n) for side in ("top", "side")}
        hit_before = {side: torch.zeros(n, dtype=torch.bool) for side in ("top", "side")}
        obs = env.place(c, f)
        t0 = time.perf_counter()
        with torch.no_grad():
            for step in range(int(available.max())):
                obs, *_ = env.step(policy(obs))
                ctx = env.last_context
                deepest, mean = env.sim.penetration()
                m = probe(ctx, (torch.from_numpy(deepest).float(), torch.from_numpy(mean).float()))
                alive = step < available
                ok = alive & (step < failed_at)
                newly = ok & (m.device_mean > cfg.fail_distance)
                failed_at = torch.where(newly, torch.full_like(failed_at, step), failed_at)
                ok &= ~newly
                simxr_fail |= alive & (m.head_to_headset > cfg.head_distance)
                for key in MEAN_KEYS:
                    value = getattr(m, key)
                    if value is not None:
                        sums[key] += torch.where(ok, torch.nan_to_num(value), 0.0)
                tracked += ok.float()
                pen_worst = torch.maximum(pen_worst, torch.where(ok, m.penetration_max, 0.0))
                if fall is not None:
                    now = fall.check(ctx) & alive
                    falls += (now & ~down).float()
                    down = now
                if props.any():
                    found = env.sim.each_env(lambda d: foot_prop_hits(model, d, feet, props))
                    for j, side in enumerate(("top", "side")):
                        now = torch.tensor([h[j] for h in found]) & alive
                        hit_steps[side] += now.float()
                        hit_events[side] += (now & ~hit_before[side]).float()
                        hit_before[side] = now
                history = [*history[-3:], ctx.sim.body_pos.clone()]
                if len(history) == 4:
                    d3 = history[3] - 3 * history[2] + 3 * history[1] - history[0]
                    jerk = d3.norm(dim=-1).mean(-1) / dt**3
                    jerk_sum += torch.where(ok, jerk, 0.0)
        wall += time.perf_counter() - t0
        simulated += float(available.sum()) * dt
        if on_batch is not None:
            on_batch(int(idx[-1]) + 1, runs)
        k = len(idx)
        denom = tracked.clamp_min(1)[:k]
        result = {key: (sums[key][:k] / denom).numpy() for key in MEAN_KEYS}
        result["jerk"] = (jerk_sum[:k] / (tracked[:k] - 3).clamp_min(1)).numpy()
        avail = available[:k].float()
        result["frames_ok"] = (torch.minimum(failed_at[:k], avail) / avail.clamp_min(1)).numpy()
        result["success_20s"] = (failed_at[:k] >= torch.clamp(avail, max=20 / dt)).numpy()
        result["success_30s"] = (failed_at[:k] >= torch.clamp(avail, max=30 / dt)).numpy()
        result["success_simxr"] = (~simxr_fail[:k]).numpy()
        result["seconds"] = (avail * dt).numpy()
        result["falls"] = falls[:k].numpy()
        result["penetration_max"] = pen_worst[:k].numpy()
        if props.any():
            result["steps"] = avail.numpy()
            for side in ("top", "side"):
                result[f"box_{side}_steps"] = hit_steps[side][:k].numpy()
                result[f"box_{side}_events"] = hit_events[side][:k].numpy()
        for key, value in result.items():
            per_run[key] = np.concatenate([per_run.get(key, np.zeros(0)), value.astype(float)])
    has_joints = probe.joints is not None
    return _aggregate(env, clips, per_run, has_joints, wall, simulated)


def _aggregate(env, clips, per_run, has_joints, wall, simulated) -> dict:
    scale = {
        "hmd_pos": 100,
        "controller_pos": 100,
        "hmd_rot": 180 / np.pi,
        "mpjre": 180 / np.pi,
        "g_mpjpe": 1000,
        "mpjpe": 1000,
        "pa_mpjpe": 1000,
        "mpjve": 1000,
        "skate": 1000,
        "jerk": 1e-3,
        "penetration_mean": 1000,
        "penetration_max": 1000,
    }
    names = {
        "hmd_pos": "headset_cm",
        "hmd_rot": "headset_deg",
        "controller_pos": "controller_cm",
        "g_mpjpe": "g_mpjpe_mm",
        "mpjpe": "mpjpe_mm",
        "pa_mpjpe": "pa_mpjpe_mm",
        "mpjre": "mpjre_deg",
        "mpjve": "mpjve_mm_per_frame",
        "skate": "foot_skate_mm",
        "jerk": "jerk_km_s3",
        "contact_agree": "contact_agreement",
        "scene_contact_agree": "scene_contact_agreement",
        "penetration_mean": "penetration_mean_mm",
        "penetration_max": "penetration_max_mm",
        "success_20s": "success_20s",
        "success_30s": "success_30s",
        "frames_ok": "success_frame",
        "success_simxr": "success_simxr",
    }
    joint_keys = {"g_mpjpe", "mpjpe", "pa_mpjpe", "mpjre", "mpjve"}

    def summary(mask: np.ndarray) -> dict[str, float]:
        out = {}
        for key, label in names.items():
            if key in joint_keys and not has_joints:
                continue
            # the worst overlap of any run; every other metric is a mean over runs
            reduce = np.nanmax if key == "penetration_max" else np.nanmean
            out[label] = float(reduce(per_run[key][mask]) * scale.get(key, 1.0))
        out["falls_per_min"] = float(
            per_run["falls"][mask].sum() / per_run["seconds"][mask].sum() * 60
        )
        if "steps" in per_run:  # pooled over runs: every step and second weighs the same
            steps, minutes = per_run["steps"][mask].sum(), per_run["seconds"][mask].sum() / 60
            for side in ("top", "side"):
                hits, events = per_run[f"box_{side}_steps"], per_run[f"box_{side}_events"]
                out[f"box_{side}_fraction"] = float(hits[mask].sum() / max(steps, 1))
                out[f"box_{side}_per_min"] = float(events[mask].sum() / max(minutes, 1e-9))
        out["runs"] = int(mask.sum())
        return out

    per_clip = {env.library.names[c]: summary(clips == c) for c in np.unique(clips)}
    overall = summary(np.ones(len(clips), dtype=bool))
    overall["real_time_factor"] = simulated / max(wall, 1e-9)
    return {"overall": overall, "clips": per_clip}
