"""``retarget eval RUN --motions PATH``: tracking metrics of a trained policy (table + JSON)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING

from retarget.cli.numbers import amount, count
from retarget.cli.run_changes import add_run_change_args
from retarget.registry import Registry

if TYPE_CHECKING:
    from rich.table import Table

COLUMNS = (
    ("headset_cm", "HMD cm", "{:.1f}"),
    ("headset_deg", "HMD deg", "{:.1f}"),
    ("controller_cm", "ctrl cm", "{:.1f}"),
    ("success_20s", "succ 20s", "{:.2f}"),
    ("success_30s", "succ 30s", "{:.2f}"),
    ("success_frame", "succ frame", "{:.2f}"),
    ("success_simxr", "succ SimXR", "{:.2f}"),
    ("mpjpe_mm", "MPJPE", "{:.0f}"),
    ("pa_mpjpe_mm", "PA-MPJPE", "{:.0f}"),
    ("jerk_km_s3", "jerk km/s3", "{:.2f}"),
    ("foot_skate_mm", "skate mm", "{:.1f}"),
    ("contact_agreement", "contact", "{:.2f}"),
    ("scene_contact_agreement", "scene contact", "{:.2f}"),
    ("penetration_mean_mm", "pen mean mm", "{:.1f}"),
    ("penetration_max_mm", "pen max mm", "{:.1f}"),
    ("falls_per_min", "falls/min", "{:.1f}"),
    ("box_side_per_min", "box side/min", "{:.1f}"),
    ("box_top_per_min", "box top/min", "{:.1f}"),
    ("runs", "runs", "{}"),
)


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("eval", help="evaluate a trained run on motion clips")
    parser.add_argument("run", help="run directory (runs/NAME/latest)")
    parser.add_argument("--motions", help="clip file or directory (default: the run's own)")
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
    add_run_change_args(parser)
    parser.set_defaults(handler=run)


def table(report: dict) -> Table:
    from rich.table import Table
    t = Table(title="tracking evaluation")
    t.add_column("clip")
    for _, label, _ in COLUMNS:
        t.add_column(label, justify="right")
    rows = [*report["clips"].items(), ("overall", report["overall"])]
    for name, metrics in rows:
        cells = [fmt.format(metrics[k]) if k in metrics else "-" for k, _, fmt in COLUMNS]
        t.add_row(name, *cells)
    return t


def run(args: argparse.Namespace, registry: Registry) -> int:
    from rich.progress import Progress

    from retarget.cli.console import out
    from retarget.eval import EvalSettings, evaluate
    from retarget.train.load import load_run
    loaded = load_run(
        args.run,
        registry,
        num_envs=args.num_envs,
        motions=args.motions,
        terminations=False,
        checkpoint=args.checkpoint,
        scene=args.scene,
        assignments=args.assignments,
    )
    fall = None
    for comp in loaded.resolved.of_kind("termination"):
        if comp.entry.name == "fall":
            fall = comp.instantiate()
            fall.bind(loaded.env.layout)
    settings = EvalSettings(every=args.every, max_seconds=args.max_seconds)
    with Progress(console=out, transient=True) as bar:
        task = bar.add_task("evaluating", total=None)
        report = evaluate(
            loaded.env,
            loaded.algorithm.act,
            settings,
            on_batch=lambda done, total: bar.update(task, completed=done, total=total),
            fall=fall,
        )
    report["run"] = str(loaded.run)
    report["checkpoint"] = str(loaded.checkpoint)
    report["motions"] = args.motions or loaded.resolved.recipe.motions.path or "(generated)"
    report["settings"] = vars(settings)
    out.print(table(report))
    out.print(f"real-time factor (batched): {report['overall']['real_time_factor']:.1f}x")
    path = Path(args.json_out) if args.json_out else loaded.run / "eval.json"
    path.write_text(json.dumps(report, indent=2))
    out.print(f"wrote {path}")
    return 0
