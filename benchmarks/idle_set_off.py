"""Setting off from standing idle: a run on held-out clips that start from rest, begun in the
reference's pose (as ``retarget eval`` begins) and in the character's idle pose (as a live
session begins).

    python benchmarks/idle_set_off.py pretrained:human-teacher --kinds walk,turn --max-clips 8
    python benchmarks/idle_set_off.py RUN --checkpoint RUN/checkpoints/ckpt-0000100.pt

Each held-out take of ``--style`` (default ``normal``) is made to set off from standing still
(:mod:`retarget.motion.rest_ends`: a double-support pose held 0.5 s, then the take's clock ramped
to full speed over 1 s). Every clip is run twice, from its first frame: once with the body in
the reference's pose and at its speed (reference state initialisation), once standing in the
idle pose where ``retarget serve`` and ``play --input`` start the avatar, turned to the
reference's heading (``env.idle_starts`` trains this start). A run fails when the mean body
position error exceeds 0.5 m at any frame (PHC's rule). Prints the share of clips tracked to
the end and the mean time to failure per kind and start, writes JSON.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from heldout_eval import corpus_files, write_rest_ends

FAIL_M = 0.5


def run_starts(run: str, folder: Path, idle: bool, checkpoint: str | None) -> dict:
    """Every clip of ``folder`` from its first frame, one environment each."""
    import torch

    import retarget
    from retarget.env.idle_starts import stand_under
    from retarget.kinds.capabilities import Acting, require
    from retarget.train.load import load_run

    registry = retarget.load_plugins()
    count = len(list(folder.glob("*.bvh")))
    loaded = load_run(run, registry, num_envs=count, motions=str(folder),
                      checkpoint=checkpoint,
                      assignments=["motions.exclude=[]", "motions.rest_ends=false"])  # fmt: skip
    env = loaded.env
    act = require(loaded.algorithm, Acting).act
    lib = env.library
    assert lib.num_clips == count, "one library clip per file"
    clips, frames = torch.arange(count), torch.zeros(count, dtype=torch.long)
    if idle:
        rows = lib.rows(clips, frames)[:, 0].numpy()
        qpos = stand_under(env.idle_qpos(env.sim.settings.control_hz), env.reference.qpos64[rows])
        qpos[:, 2] += env.options.reset_lift
        env.place_state(clips, clips, frames, qpos, np.zeros_like(env.reference.qvel64[rows]))
        obs = env.observe_now()
    else:
        obs = env.place(clips, frames)
    lengths = lib.length.numpy() - 1
    failed_at = np.full(count, -1)
    with torch.no_grad():
        for t in range(int(lengths.max())):
            obs, *_ = env.step(act(obs))
            ctx = env.last_context
            err = (ctx.sim.body_pos - ctx.ref.pose.body_pos).norm(dim=-1).mean(dim=-1).numpy()
            new = (err > FAIL_M) & (failed_at < 0) & (t < lengths)
            failed_at[new] = t
    hz = env.sim.settings.control_hz
    ok = failed_at < 0
    return {
        "clips": count,
        "success": float(ok.mean()),
        "time_to_failure_s": float(np.where(ok, lengths, failed_at).mean() / hz),
        "seconds": float(lengths.mean() / hz),
        "per_clip": {n: (None if f < 0 else f / hz) for n, f in zip(lib.names, failed_at,
                                                                    strict=True)},
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", help="run directories or pretrained:NAME")
    parser.add_argument("--style", default="normal", help="held-out style (default normal)")
    parser.add_argument("--kinds", default="walk,turn", help="comma-separated kinds")
    parser.add_argument("--max-clips", type=int, default=8, help="at most this many per kind")
    parser.add_argument("--checkpoint", help="a checkpoint file of the (one) run")
    parser.add_argument("--out", type=Path, help="JSON of every figure")
    args = parser.parse_args()
    results: dict[str, dict] = {}
    for run in args.runs:
        results[run] = {}
        print(f"\n{run}: held-out style '{args.style}', set off from standing")
        print(f"{'kind':8} {'start':9} {'clips':>5} {'success':>7} {'fails at s':>10} {'of s':>5}")
        for kind in args.kinds.split(","):
            folder = Path(tempfile.mkdtemp(prefix="set-off-"))
            try:
                if not write_rest_ends(corpus_files(args.style, kind, args.max_clips), folder,
                                       "from_rest"):  # fmt: skip
                    print(f"{kind:8} no clip of this kind sets off from standing")
                    continue
                for start in ("reference", "idle"):
                    r = run_starts(run, folder, start == "idle", args.checkpoint)
                    results[run][f"{kind} {start}"] = r
                    print(f"{kind:8} {start:9} {r['clips']:5d} {r['success']:7.2f} "
                          f"{r['time_to_failure_s']:10.2f} {r['seconds']:5.1f}", flush=True)
            finally:
                shutil.rmtree(folder, ignore_errors=True)
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
