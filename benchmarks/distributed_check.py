"""Data-parallel training on one machine: torchrun with 1 and 2 ranks against one process.

Run: ``.venv/bin/python benchmarks/distributed_check.py [--character human] [--steps 400000]
[--out benchmarks/results]``

Three trainings of the packaged recipe for the character with the same number of samples per
iteration (256 environments x 32 steps = 8192) and the same sample budget:

* ``1 process, 2 threads``: ``retarget train`` with 256 environments, physics and update on
  both cores (the default);
* ``torchrun 1 rank``: 256 environments, one thread for physics and update;
* ``torchrun 2 ranks``: two ranks of 128 environments, one thread each, gradients averaged
  over gloo.

It prints a table (environment steps/s, collection and update rates per rank, final return)
and writes the learning curves (episode return against environment steps) to a PNG: if the
all-reduce and the statistics merge are right, the 2-rank curve lies on the 1-rank curves at
equal samples (seeds differ, so they agree within the spread of runs, not bit for bit).
"""

from __future__ import annotations

import argparse
import csv
import datetime as dt
import os
import subprocess
import sys
import tempfile
from pathlib import Path

RUNS = {
    "1 process, 2 threads": (None, 256, 2, 2),
    "torchrun 1 rank": (1, 256, 1, 1),
    "torchrun 2 ranks": (2, 128, 1, 1),
}
"""label -> (torchrun ranks or None, environments per rank, physics threads, update threads)"""


def train(label: str, character: str, steps: int, root: Path) -> Path:
    ranks, envs, threads, update = RUNS[label]
    flags = ["train", "--character", character, "--steps", str(steps), "--num-envs", str(envs),
             "--threads", str(threads), "--set", f"algorithm.update_threads={update}",
             "--runs-dir", str(root / label.replace(" ", "_").replace(",", "")),
             "--no-tensorboard"]  # fmt: skip
    if ranks is None:
        cmd = [sys.executable, "-m", "retarget", *flags]
    else:
        cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone",
               f"--nproc-per-node={ranks}", "-m", "retarget", *flags]  # fmt: skip
    print(f"{label}: {' '.join(cmd[1:])}", flush=True)
    env = {**os.environ, "OMP_NUM_THREADS": str(update)}
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    return next((root / label.replace(" ", "_").replace(",", "")).glob("*/latest/metrics.csv"))


def read(path: Path) -> list[dict[str, float]]:
    with path.open() as handle:
        return [{k: float(v) for k, v in row.items() if v not in ("", None)}
                for row in csv.DictReader(handle)]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--character", default="human")
    parser.add_argument("--steps", type=int, default=400_000)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    parser.add_argument("--runs-dir", type=Path,
                        default=Path(tempfile.gettempdir()) / "retarget-ddp",
                        help="where the three runs go (kept, for a look at their metrics)")
    args = parser.parse_args()
    curves = {}
    stamp = dt.datetime.now().strftime("%H%M%S")
    for label in RUNS:
        root = args.runs_dir / stamp
        curves[label] = read(train(label, args.character, args.steps, root))
    lines = ["| run | env steps/s | collect steps/s per rank | update samples/s per rank | "
             "return (last 3 iterations) |", "|---|---|---|---|---|"]  # fmt: skip
    for label, rows in curves.items():
        tail = rows[len(rows) // 2 :]  # the second half: warm caches, steady rates
        mean = lambda key, rs=tail: sum(r.get(key, 0.0) for r in rs) / len(rs)  # noqa: E731
        ret = sum(r.get("episode_return", 0.0) for r in rows[-3:]) / len(rows[-3:])
        lines.append(f"| {label} | {rows[-1]['steps_per_s_total']:.0f} | "
                     f"{mean('collect_steps_per_s'):.0f} | {mean('update_samples_per_s'):.0f} | "
                     f"{ret:.1f} |")  # fmt: skip
    text = "\n".join(lines)
    print(text)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for label, rows in curves.items():
        ax.plot([r["step"] for r in rows], [r.get("episode_return", 0.0) for r in rows],
                label=label)  # fmt: skip
    ax.set_xlabel("environment steps (all ranks)")
    ax.set_ylabel("episode return")
    ax.set_title(f"{args.character}: PPO at equal samples per iteration (8192)")
    ax.legend()
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / f"distributed_curves_{dt.date.today()}.png"
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"curves: {png}")


if __name__ == "__main__":
    main()
