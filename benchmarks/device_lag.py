"""How much of a policy's headset and controller error is lag: the avatar doing what the person
did a few frames ago.

A student that sees only the devices' current and past poses cannot act on where they go
next; its body follows with some delay, and at walking speed every 28 ms of delay (one
control step at 36 Hz) is about 4 cm of headset error. This rolls a run out on held-out clips
of the corpus (PHC's protocol: one run per clip, first frame to last) and compares the
simulated head and hands at step ``t`` with the reference's at ``t - k`` for every lag ``k``
up to ``--max-lag`` steps, over the tracked steps: the error at ``k = 0`` is the report's
``headset_cm`` / ``controller_cm``; the smallest over ``k`` is what is left when the lag is
forgiven, and its ``k`` is the lag. At ``k = 0`` it also gives each device's mean error as a
vector in the reference headset's heading frame (forward, left, up): a body that is steadily
behind, lower or wider than the reference shows there as a bias rather than as noise.

    python benchmarks/device_lag.py pretrained:human-three_point-student --kinds walk,turn \
        --max-clips 8 --out results/device_lag.json
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch
from heldout_eval import KINDS, corpus_files

from retarget.eval.terms import MetricTerm

SITES = ("head", "left_hand", "right_hand")


class LagRecorder(MetricTerm):
    """Keeps every step's simulated and reference head and hand positions and the reference
    headset's heading (no columns: the lags are computed over all runs once the evaluation
    ends)."""

    columns = ()

    def __init__(self, head: int, hands: list[int]) -> None:
        self.head, self.hands = head, hands
        self.batches: list[dict[str, np.ndarray]] = []
        self._steps: list[tuple[torch.Tensor, ...]] = []

    def start(self, n: int) -> None:
        self._steps = []

    def update(self, step) -> None:
        s, r = step.ctx.sim, step.ctx.ref.pose
        sites = [self.head, *self.hands]
        self._steps.append((s.site_pos[:, sites].clone(), r.site_pos[:, sites].clone(),
                            step.ok.clone(), r.site_quat[:, self.head].clone()))  # fmt: skip

    def finish(self, batch) -> dict[str, np.ndarray]:
        if self._steps:
            k = batch.runs
            sim, ref, ok, quat = (torch.stack(x)[:, :k].numpy()
                                  for x in zip(*self._steps, strict=True))  # fmt: skip
            # (T, runs, 3 sites, 3); quat (T, runs, 4): the reference headset's orientation
            self.batches.append({"sim": sim, "ref": ref, "ok": ok, "head_quat": quat})
        return {}


def lag_errors(batches: list[dict[str, np.ndarray]], max_lag: int) -> dict[str, list[float]]:
    """Mean distance (cm) of the head and of the hands from the reference ``k`` steps earlier,
    for ``k = 0 .. max_lag``, over steps tracked at both times; ``head_up_cm``: the vertical
    part of the head's (how much of it is posture: a body lower or higher than the
    reference's, rather than behind or beside it)."""
    sums = np.zeros((max_lag + 1, 3))
    counts = np.zeros(max_lag + 1)
    for b in batches:
        sim, ref, ok = b["sim"], b["ref"], b["ok"].astype(bool)
        for k in range(max_lag + 1):
            now, then = sim[k:], ref[: len(ref) - k]
            both = ok[k:] & ok[: len(ok) - k]
            d = np.linalg.norm(now - then, axis=-1)  # (T-k, runs, 3)
            sums[k, 0] += d[..., 0][both].sum()
            sums[k, 1] += d[..., 1:].mean(-1)[both].sum()
            sums[k, 2] += np.abs(now[..., 0, 2] - then[..., 0, 2])[both].sum()
            counts[k] += both.sum()
    mean = sums / np.maximum(counts, 1)[:, None] * 100
    return {"head_cm": mean[:, 0].tolist(), "hands_cm": mean[:, 1].tolist(),
            "head_up_cm": mean[:, 2].tolist()}  # fmt: skip


def device_bias(batches: list[dict[str, np.ndarray]]) -> dict[str, list[float]]:
    """Per device (``head``, ``left_hand``, ``right_hand``): the mean of ``sim - ref`` at lag
    0, in cm, turned into the reference headset's heading frame (forward, left, up), over the
    tracked steps."""
    from retarget.geometry.heading import to_heading_vectors

    sums, count = np.zeros((len(SITES), 3)), 0
    for b in batches:
        ok = b["ok"].astype(bool)
        d = torch.from_numpy((b["sim"] - b["ref"])[ok]).double()  # (M, 3 sites, 3)
        local = to_heading_vectors(d, torch.from_numpy(b["head_quat"][ok]).double())
        sums += local.sum(0).numpy()
        count += len(d)
    mean = sums / max(count, 1) * 100
    return {name: mean[i].round(3).tolist() for i, name in enumerate(SITES)}


def measure(run: str, files: list[Path], num_envs: int, max_lag: int,
            sets: list[str] = ()) -> dict:  # fmt: skip
    from retarget.eval import EvalSettings, evaluate
    from retarget.kinds.capabilities import Acting
    from retarget.registry.loader import load_plugins
    from retarget.train.load import load_run

    folder = Path(tempfile.mkdtemp(prefix="lag-"))
    for f in files:
        (folder / f.name).symlink_to(f)
    loaded = load_run(run, load_plugins(strict=False), num_envs=num_envs, motions=str(folder),
                      assignments=list(sets))  # fmt: skip
    if not isinstance(loaded.algorithm, Acting):
        raise SystemExit(f"{run}: not a policy that acts")
    layout = loaded.env.layout
    rec = LagRecorder(layout.site(SITES[0]), [layout.site(name) for name in SITES[1:]])
    report = evaluate(loaded.env, loaded.algorithm.act, EvalSettings(every=10**9,
                      max_seconds=3600.0), terms=[rec])  # fmt: skip
    lags = lag_errors(rec.batches, max_lag)
    head, hands = np.array(lags["head_cm"]), np.array(lags["hands_cm"])
    return {
        "clips": len(files),
        "success_frame": report["overall"].get("success_frame", float("nan")),
        "head_cm_now": float(head[0]), "head_cm_best": float(head.min()),
        "head_lag_steps": int(head.argmin()),
        "head_up_cm_at_lag": float(lags["head_up_cm"][int(head.argmin())]),
        "hands_cm_now": float(hands[0]), "hands_cm_best": float(hands.min()),
        "hands_lag_steps": int(hands.argmin()),
        "bias_cm": device_bias(rec.batches),
        "by_lag": lags,
    }  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", help="run directories or pretrained:NAME")
    parser.add_argument("--style", default="normal", help="held-out style of the corpus")
    parser.add_argument("--kinds", default="walk,turn,run")
    parser.add_argument("--max-clips", type=int, default=8, help="per kind")
    parser.add_argument("--num-envs", type=int, default=32)
    parser.add_argument("--max-lag", type=int, default=12, help="control steps")
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="PATH=VALUE",
                        help="change a field of the run's recipe, e.g. sensors.1.offset=2")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    results: dict[str, dict] = {}
    for run in args.runs:
        results[run] = {}
        for kind in args.kinds.split(","):
            if kind not in KINDS:
                parser.error(f"--kinds: {kind!r} is not one of {', '.join(KINDS)}")
            files = corpus_files(args.style, kind, args.max_clips)
            r = measure(run, files, args.num_envs, args.max_lag, args.sets)
            results[run][kind] = r
            print(f"{run} {kind} ({r['clips']} clips): head {r['head_cm_now']:.1f} cm, "
                  f"{r['head_cm_best']:.1f} cm at a lag of {r['head_lag_steps']} steps (vertical "
                  f"{r['head_up_cm_at_lag']:.1f}); hands "
                  f"{r['hands_cm_now']:.1f} cm, {r['hands_cm_best']:.1f} cm at "
                  f"{r['hands_lag_steps']}", flush=True)
            print("  mean error (forward, left, up) cm: " + "; ".join(
                f"{name} {', '.join(f'{v:+.1f}' for v in r['bias_cm'][name])}"
                for name in SITES), flush=True)  # fmt: skip
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
