"""How far from an expert's path its own feedback still brings a body back (the path's basin).

A student cloned from a tracking expert makes small errors, so it visits states near the
expert's path rather than on it. This measures what happens there, with real physics: each
planned path is replayed from its first state with a push (a random change of every joint
velocity, ``--pushes`` standard deviations, m/s or rad/s) or with noise on every action
(``--noises``, in action units, of [-1, 1]), once open loop (the path's own actions) and once
with the iLQR feedback gains of the path (``IlqrRefiner.gains``: ``u_t + K_t (x - x_t)``).
Printed and written per setting: the median state deviation from the path, the share of trials
that fail (PHC: a frame whose mean body error exceeds 0.5 m), and the mean body error.

    python benchmarks/expert_basin.py runs/expert-human-train-ilqr --max-clips 4 \
        --out results/expert_basin.json

Trials of one setting run together, one simulation row each (no loop over trials).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

FAIL_M = 0.5


def follow(refiner, clip: int, track, gains: np.ndarray | None, *, push: float = 0.0,
           noise: float = 0.0, trials: int = 4, seed: int = 0) -> dict[str, np.ndarray]:
    """``trials`` replays of ``track`` (clip ``clip`` of ``refiner.env``) from its first
    state, velocities pushed by ``push`` and actions perturbed by ``noise`` (standard
    deviations), with ``gains`` as feedback (None: open loop). Returns per trial and step the
    tangent-space state deviation from the path (``deviation``) and the mean body error
    (``body_error``, m)."""
    import torch

    from retarget.sim.backend import make_sim

    env = refiner.env
    rng = np.random.default_rng(seed)
    plan = env.sim.settings.model_copy(update={"threads": 1, "backend": "mujoco"})
    sim = make_sim(env.sim.model, env.layout, trials, plan)
    env.place(torch.tensor([clip]), torch.tensor([0]))
    placed = {f: np.repeat(v[:1], trials, axis=0) for f, v in env.sim.state_dict().items()}
    placed["qvel"] = placed["qvel"] + push * rng.standard_normal(placed["qvel"].shape)
    sim.load_state_dict(placed)
    steps = len(track.actions)
    deviation = np.zeros((trials, steps + 1))
    body_error = np.zeros((trials, steps + 1))
    ref = np.asarray(track.ref_body_pos, dtype=np.float64)
    bodies = np.asarray(env.layout.body_ids, dtype=np.intp)
    for t in range(steps + 1):
        q, v = sim.raw("qpos"), sim.raw("qvel")
        dx = np.concatenate((refiner.tangent.difference(q, np.broadcast_to(track.qpos[t], q.shape)),
                             v - track.qvel[t]), axis=1)  # fmt: skip
        deviation[:, t] = np.linalg.norm(dx, axis=1)
        body_error[:, t] = np.linalg.norm(sim.raw("xpos")[:, bodies] - ref[t], axis=-1).mean(-1)
        if t == steps:
            break
        u = np.broadcast_to(track.actions[t].astype(np.float64), (trials, refiner.nu))
        if gains is not None:
            u = u + dx @ gains[t].T.astype(np.float64)
        u = u + noise * rng.standard_normal(u.shape)
        sim.step(np.clip(u, refiner._lo, refiner._hi))
    return {"deviation": deviation, "body_error": body_error}


def load_dir(root: Path, max_clips: int | None, every: int = 1):
    """Yield (name, refiner, track) for every ``every``-th clip of an expert directory, at most
    ``max_clips``."""
    from expert_refine import open_clip

    from retarget.expert.ilqr import IlqrRefiner
    from retarget.expert.store import read_header
    from retarget.registry.loader import load_plugins

    registry = load_plugins(strict=False)
    header = read_header(root)
    report = json.loads((root / "report.json").read_text())["clips"]
    with tempfile.TemporaryDirectory() as tmp:
        recipe_file = Path(tmp) / "recipe.yaml"
        recipe_file.write_text(yaml.safe_dump(header["recipe"]))
        for name in list(report)[::every][:max_clips]:
            env, track = open_clip(root, recipe_file, name, registry)
            yield name, IlqrRefiner(env, threads=1), track


def measure(root: Path, max_clips: int | None, every: int, pushes: list[float],
            noises: list[float], trials: int, damping: float) -> list[dict]:
    rows = []
    for name, refiner, track in load_dir(root, max_clips, every):
        cpu0 = time.process_time()
        gains = refiner.gains(0, track, damping=damping)
        gains_cpu = time.process_time() - cpu0
        settings = [("push", p) for p in pushes] + [("noise", n) for n in noises]
        for what, size in settings:
            row = {"clip": name, "perturbation": what, "size": size,
                   "gains_cpu_s": gains_cpu}  # fmt: skip
            for mode, k in (("open", None), ("feedback", gains)):
                out = follow(refiner, 0, track, k, trials=trials,
                             **({"push": size} if what == "push" else {"noise": size}))
                row[mode] = {
                    "median_deviation": float(np.median(out["deviation"])),
                    "failed": float((out["body_error"].max(1) > FAIL_M).mean()),
                    "body_error_mm": float(out["body_error"].mean() * 1000),
                }
            rows.append(row)
            o, f = row["open"], row["feedback"]
            print(f"{name} {what} {size:g}: open dev {o['median_deviation']:.4f} failed "
                  f"{o['failed']:.2f} body {o['body_error_mm']:.0f} mm | feedback dev "
                  f"{f['median_deviation']:.4f} failed {f['failed']:.2f} body "
                  f"{f['body_error_mm']:.0f} mm", flush=True)
    return rows


def summarise(rows: list[dict]) -> dict[str, dict]:
    """Per perturbation: the means over clips of each mode's figures."""
    out: dict[str, dict] = {}
    for what, size in sorted({(r["perturbation"], r["size"]) for r in rows}):
        mine = [r for r in rows if (r["perturbation"], r["size"]) == (what, size)]
        out[f"{what} {size:g}"] = {
            mode: {k: float(np.mean([r[mode][k] for r in mine])) for k in mine[0][mode]}
            for mode in ("open", "feedback")
        }
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dir", type=Path, help="an expert directory (`retarget expert --out`)")
    parser.add_argument("--max-clips", type=int, default=None)
    parser.add_argument("--every", type=int, default=1, help="every N-th clip (a spread of kinds)")
    parser.add_argument("--pushes", default="0.0001,0.001,0.01,0.03",
                        help="joint-velocity push sizes (comma-separated)")
    parser.add_argument("--noises", default="0.01,0.03,0.1",
                        help="per-step action noise sizes (comma-separated)")
    parser.add_argument("--trials", type=int, default=4)
    parser.add_argument("--damping", type=float, default=1.0, help="of the gains")
    parser.add_argument("--out", type=Path, default=None, help="JSON of the figures")
    args = parser.parse_args()
    floats = [[float(x) for x in s.split(",") if x] for s in (args.pushes, args.noises)]
    rows = measure(args.dir, args.max_clips, args.every, *floats, args.trials, args.damping)
    summary = summarise(rows)
    print(f"\n{'perturbation':14} {'open: dev / failed / body mm':>30} "
          f"{'feedback: dev / failed / body mm':>34}")
    for key, s in summary.items():
        o, f = s["open"], s["feedback"]
        print(f"{key:14} {o['median_deviation']:12.4f} {o['failed']:6.2f} "
              f"{o['body_error_mm']:8.0f} {f['median_deviation']:16.4f} {f['failed']:6.2f} "
              f"{f['body_error_mm']:8.0f}")
    if args.out:
        args.out.write_text(json.dumps({"dir": str(args.dir), "trials": args.trials,
                                        "damping": args.damping, "summary": summary,
                                        "clips": rows}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
