"""The tracking expert (``retarget expert``) on a held-out style of the Bandai Namco corpus,
by kind of motion: per-clip success, MPJPE, G-MPJPE and CPU-seconds per motion-second.

    python benchmarks/expert_heldout.py --style normal --max-clips 3 --out results/expert.json
    python benchmarks/expert_heldout.py --character dino --kinds walk,gesture --max-clips 2

The planner needs no training, so every style is unseen to it; ``normal`` is the style the
trained policies hold out, which makes the figures comparable with ``heldout_eval.py``.
``--max-clips`` takes every k-th clip of a kind; ``--seconds`` caps each clip. The planned
clips stay in ``--expert-dir`` (resumable: a second call plans only what is missing).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from heldout_eval import KINDS, corpus_files


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--style", default="normal")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--character", default="human")
    parser.add_argument("--max-clips", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--method", default="beam", help="planner plugin (beam, beam_ilqr)")
    parser.add_argument("--planner", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="PATH=VALUE",
                        help="recipe field for the planner's env, e.g. motions.level_feet=false")
    parser.add_argument("--expert-dir", default=None, help="default: runs/expert-CHAR-STYLE")
    parser.add_argument("--out", default=None, help="JSON of the figures")
    args = parser.parse_args()
    out = Path(args.expert_dir or f"runs/expert-{args.character}-{args.style}")
    kinds = [k for k in args.kinds.split(",") if k]
    figures: dict[str, dict] = {}
    for kind in kinds:
        files = corpus_files(args.style, kind, args.max_clips)
        cmd = [sys.executable, "-m", "retarget", "expert", *map(str, files), "--out", str(out),
               "--character", args.character, "--seconds", str(args.seconds),
               "--jobs", str(args.jobs), "--method", args.method,
               *(f"--planner={p}" for p in args.planner),
               *(f"--set={a}" for a in args.sets)]  # fmt: skip
        subprocess.run(cmd, check=True)
        report = json.loads((out / "report.json").read_text())["clips"]
        rows = [report[f.stem] for f in files if f.stem in report]
        seconds = sum(r["motion_seconds"] for r in rows)
        figures[kind] = {
            "clips": len(rows),
            "motion_seconds": seconds,
            "success_clip": sum(r["success_clip"] for r in rows) / max(len(rows), 1),
            "mpjpe_mm": sum(r["mpjpe_mm"] for r in rows) / max(len(rows), 1),
            "g_mpjpe_mm": sum(r["g_mpjpe_mm"] for r in rows) / max(len(rows), 1),
            "cpu_s_per_motion_s": sum(r["cpu_seconds"] for r in rows) / max(seconds, 1e-9),
            "reference_drop_beyond_fall_mm_s": sum(
                r.get("reference_drop_beyond_fall_mm_s", 0.0) for r in rows) / max(len(rows), 1),
            "per_clip": rows,
        }
    print(f"\nexpert, {args.character}, held-out style {args.style!r}")
    print(f"{'kind':8} {'clips':>5} {'success':>8} {'MPJPE mm':>9} {'G-MPJPE mm':>11} "
          f"{'CPU-s/motion-s':>15} {'ref. drop mm/s':>15}")
    for kind, f in figures.items():
        print(f"{kind:8} {f['clips']:5d} {f['success_clip']:8.2f} {f['mpjpe_mm']:9.1f} "
              f"{f['g_mpjpe_mm']:11.1f} {f['cpu_s_per_motion_s']:15.1f} "
              f"{f['reference_drop_beyond_fall_mm_s']:15.1f}")
    if args.out:
        Path(args.out).write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
