"""``retarget expert CLIPS --character NAME --out DIR``: track clips by trajectory
optimisation, no training (:mod:`retarget.expert`).

Every clip is planned on its own (one environment holding that clip only), clip by clip into
``DIR`` (:mod:`retarget.expert.store`): an interrupted run resumes where it stopped and a
clip already planned with the same settings is skipped. ``--jobs`` plans clips in parallel
processes, each with ``--threads`` physics threads.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from pathlib import Path
from typing import Any

import retarget
from retarget import Command

SUFFIXES = (".bvh", ".npz", ".json", ".csv", ".c3d")


def _overrides(pairs: list[str]) -> dict[str, Any]:
    """``--planner KEY=VALUE`` pairs as a nested dict (values read as YAML scalars)."""
    import yaml

    out: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise SystemExit(f"retarget expert: --planner takes KEY=VALUE, got {pair!r}")
        node = out
        parts = key.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = yaml.safe_load(value)
    return out


def plan_clip(job: dict[str, Any]) -> dict[str, Any]:
    """Plan one clip (runs in a worker process too): build its env, track, write."""
    import torch

    from retarget import load_plugins
    from retarget.env.build import env_from_recipe
    from retarget.expert.store import write_track
    from retarget.recipe import load

    torch.set_num_threads(1)
    registry = job.get("registry") or load_plugins(strict=False)
    resolved = load(job["recipe"], registry, shorthands={**job["shorthands"],
                    "motions": job["path"]}, assignments=job["assignments"])  # fmt: skip
    env = env_from_recipe(resolved, registry=registry, num_envs=1, threads=job["threads"])
    from retarget import Planner

    cls = registry.get("planner", job["method"]).cls
    planner = cls(cls.Config.model_validate(job["planner"]))
    assert isinstance(planner, Planner), f"{job['method']} is registered as a planner"
    track = planner.track(env, 0, seconds=job["seconds"], threads=job["threads"],
                          progress=job.get("progress"))  # fmt: skip
    from retarget.expert.reference_dynamics import drop_beyond_fall_per_second

    start = int(env.library.start[0])
    reference = env.reference.qpos64[start : start + track.frames]
    meta = {
        "key": job["key"],
        "source": job["path"],
        "reference_drop_beyond_fall_mm_s": 1000.0
        * drop_beyond_fall_per_second(env.sim.model, reference, track.fps),
    }
    return write_track(Path(job["out"]), job["name"], track, meta)


class ExpertCommand(Command):
    """Track motion clips with a planner plugin over PD targets; no training."""

    name = "expert"
    help = "track clips by trajectory optimisation (no training); data for students"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        from retarget.commands.recipe_args import add_pick_flags, add_set_flag
        parser.add_argument("clips", nargs="+", help="motion files, folders or archives")
        parser.add_argument("--out", required=True, help="expert directory (resumed if it exists)")
        parser.add_argument("--recipe", default="teacher",
                            help="recipe whose character, scene and physics to plan with")
        parser.add_argument("--character", help="character plugin name, e.g. dino")
        parser.add_argument("--scene", help="scene plugin name")
        add_pick_flags(parser)
        add_set_flag(parser, "override a recipe field, e.g. --set sim.substeps=8")
        parser.add_argument("--method", default="beam",
                            help="planner plugin (`retarget plugins`): beam "
                            "(sampling beam search, the default) or beam_ilqr (its path "
                            "refined by iLQR)")
        parser.add_argument("--planner", action="append", default=[], metavar="KEY=VALUE",
                            help="planner setting, e.g. --planner samples=512 for beam, "
                            "--planner ilqr.iterations=8 for beam_ilqr "
                            "(`retarget plugins show planner NAME`)")
        parser.add_argument("--seconds", type=float, default=None,
                            help="plan at most this much of each clip")
        parser.add_argument("--max-clips", type=int, default=None, help="plan the first N clips")
        parser.add_argument("--jobs", type=int, default=1, help="clips planned in parallel")
        parser.add_argument("--threads", type=int, default=1, help="physics threads per clip")

    def run(self, args: argparse.Namespace) -> int:
        from concurrent.futures import ProcessPoolExecutor, as_completed
        from multiprocessing import get_context

        from pydantic import ValidationError
        from rich.console import Console
        from rich.progress import Progress

        from retarget.commands.recipe_args import patterns
        from retarget.errors import PluginError, RecipeError
        from retarget.expert.store import (
            clip_name,
            done_clips,
            settings_key,
            summarize,
            write_header,
            write_report,
        )
        from retarget.motion.sources import expand, select
        from retarget.recipe import load

        console = Console(stderr=True)
        if args.jobs < 1 or args.threads < 1 or (args.seconds is not None and args.seconds <= 0):
            console.print("retarget expert: --jobs, --threads and --seconds must be positive")
            return 2
        try:
            method = self.plugins().get("planner", args.method).cls
        except PluginError as exc:
            console.print(f"retarget expert: --method: {exc}")
            return 2
        try:
            planner = method.Config.model_validate(_overrides(args.planner))
        except ValidationError as exc:
            console.print(f"retarget expert: --planner ({args.method}): {exc}")
            return 2
        files = select(expand(args.clips, SUFFIXES), patterns(args.include) or (),
                       patterns(args.exclude) or ())  # fmt: skip
        files = sorted(files)[: args.max_clips] if args.max_clips else sorted(files)
        if not files:
            console.print("retarget expert: no motion files matched")
            return 2
        shorthands = {"character": args.character, "scene": args.scene}
        resolved = load(args.recipe, self.plugins(), assignments=args.assignments,
                        shorthands={**shorthands, "motions": str(files[0])})  # fmt: skip
        recipe = resolved.to_dict()
        # the clips are named per job; how they are read (level feet, ...) is a setting
        recipe["motions"] = {**recipe["motions"], "path": None, "include": [], "exclude": []}
        out = Path(args.out)
        header = {"recipe": recipe, "planner": planner.model_dump(mode="json"),
                  "character": recipe["character"], "method": args.method}  # fmt: skip
        write_header(out, header)
        key = settings_key(header)
        done = done_clips(out, key)
        taken: set[str] = set()
        jobs = []
        planned = 0  # of these files, planned before with these settings
        for path in files:
            name = clip_name(path, taken)
            target = out / "motions" / f"{name}{path.suffix.lower()}"
            if not target.exists():
                shutil.copyfile(path, target)
            if name in done:
                planned += 1
                continue
            jobs.append({
                "recipe": args.recipe, "shorthands": shorthands, "assignments": args.assignments,
                "path": str(target), "name": name, "planner": planner.model_dump(mode="json"),
                "method": args.method,
                "seconds": args.seconds, "threads": args.threads, "out": str(out), "key": key,
            })  # fmt: skip
        figures = dict(done)
        console.print(f"{len(files)} clips: {planned} planned before, {len(jobs)} to plan "
                      f"into {out}")  # fmt: skip
        try:
            with Progress(console=console) as bar:
                task = bar.add_task("planning", total=len(jobs))
                if args.jobs == 1:
                    for job in jobs:
                        sub = bar.add_task(f"  {job['name']}", total=None)
                        job = {**job, "registry": self.plugins(),
                               "progress": lambda n, s=sub: bar.advance(s, n)}  # fmt: skip
                        figures[job["name"]] = fig = plan_clip(job)
                        bar.remove_task(sub)
                        bar.advance(task)
                        bar.console.print(_line(job["name"], fig))
                else:
                    os.environ.setdefault("OMP_NUM_THREADS", "1")
                    pool = ProcessPoolExecutor(args.jobs, mp_context=get_context("spawn"))
                    with pool:
                        running = {pool.submit(plan_clip, job): job["name"] for job in jobs}
                        for future in as_completed(running):
                            name = running[future]
                            figures[name] = fig = future.result()
                            bar.advance(task)
                            bar.console.print(_line(name, fig))
        except KeyboardInterrupt:
            console.print("interrupted: planned clips are kept; run the same command to resume")
            write_report(out, figures)
            return 130
        except RecipeError as exc:
            console.print(f"retarget expert: {exc}")
            return 2
        report = write_report(out, figures)
        s = summarize(figures)
        print(f"clips={s['clips']} success_clip={s['success_clip']:.3f} "
              f"mpjpe_mm={s['mpjpe_mm']:.1f} g_mpjpe_mm={s['g_mpjpe_mm']:.1f} "
              f"cpu_s_per_motion_s={s['cpu_s_per_motion_s']:.1f} report={out / 'report.json'}")
        sys.stdout.flush()
        return 0 if report else 1


def _line(name: str, fig: dict[str, Any]) -> str:
    ok = "ok" if fig["success_clip"] else f"failed at {fig['failed_at_s']:.1f} s"
    line = (f"{name}: {ok}, MPJPE {fig['mpjpe_mm']:.0f} mm, G-MPJPE {fig['g_mpjpe_mm']:.0f} mm, "
            f"{fig['cpu_s_per_motion_s']:.1f} CPU-s per motion-s")
    drop = fig.get("reference_drop_beyond_fall_mm_s")  # absent from clips planned before
    if drop:
        line += f"; its reference drops {drop:.0f} mm per second beyond free fall"
    return line


@retarget.hookimpl
def register_commands(register) -> None:
    register(ExpertCommand)
