"""Scene learning check: does a height map keep the feet off boxes the user never touched?

QuestEnvSim's Fig. 5 setting: the user walks on flat ground while the simulation holds boxes
on the walking path. The human character with ``three_point`` sensors is trained on the shared
walking clips with the ``path_boxes`` scene (random boxes of 5-25 cm re-drawn per episode on
the path of the clip each environment plays; reference contact labels are flat ground's),
once with the ``height_map`` observer and once without. Both are evaluated with path boxes on
the training walks and on the held-out walk, and compared: feet hitting box sides per minute
(stumbles, which the height map should prevent), feet stepping on box tops per minute, falls
per minute, success and headset error.

Run (by hand; ``--minutes`` per variant, the two one after the other unless ``--parallel``)::

    .venv/bin/python benchmarks/scene_learning_check.py --minutes 60
    .venv/bin/python benchmarks/scene_learning_check.py --minutes 30 --parallel
    .venv/bin/python benchmarks/scene_learning_check.py --runs runs/scene_check/A/latest \
        runs/scene_check/B/latest      # only evaluate finished runs (height map first)
    .venv/bin/python benchmarks/scene_learning_check.py --prefix boxes --runs \
        warm=runs/boxes/warm/latest scratch=runs/boxes/scratch/latest \
        --eval-set scene.height=[0.05,0.25]   # any runs, labelled; evaluated in another scene

Extra ``--set k=v`` pairs go to ``retarget train`` for both variants (``--parallel`` adds
``sim.threads=1``). The clip split is ``learning_run.py``'s (training: five Bandai walks and
CMU 131_02; held out: CMU 131_01). Needs the ``bench`` extra (matplotlib) for the PNG.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from learning_run import link_split, plot, retarget

from retarget.errors import require_extra

SPLITS = ("train", "walk_heldout")
VARIANTS = {"height_map": ["--observers", "height_map"], "blind": []}
COLUMNS = (
    ("box_side_per_min", "side hits/min", "{:.2f}"),
    ("box_top_per_min", "top steps/min", "{:.2f}"),
    ("box_side_fraction", "side frac", "{:.3f}"),
    ("falls_per_min", "falls/min", "{:.2f}"),
    ("success_20s", "succ 20s", "{:.2f}"),
    ("success_frame", "succ frame", "{:.2f}"),
    ("headset_cm", "HMD cm", "{:.1f}"),
)


def train_command(variant: str, args: argparse.Namespace, motions: Path, parallel: bool):
    """The ``retarget train`` arguments of one variant."""
    sets = [*args.set, *(["sim.threads=1"] if parallel else [])]
    return [
        "train", "--character", "human", "--sensors", "three_point", "--scene", "path_boxes",
        *VARIANTS[variant], "--motions", str(motions), "--minutes", str(args.minutes),
        "--runs-dir", str(args.out), "--set", f"name={args.prefix}-{variant}",
        *[x for s in sets for x in ("--set", s)],
    ]  # fmt: skip


def train(args: argparse.Namespace, motions: Path) -> dict[str, Path]:
    """Both variants' runs, trained one after the other or side by side."""
    runs = {v: Path(args.out) / f"{args.prefix}-{v}" / "latest" for v in VARIANTS}
    if not args.parallel:
        for variant in VARIANTS:
            retarget(*train_command(variant, args, motions, parallel=False))
        return runs
    cmd = [sys.executable, "-c", "from retarget.cli.main import main; raise SystemExit(main())"]
    procs = [
        subprocess.Popen([*cmd, *train_command(v, args, motions, parallel=True)]) for v in VARIANTS
    ]
    codes = [p.wait() for p in procs]
    if any(codes):
        raise SystemExit(f"training failed: exit codes {dict(zip(VARIANTS, codes, strict=True))}")
    return runs


def labelled_runs(specs: list[str]) -> dict[str, Path]:
    """``--runs``: ``LABEL=RUN`` pairs, or bare runs named after the variants in order."""
    if all("=" in s for s in specs):
        return {label: Path(run) for label, run in (s.split("=", 1) for s in specs)}
    if len(specs) != len(VARIANTS) or any("=" in s for s in specs):
        raise SystemExit(f"--runs: give {' '.join(VARIANTS)} runs in order, or LABEL=RUN pairs")
    return dict(zip(VARIANTS, (Path(r) for r in specs), strict=True))


def evaluate(runs: dict[str, Path], dirs: dict[str, Path], args: argparse.Namespace) -> dict:
    """``retarget eval`` of every run on every split (the runs' own ``path_boxes`` scene,
    changed by ``--eval-set``)."""
    report: dict[str, dict] = {}
    for variant, run in runs.items():
        report[variant] = {"run": str(run)}
        for split in SPLITS:
            path = Path(args.out) / f"{args.prefix}-{variant}-eval-{split}.json"
            retarget("eval", str(run), "--motions", str(dirs[split]), "--json", str(path),
                     "--every", str(args.every), "--max-seconds", str(args.max_seconds),
                     "--num-envs", str(args.eval_envs),
                     *[x for a in args.eval_set for x in ("--set", a)])  # fmt: skip
            overall = json.loads(path.read_text())["overall"]
            if "box_side_per_min" not in overall:
                raise SystemExit(f"{path}: no box metrics; was {run} trained with path_boxes?")
            report[variant][split] = overall
    return report


def table(report: dict) -> str:
    """The comparison as fixed-width text, one row per variant and split."""
    head = f"{'run':<12}{'split':<14}" + "".join(f"{c[1]:>15}" for c in COLUMNS)
    rows = [head, "-" * len(head)]
    for variant, splits in report.items():
        for split in SPLITS:
            m = splits[split]
            cells = "".join(f"{fmt.format(m[k]) if k in m else '-':>15}" for k, _, fmt in COLUMNS)
            rows.append(f"{variant:<12}{split:<14}{cells}")
    return "\n".join(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0, help="training time per variant")
    parser.add_argument("--out", default="runs/scene_check", help="runs, links and reports")
    parser.add_argument("--prefix", default="human-three_point-path_boxes")
    parser.add_argument("--set", action="append", default=[], help="passed to retarget train")
    parser.add_argument("--parallel", action="store_true", help="train both at once")
    parser.add_argument("--runs", nargs="+", metavar="RUN",
                        help="evaluate these finished runs instead of training: the height-map "
                        "and the blind run, or LABEL=RUN pairs")  # fmt: skip
    parser.add_argument("--eval-set", action="append", default=[], metavar="PATH=VALUE",
                        help="passed to retarget eval, e.g. scene.height=[0.05,0.25]")  # fmt: skip
    parser.add_argument("--every", type=int, default=30, help="eval: a run every K frames")
    parser.add_argument("--max-seconds", type=float, default=30.0, help="eval: run length")
    parser.add_argument("--eval-envs", type=int, default=64, help="eval: runs batched together")
    args = parser.parse_args()
    require_extra("bench", "matplotlib", needed_for="the learning-curve pictures")
    out = Path(args.out)
    dirs = link_split(out)
    runs = labelled_runs(args.runs) if args.runs else train(args, dirs["train"])
    report = evaluate(runs, dirs, args)
    text = table(report)
    print(text)
    path = out / f"{args.prefix}-check.json"
    path.write_text(json.dumps(report, indent=2))
    print(f"wrote {path}")
    plot(list(runs.values()), out / f"{args.prefix}-curves.png")


if __name__ == "__main__":
    main()
