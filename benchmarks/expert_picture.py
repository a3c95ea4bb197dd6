"""A contact sheet of one clip the expert planned: its actions replayed in the env (the
simulated character) with the reference as a blue ghost skeleton, a few frames across the clip.

    python benchmarks/expert_picture.py runs/expert walk_normal_001 --out results/x.png

The env is ``--recipe`` (the packaged ``teacher`` recipe, as for ``retarget expert``) with the
physics and the clip reading the expert directory recorded; replaying the recorded actions
from the placed first frame goes through the planned states (the expert's tests check this),
so the picture is the plan itself.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("expert_dir", type=Path)
    parser.add_argument("clip", help="clip name, or a unique part of it")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--recipe", default="teacher")
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--size", type=int, nargs=2, default=(320, 320), metavar=("W", "H"))
    args = parser.parse_args()

    from retarget import load_plugins
    from retarget.env.build import env_from_recipe
    from retarget.expert.store import read_header
    from retarget.recipe import load
    from retarget.render.gl import ensure_offscreen
    from retarget.render.motion import contact_sheet, write_png
    from retarget.render.policy_video import render_rollout

    header = read_header(args.expert_dir)
    found = sorted(p for p in (args.expert_dir / "clips").glob("*.npz") if args.clip in p.stem)
    if len(found) != 1:
        parser.error(f"{args.clip!r} matches {len(found)} planned clips in {args.expert_dir}")
    name = found[0].stem
    motion = next((args.expert_dir / "motions").glob(f"{name}.*"), None)
    if motion is None:
        parser.error(f"{args.expert_dir / 'motions'} holds no copy of {name}")
    with np.load(found[0], allow_pickle=False) as z:
        actions = np.asarray(z["actions"], dtype=np.float32)
    ensure_offscreen()
    registry = load_plugins(strict=False)
    recorded = header["recipe"]
    sets = ["env.num_envs=1"] + [
        f"{section}.{key}={json.dumps(value)}"
        for section in ("sim", "motions")
        for key, value in (recorded.get(section) or {}).items()
        if isinstance(value, bool | int | float | str) and key != "threads"
    ]  # the physics and clip reading the expert planned with
    recipe = load(args.recipe, registry, shorthands={"character": header["character"],
                  "motions": str(motion)}, assignments=sets)  # fmt: skip
    env = env_from_recipe(recipe, registry=registry, threads=1)
    step = iter(actions)

    def replay(_obs):
        return torch.from_numpy(next(step, actions[-1]))[None]

    seconds = len(actions) / env.sim.settings.control_hz
    frames = render_rollout(env, replay, 0, seconds=seconds, width=args.size[0],
                            height=args.size[1])  # fmt: skip
    pick = np.linspace(0, len(frames) - 1, args.frames).round().astype(int)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_png(args.out, contact_sheet(np.stack([frames[i] for i in pick]), columns=4))
    print(f"{name}: {len(frames)} frames, {seconds:.1f} s -> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
