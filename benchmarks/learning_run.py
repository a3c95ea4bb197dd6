"""Learning benchmark: train on the shared walking clips, evaluate on them and on clips left out,
and draw the learning curves.

Run (by hand; one hour per character on a 2-core machine)::

    .venv/bin/python benchmarks/learning_run.py --character human --sensors three_point --minutes 60
    .venv/bin/python benchmarks/learning_run.py --character dino --sensors hmd --minutes 60
    .venv/bin/python benchmarks/learning_run.py --plot runs/learning/human-three_point/latest \
        runs/learning/dino-hmd/latest --png curves.png   # curves of finished runs side by side

Extra ``--set k=v`` pairs go to ``retarget train`` (e.g. ``--set sim.threads=1`` when two
runs share the machine, ``--set sim.actuation=pd`` for PD-target actions, which learn faster
at this budget: ``benchmarks/results/learning_2026-11-29.md``). Needs the ``bench`` extra
(matplotlib) for the PNG.

Split of ``../shared/data/mocap`` (or ``$RETARGET_SHARED_DATA``): training = the five Bandai
walks (straight, slow, brisk, left and right turn) and CMU 131_02; held out = CMU 131_01 (a
walk by another subject and studio), and a jog and a wave (motions not trained on).
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

import yaml

from retarget.errors import require_extra
from retarget.motion.shared_data import require_clips, shared_data

TRAIN = [
    "bandai_d2_walk_normal_020",
    "bandai_d2_walk_elderly_004",
    "bandai_d2_walk_active_002",
    "bandai_d2_walk-turn-left_normal_007",
    "bandai_d2_walk-turn-right_normal_004",
    "cmu_131_02_walk_start_stop",
]
HELD_OUT = {
    "walk_heldout": ["cmu_131_01_walk_start_stop"],
    "other": ["bandai_d2_run_exhausted_003", "bandai_d2_wave-right-hand_normal_018"],
}
REPO = Path(__file__).resolve().parents[1]


def shared_mocap() -> Path:
    """The shared clips, checked before any work starts."""
    folder = shared_data("mocap")
    require_clips(folder)
    return folder


def link_clips(out: Path, split: dict[str, list[str]]) -> dict[str, Path]:
    """``out/motions/NAME/`` for each part of ``split``: symbolic links to the shared clips
    (they are never copied)."""
    source = shared_mocap()
    dirs = {}
    for name, stems in split.items():
        d = out / "motions" / name
        d.mkdir(parents=True, exist_ok=True)
        for stem in stems:
            link = d / f"{stem}.bvh"
            if not link.exists():
                link.symlink_to(source / f"{stem}.bvh")
        dirs[name] = d
    return dirs


def link_split(out: Path) -> dict[str, Path]:
    """This benchmark's split: six training walks, and the clips left out."""
    return link_clips(out, {"train": TRAIN, **HELD_OUT})


def retarget(*args: str) -> None:
    cmd = [sys.executable, "-c", "from retarget.cli.main import main; raise SystemExit(main())"]
    subprocess.run([*cmd, *args], check=True)


def read_metrics(run: Path) -> list[dict[str, float]]:
    with (run / "metrics.csv").open() as f:
        return [{k: float(v) for k, v in r.items() if v} for r in csv.DictReader(f)]


def plot(runs: list[Path], png: Path, x: str = "steps") -> None:
    """Training curves of ``runs`` side by side against environment steps (``x="steps"``) or
    the minutes each run had spent (``x="minutes"``: equal CPU time when the runs shared the
    machine alike)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [
        ("episode_return", "mean episode return"),
        ("episode_length", "mean episode length (control steps)"),
        ("mean_reward", "mean reward per step"),
        ("end_root_distance", "share of episodes ended by root distance"),
    ]
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4))
    for run in runs:
        rows = read_metrics(run)
        label = run.resolve().parent.name
        minutes = [r.get("elapsed_s", r["step"] / r["steps_per_s_total"]) / 60 for r in rows]
        along = minutes if x == "minutes" else [r["step"] / 1e6 for r in rows]
        for ax, (key, title) in zip(axes, panels, strict=True):
            pts = [(s, r[key]) for s, r in zip(along, rows, strict=True) if key in r]
            if pts:
                ax.plot(*zip(*pts, strict=True), label=f"{label} ({minutes[-1]:.0f} min)")
            ax.set_title(title)
            ax.set_xlabel("minutes of training" if x == "minutes"
                          else "environment steps (millions)")  # fmt: skip
            ax.grid(alpha=0.3)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    print(f"wrote {png}")


def compare(runs: list[Path], marks: list[float]) -> str:
    """Markdown table: mean episode length / return of each run around equal environment
    steps (the rows logged in the last 100k steps before each mark), so that runs that shared
    the machine differently are compared by samples, not by minutes."""
    head = "| run | " + " | ".join(f"{m:g} M" for m in marks) + " |"
    lines = [head, "|---|" + "---|" * len(marks)]
    for run in runs:
        rows = read_metrics(run)
        cells = []
        for m in marks:
            near = [r for r in rows if m * 1e6 - 1e5 < r["step"] <= m * 1e6
                    and "episode_length" in r]  # fmt: skip
            if near:
                length = sum(r["episode_length"] for r in near) / len(near)
                ret = sum(r["episode_return"] for r in near) / len(near)
                cells.append(f"{length:.1f} / {ret:.0f}")
            else:
                cells.append("-")
        lines.append(f"| {run} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run_name(run: Path) -> str:
    """A finished run's recipe name (its reports are named after it, not after the flags)."""
    lock = yaml.safe_load((run / "recipe.lock.yaml").read_text())
    return str(lock.get("name") or run.resolve().parent.name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--character", default="human")
    parser.add_argument("--sensors", default="three_point")
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--out", default="runs/learning", help="runs and motion links go here")
    parser.add_argument("--set", action="append", default=[], help="passed to retarget train")
    parser.add_argument("--run", help="evaluate and plot this finished run instead of training")
    parser.add_argument("--plot", nargs="+", help="only draw the curves of these runs")
    parser.add_argument("--png", help="curves image (default: OUT/NAME-curves.png)")
    parser.add_argument("--x", choices=("steps", "minutes"), default="steps",
                        help="curves against environment steps or minutes of training")
    parser.add_argument("--compare", nargs="+", help="A/B table of these runs at equal steps")
    parser.add_argument("--marks", type=float, nargs="+", default=[0.5, 1, 2, 3, 4],
                        help="--compare: millions of environment steps")
    args = parser.parse_args()
    require_extra("bench", "matplotlib", needed_for="the learning-curve pictures")
    out = Path(args.out)
    if args.compare:
        print(compare([Path(p) for p in args.compare], args.marks))
        return
    if args.plot:
        plot([Path(p) for p in args.plot], Path(args.png or out / "curves.png"), args.x)
        return
    dirs = link_split(out)
    name = f"{args.character}-{args.sensors}"
    if args.run:
        run = Path(args.run)
        name = run_name(run)
    else:
        sets = [x for s in args.set for x in ("--set", s)]
        retarget("train", "--character", args.character, "--sensors", args.sensors,
                 "--motions", str(dirs["train"]), "--minutes", str(args.minutes),
                 "--runs-dir", str(out), "--set", f"name={name}", *sets)  # fmt: skip
        run = out / name / "latest"
    report = {}
    for split, d in dirs.items():
        path = out / f"{name}-eval-{split}.json"
        retarget("eval", str(run), "--motions", str(d), "--json", str(path))
        report[split] = json.loads(path.read_text())["overall"]
    print(json.dumps(report, indent=2))
    plot([run], Path(args.png or out / f"{name}-curves.png"))


if __name__ == "__main__":
    main()
