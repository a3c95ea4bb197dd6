"""Does the character step over (or onto) the boxes on its path, or hit them and fall?

What ``retarget play`` shows for a scene with props, in numbers, box by box: the policy drives
environment 0 from the start of one clip (no early termination, as in ``play``) and, for each
prop box, this reports its height, whether a foot passed above its footprint (and the lowest
clearance then), how many control steps a foot pushed on its top or against a side, and when
the character fell (body top below half its starting height). Usage::

    .venv/bin/python benchmarks/box_crossings.py runs/boxes/warm/latest \\
        --motions runs/scene_pd/motions/train --clip 4 --seconds 8 \\
        [--set scene.height=[0.05,0.25]]

A box is *stepped over* when a foot passed above it with positive clearance and never pushed
on it, *stepped on* when a foot pushed on its top (possibly grazing a side on the way), *hit a
side* when a foot pushed only against a side (a stumble).
"""

from __future__ import annotations

import argparse
from collections import defaultdict

import mujoco
import numpy as np
import torch
from rollout_args import add_rollout_args

from retarget.eval.prop_clearance import foot_clearance, world_boxes
from retarget.eval.prop_hits import foot_geoms, foot_prop_contacts, prop_geoms
from retarget.registry.loader import load_plugins
from retarget.render.policy_video import copy_env_pose
from retarget.train.load import load_run


def crossings(args: argparse.Namespace) -> list[dict]:
    """One row per prop geom: height, feet-over steps, lowest clearance, top and side steps."""
    loaded = load_run(args.run, load_plugins(strict=False), num_envs=1, motions=args.motions,
                      assignments=args.assignments)  # fmt: skip
    env, lib = loaded.env, loaded.env.library
    model = env.world.model
    hz = env.sim.settings.control_hz
    steps = int(min(args.seconds * hz, int(lib.length[args.clip]) - 2))
    data = mujoco.MjData(model)
    feet, props = foot_geoms(model, env.layout), prop_geoms(model)
    ids = np.nonzero(props)[0]
    obs = env.place(torch.full((1,), args.clip), torch.full((1,), 0))
    top0 = float(env.sim.state.body_pos[0, :, 2].max())
    over = np.zeros(len(ids), dtype=int)
    lowest = np.full(len(ids), np.inf)
    pushes: dict[tuple[int, bool], int] = defaultdict(int)
    fell = None
    with torch.no_grad():
        for t in range(steps):
            obs, *_ = env.step(loaded.algorithm.act(obs))
            copy_env_pose(env, 0, data)
            clearance = foot_clearance(model, data, feet, props)
            over += np.isfinite(clearance)
            lowest = np.minimum(lowest, clearance)
            touching = env.sim.each_env(lambda d: foot_prop_contacts(model, d, feet, props))[0]
            for key in set(touching):  # control steps, not contact points
                pushes[key] += 1
            if fell is None and float(env.sim.state.body_pos[0, :, 2].max()) < 0.5 * top0:
                fell = t / hz
    heights = world_boxes(model, data, ids)[4]  # the boxes do not move
    ending = f"fell at {fell:.1f} s" if fell is not None else "no fall"
    print(f"{args.run}: {lib.names[args.clip]}, {steps / hz:.1f} s; {ending}")
    rows = []
    for k, g in enumerate(ids):
        top, side = pushes[(int(g), True)], pushes[(int(g), False)]
        if top:
            verdict = "stepped on" + (", grazed a side" if side else "")
        elif side:
            verdict = "hit a side" + (", foot over it" if over[k] else "")
        elif over[k]:
            verdict = "stepped over" if lowest[k] > 0 else "touched"
        else:
            verdict = "not reached"
        rows.append({"box": model.geom(g).name or str(g), "height": float(heights[k]),
                     "over_steps": int(over[k]), "clearance": float(lowest[k]),
                     "top_steps": top, "side_steps": side, "verdict": verdict})  # fmt: skip
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_rollout_args(parser)
    parser.add_argument("--set", dest="assignments", action="append", default=[],
                        metavar="PATH=VALUE",
                        help="change the run's recipe, e.g. scene.height=[0.05,0.25]")  # fmt: skip
    args = parser.parse_args()
    rows = crossings(args)
    head = ("box", "top m", "foot over", "clear cm", "on top", "side")
    print(f"{head[0]:<20}" + "".join(f"{h:>10}" for h in head[1:]) + "  verdict")
    for r in rows:
        clear = f"{100 * r['clearance']:.1f}" if np.isfinite(r["clearance"]) else "-"
        print(f"{r['box']:<20}{r['height']:>10.2f}{r['over_steps']:>10}{clear:>10}"
              f"{r['top_steps']:>10}{r['side_steps']:>10}  {r['verdict']}")  # fmt: skip


if __name__ == "__main__":
    main()
