"""iLQR refinement (``beam_ilqr``'s second stage) of paths an expert directory already holds.

``retarget expert --method beam_ilqr`` plans the beam search and then refines its path; the
beam part is deterministic for given settings, so refining the paths of a ``beam`` directory
planned with the same settings gives what ``beam_ilqr`` would, without planning the beam
again. Prints, per clip and per kind, the beam's figures and the refined ones, and the
CPU-seconds per motion-second of each stage (the beam's as its directory recorded them):

    python benchmarks/expert_refine.py runs/expert-heldout-p2 runs/expert-heldout-p2b \
        --out results/expert_refine.json [--set iterations=8] [--max-clips 2]

``--write DIR`` (one source directory) also writes the refined paths as an expert directory,
the one ``retarget expert --method beam_ilqr`` with the source's beam settings writes (the
beam's other members kept as demonstrations), which ``retarget train --expert DIR`` reads;
it resumes clip by clip.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from fnmatch import fnmatch
from pathlib import Path

import numpy as np
import yaml
from heldout_eval import KINDS


def kind_of(name: str) -> str:
    """The kind (``heldout_eval.KINDS``) of a corpus clip named ``name``."""
    for kind, motions in KINDS.items():
        if any(f"_{motion}_" in name for motion in motions):
            return kind
    return "other"


def target_dir(root: Path, write: Path, overrides: dict) -> str:
    """Start ``write`` as ``beam_ilqr``'s directory for ``root``'s clips; its settings key."""
    import shutil

    from retarget.expert.config import IlqrConfig
    from retarget.expert.store import read_header, settings_key, write_header

    header = read_header(root)
    planner = {"beam": header["planner"],
               "ilqr": IlqrConfig(**overrides).model_dump(mode="json")}  # fmt: skip
    new = {"recipe": header["recipe"], "planner": planner, "character": header["character"],
           "method": "beam_ilqr"}  # fmt: skip
    write_header(write, new)
    for motion in (root / "motions").iterdir():
        if not (write / "motions" / motion.name).exists():
            shutil.copyfile(motion, write / "motions" / motion.name)
    return settings_key(new)


def open_clip(root: Path, recipe_file: Path, name: str, registry, cpu_seconds: float = 0.0):
    """One planned clip of expert directory ``root``: an env of that clip alone (the
    directory's recipe, written to ``recipe_file``) and the clip's path as a ``Track`` (its
    arrays checked by ``load_track``; the beam's other members as its demos)."""
    from retarget import Track
    from retarget.env.build import env_from_recipe
    from retarget.expert.store import load_track
    from retarget.recipe import load

    motion = next((root / "motions").glob(f"{name}.*"))
    recipe = load(recipe_file, registry, shorthands={"motions": str(motion)},
                  assignments=["env.num_envs=1", "sim.threads=1"])  # fmt: skip
    env = env_from_recipe(recipe, registry=registry, num_envs=1, threads=1)
    sim = env.sim
    shapes = {k: tuple(sim.raw(k).shape[1:]) for k in sim.STATE_FIELDS}
    data = load_track(root / "clips" / f"{name}.npz", nq=shapes["qpos"][0],
                      nv=shapes["qvel"][0], nu=env.layout.nu, state_shapes=shapes)
    demos = {k[5:]: v for k, v in data.items() if k.startswith("demo_")}
    track = Track(clip=name, fps=float(data["fps"]), actions=data["actions"],
                  qpos=data["qpos"], qvel=data["qvel"], body_pos=data["body_pos"],
                  ref_body_pos=data["ref_body_pos"], ref_qpos0=data["ref_qpos0"],
                  cpu_seconds=cpu_seconds, demos=demos)  # fmt: skip
    return env, track


def refine_dir(root: Path, overrides: dict, max_clips: int | None,
               write: Path | None = None, shard: tuple[int, int] = (0, 1),
               include: str = "*") -> list[dict]:
    from retarget.expert.config import IlqrConfig
    from retarget.expert.ilqr import IlqrRefiner
    from retarget.expert.store import done_clips, read_header, write_report
    from retarget.expert.store import write_track as store_track
    from retarget.registry.loader import load_plugins

    registry = load_plugins(strict=False)
    header = read_header(root)
    report = json.loads((root / "report.json").read_text())["clips"]
    key = target_dir(root, write, overrides) if write else ""
    written = done_clips(write, key) if write else {}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        recipe_file = Path(tmp) / "recipe.yaml"
        recipe_file.write_text(yaml.safe_dump(header["recipe"]))
        for i, name in enumerate(list(report)[:max_clips]):
            before = report[name]
            if name in written or i % shard[1] != shard[0] or not fnmatch(name, include):
                continue
            env, track = open_clip(root, recipe_file, name, registry, before["cpu_seconds"])
            refiner = IlqrRefiner(env, IlqrConfig(**overrides), threads=1)
            cpu0 = time.process_time()
            refined = refiner.refine(0, track)
            spent = time.process_time() - cpu0
            after = refined.metrics()
            if write:
                written[name] = store_track(write, name, refined,
                                            {"key": key, "source": before.get("source")})
                write_report(write, written)
            seconds = after["motion_seconds"]
            rows.append({
                "clip": name, "kind": kind_of(name), "motion_seconds": seconds,
                "beam": {k: before[k] for k in ("success_clip", "mpjpe_mm", "g_mpjpe_mm",
                                                "cpu_s_per_motion_s")},
                "refined": {k: after[k] for k in ("success_clip", "mpjpe_mm", "g_mpjpe_mm")},
                "refine_cpu_s_per_motion_s": spent / seconds,
                "rounds_kept": sum(h["trial"] < h["cost"] for h in refiner.history),
                "rounds": len(refiner.history),
            })  # fmt: skip
            r = rows[-1]
            print(f"{name}: MPJPE {before['mpjpe_mm']:.1f} -> {after['mpjpe_mm']:.1f} mm, "
                  f"G-MPJPE {before['g_mpjpe_mm']:.1f} -> {after['g_mpjpe_mm']:.1f} mm, "
                  f"success {before['success_clip']} -> {after['success_clip']}, "
                  f"+{r['refine_cpu_s_per_motion_s']:.1f} CPU-s per motion-s "
                  f"({r['rounds_kept']}/{r['rounds']} rounds kept)", flush=True)
    if write:  # other shards may have written clips meanwhile: report them all
        write_report(write, done_clips(write, key))
    return rows


def summarise(rows: list[dict]) -> dict[str, dict]:
    """Per kind: clips, the beam's and the refined means, each stage's CPU-s per motion-s."""
    summary = {}
    for row in rows:
        row["kind"] = kind_of(row["clip"])
    for kind in (*KINDS, "other"):
        mine = [r for r in rows if r["kind"] == kind]
        if not mine:
            continue
        secs = sum(r["motion_seconds"] for r in mine)

        def mean(stage: str, key: str, mine=mine) -> float:
            return float(np.mean([r[stage][key] for r in mine]))

        summary[kind] = {
            "clips": len(mine),
            "beam": {k: mean("beam", k) for k in ("success_clip", "mpjpe_mm", "g_mpjpe_mm")},
            "refined": {k: mean("refined", k) for k in ("success_clip", "mpjpe_mm",
                                                          "g_mpjpe_mm")},
            "beam_cpu_s_per_motion_s": sum(r["beam"]["cpu_s_per_motion_s"] * r["motion_seconds"]
                                           for r in mine) / secs,
            "refine_cpu_s_per_motion_s": sum(r["refine_cpu_s_per_motion_s"] * r["motion_seconds"]
                                             for r in mine) / secs,
        }
    return summary


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dirs", nargs="+", type=Path, help="expert directories (beam paths)")
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                        help="refinement setting (retarget.expert.ilqr.IlqrConfig)")
    parser.add_argument("--max-clips", type=int, default=None, help="per directory")
    parser.add_argument("--out", type=Path, default=None, help="JSON of the figures")
    parser.add_argument("--write", type=Path, default=None,
                        help="write the refined paths as an expert directory (one source)")
    parser.add_argument("--include", default="*", metavar="GLOB",
                        help="only clips whose names match, e.g. '*_walk_*'")
    parser.add_argument("--shard", default="0/1", metavar="K/N",
                        help="refine only every N-th clip from the K-th (parallel processes "
                        "writing one directory)")
    args = parser.parse_args()
    k, _, n = args.shard.partition("/")
    if not (k.isdigit() and n.isdigit() and int(k) < int(n)):
        parser.error(f"--shard {args.shard!r}: expected K/N with 0 <= K < N")
    if args.write and len(args.dirs) != 1:
        parser.error("--write takes one source directory")
    overrides = {}
    for pair in args.sets:
        key, _, value = pair.partition("=")
        overrides[key] = yaml.safe_load(value)
    rows = [r for d in args.dirs for r in refine_dir(d, overrides, args.max_clips, args.write,
                                                    (int(k), int(n)), args.include)]
    summary = summarise(rows)
    print(f"\n{'kind':8} {'clips':>5} {'success':>15} {'MPJPE mm':>15} {'G-MPJPE mm':>15} "
          f"{'CPU-s/motion-s':>16}")
    for kind, s in summary.items():
        b, r = s["beam"], s["refined"]
        print(f"{kind:8} {s['clips']:5d} {b['success_clip']:6.2f} -> {r['success_clip']:5.2f} "
              f"{b['mpjpe_mm']:6.1f} -> {r['mpjpe_mm']:5.1f} {b['g_mpjpe_mm']:6.1f} -> "
              f"{r['g_mpjpe_mm']:5.1f} {s['beam_cpu_s_per_motion_s']:6.1f} + "
              f"{s['refine_cpu_s_per_motion_s']:5.1f}")
    if args.out:
        args.out.write_text(json.dumps({"settings": overrides, "summary": summary,
                                        "clips": rows}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
