"""``retarget eval RUN --motions PATH``: tracking metrics of a trained policy (table + JSON)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING

from retarget.cli.run_changes import add_run_change_args
from retarget.commands.numbers import amount, count
from retarget.commands.recipe_args import add_pick_flags, patterns
from retarget.errors import RetargetError
from retarget.kinds.capabilities import Acting, PoseEstimating, require
from retarget.registry import Registry

if TYPE_CHECKING:
    from rich.table import Table

COLUMNS = (
    ("headset_cm", "HMD\ncm", "{:.1f}"),
    ("headset_deg", "HMD\ndeg", "{:.1f}"),
    ("controller_cm", "ctrl\ncm", "{:.1f}"),
    ("success_20s", "succ\n20s", "{:.2f}"),
    ("success_30s", "succ\n30s", "{:.2f}"),
    ("success_frame", "succ\nframe", "{:.2f}"),
    ("success_simxr", "succ\nSimXR", "{:.2f}"),
    ("mpjpe_mm", "MPJPE\nmm", "{:.0f}"),
    ("pa_mpjpe_mm", "PA-\nMPJPE", "{:.0f}"),
    ("jerk_km_s3", "jerk\nkm/s3", "{:.2f}"),
    ("foot_skate_mm", "skate\nmm", "{:.1f}"),
    ("contact_agreement", "foot\ncont", "{:.2f}"),
    ("scene_contact_agreement", "scene\ncont", "{:.2f}"),
    ("penetration_max_mm", "pen\nmax mm", "{:.0f}"),
    ("falls_per_min", "falls\n/min", "{:.1f}"),
    ("box_side_per_min", "box\nside/m", "{:.1f}"),
    ("box_top_per_min", "box\ntop/m", "{:.1f}"),
    ("runs", "runs", "{}"),
)
"""What the table shows (every figure is in the JSON, with the clips' full names)."""
SCENE_ONLY = {"scene_contact_agreement", "penetration_max_mm", "box_side_per_min",
              "box_top_per_min"}  # fmt: skip
FLAT_ONLY = {"success_frame", "success_simxr", "jerk_km_s3", "contact_agreement"}
"""Shown without props; with props the scene's columns take their place (in the JSON: all)."""
LABEL = 16
"""Widest clip label in the table; longer names are shortened (the JSON keeps them whole)."""
WINDOWS = {"success_20s": 20.0, "success_30s": 30.0}



def _no_actions(obs: object) -> object:
    """The policy of a kinematic method, never called: its character is placed, not stepped."""
    raise RuntimeError("a pose estimator is evaluated by placing the character, not by acting")

def short_label(name: str, width: int = LABEL) -> str:
    """``name`` cut to ``width`` characters, keeping its end (clip files differ at the end)."""
    return name if len(name) <= width else "…" + name[-(width - 1) :]


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("eval", help="evaluate a trained run on motion clips")
    parser.add_argument("run", help="run directory (runs/NAME/latest)")
    parser.add_argument("--motions", help="clip file, folder or archive (default: the run's own)")
    add_pick_flags(parser)
    parser.add_argument(
        "--every", type=count(1, 10**6), default=30, help="start a run every K frames"
    )
    parser.add_argument(
        "--max-seconds", type=amount(0.0, 3600.0), default=30.0, help="length of each run"
    )
    parser.add_argument(
        "--num-envs", type=count(1, 4096), default=64, help="runs evaluated together"
    )
    parser.add_argument("--json", dest="json_out", help="where to write the JSON report")
    parser.add_argument("--checkpoint", help="a specific checkpoint file (default: latest)")
    parser.add_argument(
        "--estimator",
        metavar="RUN",
        help="two-stage: RUN (a pose estimator) turns the devices into a body and this run "
        "(a full-body imitator) follows it; measured against the true motion",
    )
    parser.add_argument(
        "--protocol", choices=("standard", "phc"), default="standard",
        help="phc: one run per clip from its first frame to its last (PHC's protocol; "
        "overrides --every and --max-seconds)",
    )  # fmt: skip
    add_run_change_args(parser)
    parser.set_defaults(handler=run)


PHC_COLUMNS = (
    ("phc_success", "succ", "{:.2f}"),
    *((f"phc_{k}{s}", f"{label}\n{'succ' if s else 'all'}", "{:.0f}")
      for k, label in (("mpjpe_mm", "MPJPE"), ("g_mpjpe_mm", "G-MPJPE"),
                       ("pa_mpjpe_mm", "PA-MPJPE"), ("accel_mm_f2", "accel"),
                       ("vel_mm_f", "vel")) for s in ("", "_succ")),
)  # fmt: skip
"""PHC's figures (all runs, successful runs only), mm; accel mm/frame^2, vel mm/frame."""


def phc_table(report: dict) -> Table:
    """PHC's protocol: success (mean body error never above 0.5 m) and errors over every
    frame, per clip and overall."""
    from rich import box
    from rich.table import Table

    t = Table(title="PHC protocol (all bodies, every frame; mm)", box=box.SIMPLE_HEAD,
              padding=(0, 1), collapse_padding=True, pad_edge=False)  # fmt: skip
    t.add_column("clip", max_width=LABEL, no_wrap=True)
    for _, label, _ in PHC_COLUMNS:
        t.add_column(label, justify="right")
    for name, metrics in [*report["clips"].items(), ("overall", report["overall"])]:
        cells = [fmt.format(metrics[key]) if key in metrics else "-"
                 for key, _, fmt in PHC_COLUMNS]  # fmt: skip
        t.add_row(short_label(name), *cells)
    return t


def table(report: dict) -> Table:
    """The report as a table that fits 120 columns: two-line headers, short clip labels, and
    the scene columns only for scenes with props. A success window longer than every run of
    a clip reads ``<20s``: the figure would only repeat success to the clip's end."""
    from rich import box
    from rich.table import Table

    scene = "box_side_per_min" in report["overall"]
    hidden = FLAT_ONLY if scene else SCENE_ONLY
    shown = [col for col in COLUMNS if col[0] not in hidden]
    t = Table(
        title="tracking evaluation", box=box.SIMPLE_HEAD, padding=(0, 1), collapse_padding=True,
        pad_edge=False,
    )  # fmt: skip
    t.add_column("clip", max_width=LABEL, no_wrap=True)
    for _, label, _ in shown:
        t.add_column(label, justify="right")
    rows = [*report["clips"].items(), ("overall", report["overall"])]
    for name, metrics in rows:
        cells = []
        for key, _, fmt in shown:
            window = WINDOWS.get(key)
            if key not in metrics:
                cells.append("-")
            elif window and name != "overall" and metrics.get("longest_run_s", 1e9) < window:
                cells.append(f"<{window:.0f}s")
            else:
                cells.append(fmt.format(metrics[key]))
        t.add_row(short_label(name), *cells)
    return t


def _default_report(run_dir: Path, given: str) -> Path:
    """``RUN/eval.json``; a shipped model's report goes to the working folder instead."""
    from retarget.pretrained import inside_models

    if inside_models(run_dir):
        return Path(f"eval-{run_dir.name}.json")
    return run_dir / "eval.json"


def run(args: argparse.Namespace, registry: Registry) -> int:
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    from retarget.cli.console import out
    from retarget.eval import EvalSettings, evaluate
    from retarget.train.load import load_run

    def build(clips=None):
        return load_run(
            args.run,
            registry,
            num_envs=args.num_envs,
            motions=None if clips is not None else args.motions,
            clips=clips,
            terminations=False,
            checkpoint=args.checkpoint,
            scene=args.scene,
            assignments=args.assignments,
            include=patterns(args.include),
            exclude=patterns(args.exclude),
        )

    truth = None
    if args.estimator:
        from retarget.eval.ground_truth import GroundTruth
        from retarget.eval.kinematic import estimate_library

        truth_run = build()
        motions = args.motions or truth_run.resolved.recipe.motions.path
        if motions is None:
            raise RetargetError("--estimator needs --motions: the clips both runs read")
        source = load_run(args.estimator, registry, num_envs=1, motions=motions,
                          include=patterns(args.include), exclude=patterns(args.exclude))
        if not isinstance(source.algorithm, PoseEstimating):
            raise RetargetError(f"--estimator {args.estimator} is not a pose estimator run")
        loaded = build(estimate_library(source.env, source.algorithm.pose_estimator()).clips)
        truth = GroundTruth(truth_run.env, loaded.env)
    else:
        loaded = build()
    fall = None
    for comp in loaded.resolved.of_kind("termination"):
        if comp.entry.name == "fall":
            fall = comp.instantiate()
            fall.bind(loaded.env.layout)
    settings = EvalSettings(every=args.every, max_seconds=args.max_seconds)
    if args.protocol == "phc":
        settings = EvalSettings(every=10**9, max_seconds=3600.0)
    columns = (
        TextColumn("[bold]eval"), BarColumn(), MofNCompleteColumn(), TextColumn("runs"),
        TextColumn("{task.fields[clips]}"), TimeRemainingColumn(),
    )  # fmt: skip
    with Progress(*columns, console=out, transient=True) as bar:
        task = bar.add_task("eval", total=None, clips="")

        def progress(done: int, total: int, clips_done: int, clips: int) -> None:
            bar.update(task, completed=done, total=total, clips=f"{clips_done}/{clips} clips")

        algorithm = loaded.algorithm
        kinematic = None
        if isinstance(algorithm, PoseEstimating):  # the character placed in its estimate
            from retarget.eval.kinematic import KinematicRollout, estimate_library

            estimates = estimate_library(loaded.env, algorithm.pose_estimator())
            kinematic = KinematicRollout(loaded.env, estimates)
            policy = _no_actions
        else:
            policy = require(algorithm, Acting).act
        report = evaluate(loaded.env, policy, settings, progress, fall=fall,
                          kinematic=kinematic, truth=truth)  # fmt: skip
        if truth is not None:
            report["method"] = f"two-stage (estimator {args.estimator})"
        if kinematic is not None:
            report["method"] = "kinematic (pose estimator)"
    report["run"] = str(loaded.run)
    report["checkpoint"] = str(loaded.checkpoint)
    report["motions"] = args.motions or loaded.resolved.recipe.motions.path or "(generated)"
    report["settings"] = vars(settings)
    path = Path(args.json_out) if args.json_out else _default_report(loaded.run, args.run)
    path.write_text(json.dumps(report, indent=2))
    if report.get("interrupted"):
        out.print(f"interrupted: {len(report['clips'])} clips finished, written to {path}")
        return 130
    out.print(table(report))
    out.print(phc_table(report))
    out.print(f"real-time factor (batched): {report['overall']['real_time_factor']:.1f}x")
    out.print(f"wrote {path}")
    return 0
