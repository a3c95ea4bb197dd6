"""Held-out quality against CPU-hours: a run's checkpoints measured on a held-out style.

    python benchmarks/heldout_curve.py RUN --points 4 --kinds walk --max-clips 8 \
        --png benchmarks/results/curve.png --out curve.json

Picks ``--points`` checkpoints evenly over the run, measures each with
``benchmarks/heldout_eval.py`` (PHC protocol, one run per clip), and plots PHC success,
global MPJPE and falls per minute against the CPU-hours the run had spent at that checkpoint
(its ``metrics.csv`` elapsed time times ``--cores``).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from heldout_eval import corpus_files, evaluate

from retarget.train.run_dir import CHECKPOINTS, resolve_run


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run")
    parser.add_argument("--points", type=int, default=4)
    parser.add_argument("--kinds", default="walk")
    parser.add_argument("--style", default="normal")
    parser.add_argument("--max-clips", type=int, default=8)
    parser.add_argument("--cores", type=float, default=1.0)
    parser.add_argument("--num-envs", type=int, default=32)
    parser.add_argument("--png", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    run = resolve_run(args.run)
    ckpts = sorted((run / CHECKPOINTS).glob("ckpt-*.pt"))
    spread = max(args.points - 1, 1)
    picks = [ckpts[round(i * (len(ckpts) - 1) / spread)] for i in range(args.points)]
    with (run / "metrics.csv").open() as f:
        elapsed = {int(float(r["iteration"])): (float(r["elapsed_s"]), float(r["step"]))
                   for r in csv.DictReader(f)}  # fmt: skip
    points = []
    for ckpt in dict.fromkeys(picks):
        iteration = int(ckpt.stem.split("-")[1])
        seconds, steps = elapsed.get(iteration, (float("nan"), float("nan")))
        row = {"checkpoint": ckpt.name, "cpu_hours": seconds / 3600 * args.cores, "steps": steps}
        for kind in args.kinds.split(","):
            files = corpus_files(args.style, kind, args.max_clips)
            row[kind] = evaluate(str(run), files, args.num_envs, checkpoint=str(ckpt))
        points.append(row)
        figures = {k: (round(v["phc_success"], 2), round(v["phc_g_mpjpe_mm"]),
                       round(v["falls_per_min"], 1)) for k, v in row.items()
                   if isinstance(v, dict)}  # fmt: skip
        print(ckpt.name, f"{row['cpu_hours']:.2f} CPU-h", figures)
    if args.out:
        args.out.write_text(json.dumps(points, indent=2))
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        panels = (("phc_success", "PHC success"), ("phc_g_mpjpe_mm", "G-MPJPE (mm)"),
                  ("falls_per_min", "falls per minute"))  # fmt: skip
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
        for ax, (key, title) in zip(axes, panels, strict=True):
            for i, kind in enumerate(args.kinds.split(",")):
                ax.plot([p["cpu_hours"] for p in points], [p[kind][key] for p in points],
                        "o-", color=f"C{i}", label=f"held-out {args.style} {kind}")  # fmt: skip
            ax.set_title(title)
            ax.set_xlabel("CPU-hours of training")
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=8)
        fig.suptitle(run.parent.name, fontsize=9)
        fig.tight_layout()
        fig.savefig(args.png, dpi=90)
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
