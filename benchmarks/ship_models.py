"""Ship trained runs as the package's pretrained models, and keep their training state.

    python benchmarks/ship_models.py human-teacher RUN --heldout heldout.json [--teacher NAME]

For each model: ``core/pretrained/models/NAME`` gets the lock (motion path removed), the
policy-only checkpoint and the card (data, samples, CPU-hours, the held-out figures that
``benchmarks/heldout_eval.py`` wrote for that run); ``benchmarks/pretrain/NAME`` gets the
run's full training state (lock, settings, metrics, newest full checkpoint) so a later
session continues it exactly:

    retarget train --resume benchmarks/pretrain/human-teacher --minutes 60 --threads 1

CPU-hours are the training's wall-clock hours times the one core each process was given.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import shutil
import sys
from pathlib import Path

import yaml

from retarget.errors import RetargetError
from retarget.pretrained import MODELS, ModelCard
from retarget.train.package_model import package
from retarget.train.run_dir import CHECKPOINTS, LOCK, latest_checkpoint, resolve_run

HERE = Path(__file__).resolve().parent
DATA = ("Bandai Namco Research Motion Dataset 2 (../shared/data/mocap_corpus): styles active, "
        "elderly, exhausted and masculine (1,630 clips, 2.0 h); style 'normal' (465 clips) "
        "held out and never trained on")  # fmt: skip
LICENCE = ("CC BY-NC 4.0 (the training motion's licence): attribution, non-commercial use "
           "only")  # fmt: skip


def last_row(run: Path) -> dict[str, str]:
    with (run / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    return rows[-1]


def keep_state(run: Path, name: str, teacher: str | None = None) -> Path:
    """The run's full training state under ``benchmarks/pretrain/NAME`` (newest checkpoint);
    a student's lock names its teacher as the shipped model, so it resumes from any checkout.
    A state trained on in place keeps its files and loses only its older checkpoints."""
    out = HERE / "pretrain" / name
    ckpt = latest_checkpoint(run)
    if out.resolve() == run.resolve():  # trained on in place (`--resume` of the kept state)
        for old in (out / CHECKPOINTS).glob("*.pt"):
            if old.name != ckpt.name:
                old.unlink()
    else:
        if out.exists():
            shutil.rmtree(out)
        (out / CHECKPOINTS).mkdir(parents=True)
        for f in (LOCK, "metrics.csv", "train_settings.json"):
            if (run / f).exists():
                shutil.copy2(run / f, out / f)
        shutil.copy2(ckpt, out / CHECKPOINTS / ckpt.name)
    if teacher is not None:
        lock = yaml.safe_load((out / LOCK).read_text())
        lock["algorithm"]["teacher"] = teacher
        (out / LOCK).write_text(yaml.safe_dump(lock, sort_keys=False))
    return out


def students_checkpoints(name: str, models: Path = MODELS) -> dict[str, bytes]:
    """The checkpoints of shipped model ``name`` that other shipped models' locks distil from
    (``algorithm.teacher_checkpoint``), read before ``name`` is packaged again (packaging
    replaces its folder) so that each student keeps the teacher file it names."""
    kept: dict[str, bytes] = {}
    for lock_path in sorted(models.glob(f"*/{LOCK}")):
        algorithm = yaml.safe_load(lock_path.read_text()).get("algorithm")
        if not isinstance(algorithm, dict) or algorithm.get("teacher") != f"pretrained:{name}":
            continue
        rel = algorithm.get("teacher_checkpoint")
        path = models / name / str(rel)
        if rel and path.is_file() and path.parent == models / name / CHECKPOINTS:
            kept[path.name] = path.read_bytes()
    return kept


def students_left_behind(name: str, models: Path = MODELS) -> list[str]:
    """Shipped students whose locks no longer prepare unchanged against teacher ``name`` as
    now packaged (a sensor set up otherwise, other references or elbows): their kept teacher
    checkpoint would run under a recipe it was not trained with."""
    from retarget.registry.loader import load_plugins
    from retarget.train.load import locked_recipe, prepared_recipe

    registry = load_plugins()
    behind = []
    for lock_path in sorted(models.glob(f"*/{LOCK}")):
        algorithm = yaml.safe_load(lock_path.read_text()).get("algorithm")
        if not isinstance(algorithm, dict) or algorithm.get("teacher") != f"pretrained:{name}":
            continue
        try:
            resolved, _ = locked_recipe(lock_path.parent, registry)
            same = prepared_recipe(resolved, registry).to_dict() == resolved.to_dict()
        except RetargetError as exc:
            same, reason = False, str(exc)
        else:
            reason = "its recipe would change to the new teacher's references"
        if not same:
            behind.append(f"{lock_path.parent.name}: {reason}")
    return behind


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("name")
    parser.add_argument("run")
    parser.add_argument("--summary", required=True)
    parser.add_argument("--heldout", type=Path, help="heldout_eval.py JSON holding this run")
    parser.add_argument("--teacher", help="the shipped teacher's name (students)")
    parser.add_argument("--cores", type=float, default=1.0, help="cores the training used")
    parser.add_argument("--notes", default="")
    parser.add_argument("--plus-card", metavar="NAME", help="a run started --init-from this "
                        "shipped model: its card's samples and CPU-hours are added to the run's")
    parser.add_argument("--plus-run", action="append", default=[], metavar="RUN",
                        help="a run between that shipped model and this one in a chain of "
                        "--init-from starts: its samples and CPU-hours are added too")
    parser.add_argument("--plus-steps", type=float, default=0.0, metavar="N",
                        help="samples of earlier links of the chain whose runs are no longer "
                        "on disk (say which in --notes)")
    parser.add_argument("--plus-hours", type=float, default=0.0, metavar="H",
                        help="their CPU-hours")
    parser.add_argument("--no-state", action="store_true", help="package only: leave "
                        "benchmarks/pretrain/NAME as it is (a snapshot of a run still training)")
    args = parser.parse_args()
    run = resolve_run(args.run)
    lock = yaml.safe_load((run / LOCK).read_text())
    row = last_row(run)
    before_steps, before_hours = int(args.plus_steps), float(args.plus_hours)
    if args.plus_card:  # read before packaging: shipping NAME may replace that very card
        from retarget.pretrained import card as card_of

        before = card_of(args.plus_card)
        before_steps += before.env_steps
        before_hours += before.cpu_hours
    for between in args.plus_run:
        last = last_row(resolve_run(between))
        before_steps += int(float(last["step"]))
        before_hours += float(last["elapsed_s"]) / 3600 * args.cores
    metrics: dict[str, dict[str, float]] = {}
    if args.heldout:
        found = json.loads(args.heldout.read_text())
        mine = found.get(args.run) or next(
            (v for k, v in found.items() if resolve_run(k) == run), {}
        )
        metrics = {f"held-out normal: {kind}": {k: (v if math.isfinite(v) else None)
                                                for k, v in figs.items()}
                   for kind, figs in mine.items()}  # fmt: skip
    def kind(comp: str | dict) -> str:
        return comp if isinstance(comp, str) else comp["type"]

    algorithm, character = kind(lock["algorithm"]), kind(lock["character"])
    actor = ((lock.get("env") or {}).get("groups") or {}).get("actor")  # a student's own inputs
    sensors = [kind(s) for s in lock.get("sensors") or [] if actor is None or kind(s) in actor]
    card = ModelCard(
        name=args.name, summary=args.summary, character=character, sensors=sensors,
        algorithm=algorithm, data=DATA, licence=LICENCE,
        env_steps=before_steps + int(float(row["step"])),
        cpu_hours=round(before_hours + float(row["elapsed_s"]) / 3600 * args.cores, 3),
        teacher=f"pretrained:{args.teacher}" if args.teacher else None, metrics=metrics,
        notes=args.notes,
    )  # fmt: skip
    teacher_files = students_checkpoints(args.name)
    out = package(run, card, teacher=card.teacher)
    for file_name, data in teacher_files.items():
        if not (out / CHECKPOINTS / file_name).exists():
            (out / CHECKPOINTS / file_name).write_bytes(data)
            print(f"kept {CHECKPOINTS}/{file_name}: a shipped student distils from it")
    print(out)
    if not args.no_state:
        print(keep_state(run, args.name, card.teacher))
    behind = students_left_behind(args.name)
    for line in behind:
        print(f"error: shipped student {line}", file=sys.stderr)
    if behind:
        print("hint: ship the teacher those students learned from under a name of its own "
              "and point their locks' algorithm.teacher at it (as human-hmd-teacher)",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
