"""The reference as open-loop PD targets, with and without its feedforward: how far the
joints sag and how long the body stays up when nothing corrects it.

    python benchmarks/feedforward_open_loop.py --characters human,dino,oppy --max-clips 4 \
        --out benchmarks/results/feedforward_open_loop.json

For each held-out clip (style ``normal`` of ``../shared/data/mocap_corpus``) and each share
of ``SimState.pd_feedforward`` (0: the reference angles alone, the base the packaged teachers
used; 1: plus the reference's inverse-dynamics torque and damping over kp) the character
starts on the reference and is driven frame after frame by the reference's targets, with no
policy: the mean absolute joint error over the first second, and the share of the clip (its
first ``--seconds``) before the root drops below half the reference's height. The base a
residual policy starts from is this open-loop controller, so what it holds is what the policy
need not learn.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import mujoco
import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).parent))
from heldout_eval import KINDS, corpus_files

RECIPES = {"human": "teacher", "dino": "dino_teacher", "oppy": "oppy_teacher"}


def open_loop(env, share: float, seconds: float) -> tuple[float, float]:
    """(mean joint error over the first second in radians, share of the frames standing)."""
    model, ref, lay = env.sim.model, env.reference, env.layout
    joints = model.actuator_trnid[: lay.nu, 0]
    scale = np.maximum(np.abs(model.jnt_range[joints]).max(axis=1), 1e-6)
    qadr = model.jnt_qposadr[joints]
    hz = env.sim.settings.control_hz
    frames = min(ref.num_frames, int(seconds * hz))
    ff = ref.pose(torch.arange(frames)).pd_feedforward.double().numpy()
    data = mujoco.MjData(model)
    data.qpos[: lay.nq], data.qvel[: lay.nv] = ref.qpos64[0], ref.qvel64[0]
    errors, up = [], 1.0
    for f in range(frames):
        data.ctrl[: lay.nu] = np.clip((ref.qpos64[f, qadr] + share * ff[f]) / scale, -1, 1)
        for _ in range(env.sim.settings.substeps):
            mujoco.mj_step(model, data)
        errors.append(np.abs(data.qpos[qadr] - ref.qpos64[f, qadr]).mean())
        if data.qpos[2] < 0.5 * ref.qpos64[f, 2]:
            up = f / frames
            break
    return float(np.mean(errors[: int(hz)])), up


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--characters", default="human,dino,oppy")
    parser.add_argument("--kinds", default="walk,turn,run,gesture")
    parser.add_argument("--style", default="normal")
    parser.add_argument("--max-clips", type=int, default=4)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--shares", default="0,1")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins

    registry = load_plugins()
    shares = [float(s) for s in args.shares.split(",")]
    kinds = [k for k in args.kinds.split(",") if k]
    unknown = [k for k in kinds if k not in KINDS]
    if unknown:
        parser.error(f"unknown kinds {unknown}; known: {', '.join(KINDS)}")
    results: dict[str, dict] = {}
    print(f"{'character':9} {'kind':8} " + " ".join(
        f"{'share ' + str(s):>22}" for s in shares) + "   (joint error rad / share of the clip up)")
    for character in args.characters.split(","):
        results[character] = {}
        for kind in kinds:
            rows = {s: [] for s in shares}
            for clip in corpus_files(args.style, kind, args.max_clips):
                recipe = load(RECIPES[character], registry, shorthands={"motions": str(clip)},
                              assignments=["env.num_envs=1"])  # fmt: skip
                env = env_from_recipe(recipe, registry=registry, threads=1)
                for s in shares:
                    rows[s].append(open_loop(env, s, args.seconds))
            summary = {str(s): {"joint_error_rad": float(np.mean([r[0] for r in v])),
                                "share_up": float(np.mean([r[1] for r in v])),
                                "clips": len(v)} for s, v in rows.items()}  # fmt: skip
            results[character][kind] = summary
            cells = [f"{summary[str(s)]['joint_error_rad']:>12.3f} / "
                     f"{summary[str(s)]['share_up']:>7.2f}" for s in shares]  # fmt: skip
            print(f"{character:9} {kind:8} " + " ".join(cells))
    if args.out:
        args.out.write_text(json.dumps({"style": args.style, "seconds": args.seconds,
                                        "results": results}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
