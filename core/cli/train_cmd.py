"""``retarget train``: train a policy from a recipe (or the packaged default plus flags)."""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Any

from retarget.commands.numbers import amount, count
from retarget.commands.recipe_args import add_recipe_flags, load_from_args
from retarget.registry import Registry
from retarget.train.run_dir import latest_checkpoint, resolve_run, starting_run
from retarget.train.start import DEFAULT_SETTINGS

if TYPE_CHECKING:
    from retarget.train.distributed import Comm


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("train", help="train a policy (PPO by default)")
    add_recipe_flags(parser)
    parser.add_argument(
        "--steps",
        type=count(1, 10**12),
        help="stop after this many environment steps (with --resume: this many more)",
    )
    parser.add_argument(
        "--minutes",
        type=amount(0.0, 1e6),
        help="stop after this many minutes (with --resume: this many more)",
    )
    parser.add_argument("--resume", metavar="RUN", help="continue a run (runs/NAME/latest)")
    parser.add_argument(
        "--init-from",
        metavar="RUN",
        help="start from another run's latest weights (a new run: its own recipe, fresh "
        "optimiser); inputs are matched by sensor/observer name, new observers start at zero "
        "weight",
    )
    parser.add_argument(
        "--teacher",
        metavar="RUN",
        help="distil from a trained teacher run with DAgger (algorithm: {type: dagger, "
        "teacher: RUN}); the teacher's sensors are added for it, the student's actor keeps "
        "the recipe's own",
    )
    parser.add_argument(
        "--expert",
        metavar="DIR",
        help="learn from a tracking expert's directory (`retarget expert`) by behaviour "
        "cloning (algorithm: {type: expert_bc, expert: DIR}); the expert's clips, character "
        "and physics are used",
    )
    parser.add_argument("--runs-dir", default="runs", help="where run directories go")
    parser.add_argument(
        "--num-envs", type=count(1, 65536),
        help="override env.num_envs (per rank under torchrun: `torchrun --nproc-per-node K -m "
        "retarget train ...` trains K ranks data-parallel)",
    )
    parser.add_argument(
        "--threads",
        type=count(0, 1024),
        help="physics threads (overrides sim.threads; allowed with --resume: each environment "
        "steps the same whatever the thread count, so only the speed changes)",
    )
    parser.add_argument(
        "--checkpoint-every",
        type=count(1, 10**6),
        help=f"iterations between checkpoints (default: {DEFAULT_SETTINGS['checkpoint_every']}; "
        "recorded in the run and kept by --resume)",
    )
    parser.add_argument(
        "--no-tensorboard",
        action="store_const",
        const=False,
        dest="tensorboard",
        help="CSV logs only (recorded in the run and kept by --resume)",
    )
    parser.set_defaults(handler=run)


def _budget(args: argparse.Namespace, done: Any) -> Any:
    """The stopping point: with --resume the budget is on top of what the run has done."""
    from retarget.train.runner import Budget

    return Budget(
        steps=None if args.steps is None else done.env_steps + args.steps,
        minutes=None if args.minutes is None else done.elapsed / 60.0 + args.minutes,
    )


_LABELS = {
    "episode_return": ("return", "{:>7.2f}"),
    "episode_length": ("ep len", "{:>5.1f}"),
    "loss": ("loss", "{:>7.3f}"),
    "mpjpe_mm": ("mpjpe", "{:>5.1f} mm"),
}


def _figures(last: dict[str, float], headline: tuple[str, ...]) -> str:
    """What the progress bar shows: the figures the algorithm's iteration names as its
    headline (a policy's return and episode length, a pose estimator's loss and error)."""
    parts = []
    for key in headline:
        if key in last:
            label, fmt = _LABELS.get(key, (key, "{:.4g}"))
            parts.append(f"{label} {fmt.format(last[key])}")
    return "  ".join(parts)


@contextmanager
def _rank_run_dir(comm: Comm, context: AbstractContextManager[Path]) -> Iterator[Path]:
    """Rank 0 enters ``context`` (creating the run directory) and tells the other ranks
    where it is; a single process just enters it."""
    if comm.main:
        with context as path:
            comm.broadcast(str(path))
            yield path
    else:
        yield Path(comm.broadcast(None))


def run(args: argparse.Namespace, registry: Registry) -> int:
    """``retarget train``, in one process or as one rank of a torchrun job."""
    from retarget.train import distributed

    comm = distributed.from_environment()
    try:
        return _train(args, registry, comm)
    finally:
        if comm.distributed:
            distributed.shutdown()


def _train(args: argparse.Namespace, registry: Registry, comm: Comm) -> int:
    from rich.progress import (
        BarColumn,
        Progress,
        TaskProgressColumn,
        TextColumn,
        TimeRemainingColumn,
    )

    from retarget.cli.console import out, warning
    from retarget.train.load import prepared_recipe
    from retarget.train.runner import Trainer
    from retarget.train.start import (
        check_motion_source,
        check_start,
        fields_newer_than_lock,
        resume_recipe,
        run_name,
        run_settings,
        start_assignments,
    )
    from retarget.train.warm_start import INIT_FROM, warm_start
    if comm.distributed and comm.main:
        out.print(f"data-parallel: {comm.size} ranks, {comm.local_size} on this machine")
    if args.steps is None and args.minutes is None and comm.main:
        out.print("no --steps or --minutes given: training until Ctrl-C (checkpoint on exit)")
    given = {"checkpoint_every": args.checkpoint_every, "tensorboard": args.tensorboard}
    check_start(resume=args.resume, init_from=bool(args.init_from),
                teacher=bool(args.teacher), expert=bool(args.expert),
                recipe_changes=bool(args.recipe or args.assignments),
                num_envs=args.num_envs is not None)  # fmt: skip
    if args.resume:
        run_dir = resolve_run(args.resume)
        resolved, moved = resume_recipe(run_dir, registry, args.threads)
        for line in moved:
            warning(line)
        context: AbstractContextManager[Path] = nullcontext(run_dir)
    else:
        args.assignments = [*start_assignments(teacher=args.teacher, expert=args.expert,
                                               num_envs=args.num_envs, threads=args.threads),
                            *args.assignments]  # fmt: skip
        resolved = prepared_recipe(load_from_args(args, registry), registry)
        check_motion_source(resolved.recipe.motions)
        if comm.main:
            for line in fields_newer_than_lock(args.recipe, resolved):
                warning(line)
        # only rank 0 creates it; removed again if the start fails
        context = (starting_run(args.runs_dir, run_name(resolved)) if comm.main
                   else nullcontext(Path()))  # fmt: skip
    with _rank_run_dir(comm, context) as run_dir:
        settings = comm.broadcast(
            run_settings(run_dir, given, resume=bool(args.resume)) if comm.main else None
        )
        trainer = Trainer(
            resolved,
            run_dir,
            checkpoint_every=settings["checkpoint_every"],
            tensorboard=settings["tensorboard"],
            registry=registry,
            comm=comm,
        )
        if args.resume:
            ckpt = latest_checkpoint(run_dir)
            trainer.restore(ckpt)
            if comm.main:
                out.print(f"resumed {ckpt} at {trainer.progress.env_steps} steps")
        if args.init_from:
            start = warm_start(trainer.algorithm, trainer.env.obs_layout, args.init_from, registry)
            if comm.main:
                (run_dir / INIT_FROM).write_text(f"{start.checkpoint}\n{start.summary()}\n")
            trainer.save()  # a resume of this run starts from these weights, not from scratch
            if comm.main:
                out.print(f"weights from {start.checkpoint}\n{start.summary()}", markup=False)
    if not comm.main:  # the other ranks train in step with rank 0 and print nothing
        trainer.train(_budget(args, trainer.progress))
        return 130 if trainer.stop_reason == "interrupted" else 0
    out.print(
        f"run directory: {run_dir}  ({trainer.env.num_envs} envs"
        f"{f' per rank, {comm.size} ranks' if comm.distributed else ''}, "
        f"{trainer.env.character.name}, obs {dict(trainer.env.obs_dims)})"
    )
    budget = _budget(args, trainer.progress)
    total = budget.steps
    columns = [
        TextColumn("[bold]train"),
        BarColumn(),
        TaskProgressColumn(),
        TextColumn("{task.fields[rate]:>6.0f} steps/s  {task.fields[figures]}"),
        TimeRemainingColumn(),
    ]
    minutes_total = 60.0 * budget.minutes if budget.minutes is not None else None
    with Progress(*columns, console=out, transient=False) as bar:
        task = bar.add_task("train", total=total or minutes_total, rate=0.0, figures="")

        def update(p) -> None:
            done = p.env_steps if total is not None else p.elapsed
            bar.update(
                task,
                completed=done if (total or minutes_total) else None,
                rate=p.last.get("steps_per_s_total", 0.0),
                figures=_figures(p.last, trainer.headline),
            )

        last = trainer.train(budget, on_iteration=update)
    out.print(
        f"stopped ({trainer.stop_reason}) after {trainer.progress.iteration} iterations, "
        f"{trainer.progress.env_steps} steps; checkpoint {last}"
    )
    return 130 if trainer.stop_reason == "interrupted" else 0
