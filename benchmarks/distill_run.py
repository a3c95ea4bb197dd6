"""Teacher/student benchmark: a full-body imitator per character, students distilled from it by
DAgger, evaluated on training clips and on shared clips left out, with the learning curves.

Run by hand, in stages (each prints what it ran; figures go to ``OUT/*.json`` and a table)::

    python benchmarks/distill_run.py teacher --character human --minutes 60
    python benchmarks/distill_run.py student --teacher runs/distill/human-teacher/latest \
        --sensors three_point --minutes 25
    python benchmarks/distill_run.py eval runs/distill/human-teacher/latest \
        runs/distill/human-three_point-student/latest          # table of every run given
    python benchmarks/distill_run.py quality runs/distill/human-three_point-student/latest
        # per-frame success of its checkpoints on the training clips: steps to 0.8
    python benchmarks/distill_run.py plot RUN [RUN ...] --png curves.png
    python benchmarks/distill_run.py compare RUN [RUN ...] --marks 0.1 0.2 0.3   # A/B, equal steps

Split of ``../shared/data/mocap`` (or ``$RETARGET_SHARED_DATA``): training = every clip but
three (walks, turns, runs, hop, kick, gestures); left out = CMU 131_01 (a walk by another
subject and studio), a slow jog and a one-hand wave (a standing gesture). Extra ``--set k=v``
go to ``retarget train``. Two stages can run at once with ``--set sim.threads=1``.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

from retarget.errors import require_extra

HELD_OUT = {
    "heldout_walk": ["cmu_131_01_walk_start_stop"],
    "heldout_jog": ["bandai_d2_run_exhausted_003"],
    "heldout_wave": ["bandai_d2_wave-right-hand_normal_018"],
}
sys.path.insert(0, str(Path(__file__).parent))
from learning_run import compare, link_clips, shared_mocap  # noqa: E402  (one definition each)

METRICS = [
    ("success_frame", "succ/frame", "{:.2f}"),
    ("success_20s", "succ 20 s", "{:.2f}"),
    ("mpjpe_mm", "MPJPE mm", "{:.0f}"),
    ("headset_cm", "HMD cm", "{:.1f}"),
    ("controller_cm", "ctrl cm", "{:.1f}"),
    ("falls_per_min", "falls/min", "{:.1f}"),
    ("runs", "runs", "{:d}"),
]


def link_split(out: Path) -> dict[str, Path]:
    """Links to the shared clips (never copied): every clip but the left-out ones trains."""
    source = shared_mocap()
    clips = sorted(p.stem for p in source.glob("*.bvh"))
    if not clips:
        raise SystemExit(f"no .bvh clips in {source} (set RETARGET_SHARED_DATA)")
    held = {s for stems in HELD_OUT.values() for s in stems}
    return link_clips(out, {"train": [c for c in clips if c not in held], **HELD_OUT})


def retarget(*args: str) -> None:
    print("$ retarget", " ".join(args), flush=True)
    cmd = [sys.executable, "-c", "from retarget.cli.main import main; raise SystemExit(main())"]
    subprocess.run([*cmd, *args], check=True)


def read_metrics(run: Path) -> list[dict[str, float]]:
    with (run / "metrics.csv").open() as f:
        return [{k: float(v) for k, v in r.items() if v} for r in csv.DictReader(f)]


def train(args: argparse.Namespace, extra: list[str], name: str) -> None:
    out = Path(args.out)
    dirs = link_split(out)
    sets = [x for s in args.set for x in ("--set", s)]
    retarget("train", *extra, "--motions", str(dirs["train"]), "--minutes", str(args.minutes),
             "--runs-dir", str(out), "--set", f"name={name}", *sets)  # fmt: skip


def evaluate(run: Path, out: Path, every: int, seconds: float) -> dict[str, dict]:
    dirs = link_split(out)
    label = run.resolve().parent.name
    report = {}
    for split, d in dirs.items():
        path = out / f"{label}-eval-{split}.json"
        if not path.exists():
            retarget("eval", str(run), "--motions", str(d), "--json", str(path),
                     "--every", str(every), "--max-seconds", str(seconds))  # fmt: skip
        report[split] = json.loads(path.read_text())["overall"]
    return report


def table(reports: dict[str, dict[str, dict]]) -> str:
    head = "| run | split | " + " | ".join(t for _, t, _ in METRICS) + " |"
    lines = [head, "|---|---|" + "---:|" * len(METRICS)]
    for label, report in reports.items():
        for split, overall in report.items():
            cells = []
            for key, _, fmt in METRICS:
                v = overall.get(key)
                cells.append("-" if v is None else fmt.format(int(v) if key == "runs" else v))
            lines.append(f"| {label} | {split} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def quality(run: Path, out: Path, target: float, stride: int) -> str:
    """Per-frame success of every ``stride``-th checkpoint on the training clips (a cheap
    evaluation: every 60th frame, 10 s): the steps until ``target`` is reached."""
    dirs = link_split(out)
    ckpts = sorted((run / "checkpoints").glob("ckpt-*.pt"))[::stride]
    steps = {int(r["iteration"]): r["step"] for r in read_metrics(run)}
    lines, reached = [], None
    for ckpt in ckpts:
        it = int(ckpt.stem.split("-")[1])
        path = out / f"{run.resolve().parent.name}-q-{it}.json"
        if not path.exists():
            retarget("eval", str(run), "--checkpoint", str(ckpt), "--motions", str(dirs["train"]),
                     "--json", str(path), "--every", "60", "--max-seconds", "10")  # fmt: skip
        ok = json.loads(path.read_text())["overall"]["success_frame"]
        lines.append(f"| {it} | {steps.get(it, 0) / 1e6:.2f} | {ok:.2f} |")
        if reached is None and ok >= target:
            reached = steps.get(it, 0)
    head = ["| iteration | steps (M) | succ/frame (train, quick) |", "|---:|---:|---:|"]
    verdict = (f"reached {target} at {reached / 1e6:.2f} M steps" if reached is not None
               else f"did not reach {target}")  # fmt: skip
    return "\n".join([*head, *lines, "", verdict])


def plot(runs: list[Path], png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [
        ("episode_length", "mean episode length (control steps)"),
        ("episode_return", "mean episode return"),
        ("action_gap", "student - teacher action MSE (DAgger)"),
    ]
    tables = {run: read_metrics(run) for run in runs}
    panels = [p for p in panels if any(p[0] in r for rows in tables.values() for r in rows)]
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4), squeeze=False)
    axes = axes[0]
    for i, run in enumerate(runs):  # one colour per run in every panel
        rows = tables[run]
        label = run.resolve().parent.name
        minutes = rows[-1]["elapsed_s"] / 60 if rows else 0
        for ax, (key, title) in zip(axes, panels, strict=True):
            pts = [(r["step"] / 1e6, r[key]) for r in rows if key in r]
            if pts:
                ax.plot(*zip(*pts, strict=True), color=f"C{i}",
                        label=f"{label} ({minutes:.0f} min)")  # fmt: skip
            ax.set_title(title)
            ax.set_xlabel("environment steps (millions)")
            ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    print(f"wrote {png}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "stage", choices=("teacher", "student", "eval", "quality", "plot", "compare")
    )
    parser.add_argument("runs", nargs="*", help="eval/quality/plot: run directories")
    parser.add_argument("--character", default="human")
    parser.add_argument("--sensors", default="three_point")
    parser.add_argument("--teacher", help="student: the teacher run")
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--out", default="runs/distill", help="runs, motion links, reports")
    parser.add_argument("--set", action="append", default=[], help="passed to retarget train")
    parser.add_argument("--every", type=int, default=30, help="eval: a run every K frames")
    parser.add_argument("--seconds", type=float, default=30.0, help="eval: seconds per run")
    parser.add_argument("--target", type=float, default=0.8, help="quality: success to reach")
    parser.add_argument("--stride", type=int, default=2, help="quality: every K-th checkpoint")
    parser.add_argument("--png", default="curves.png", help="plot: the image")
    parser.add_argument("--marks", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.5, 1.0],
                        help="compare: millions of environment steps")
    args = parser.parse_args()
    require_extra("bench", "matplotlib", needed_for="the learning-curve pictures")
    out = Path(args.out)
    if args.stage == "teacher":
        train(args, ["teacher", "--character", args.character], f"{args.character}-teacher")
    elif args.stage == "student":
        if not args.teacher:
            raise SystemExit("student needs --teacher RUN")
        lock = Path(args.teacher) / "recipe.lock.yaml"
        import yaml

        character = yaml.safe_load(lock.read_text())["character"]["type"]
        train(args, ["--character", character, "--sensors", args.sensors,
                     "--teacher", args.teacher],
              f"{character}-{args.sensors.replace(',', '-')}-student")  # fmt: skip
    elif args.stage == "eval":
        reports = {Path(r).resolve().parent.name: evaluate(Path(r), out, args.every, args.seconds)
                   for r in args.runs}  # fmt: skip
        print(table(reports))
    elif args.stage == "quality":
        for r in args.runs:
            print(f"\n{r}\n" + quality(Path(r), out, args.target, args.stride))
    elif args.stage == "compare":
        print(compare([Path(r) for r in args.runs], args.marks))
    else:
        plot([Path(r) for r in args.runs], Path(args.png))


if __name__ == "__main__":
    main()
