"""Real-time cost of one 36 Hz frame for one user: observation + policy + physics, batch 1, on
one core. Target: <= 2 ms per frame (>= 14x real time).

Run: ``.venv/bin/python benchmarks/bench_realtime.py [--character human] [--sensors three_point]
[--run RUNDIR] [--frames 1000]``

Measured in the same run, all on one thread:

* ``physics``: ``substeps`` x ``mujoco.mj_step`` on one plain ``MjData`` of the same compiled
  model: the floor any deployment pays.
* ``policy (torch)`` / ``policy (onnxruntime)``: the exported actor (normaliser included) on
  one observation (onnxruntime only when the ``export`` extra is installed).
* ``env frame``: a whole ``RetargetEnv.step`` with batch 1 plus the torch policy. This is an
  upper bound on deployment: it also computes the training reference, rewards and
  terminations, which a headset application does not need; its observation share (the actor
  group only: sensors + proprioception, as deployed) is printed.
* ``deploy_ms`` = physics + policy (onnxruntime when available) + observations: the frame cost
  of a headset application.

Without ``--run`` the policy is an untrained PPO actor of the paper's sizes (same cost).
"""

from __future__ import annotations

import argparse
import statistics
import time

import mujoco
import numpy as np
import torch

from retarget.recipe import load
from retarget.registry.loader import load_plugins


def per_call_ms(fn, repeats: int) -> float:
    """Median of 5 blocks of ``repeats`` calls, in ms per call."""
    for _ in range(max(5, repeats // 20)):
        fn()
    blocks = []
    for _ in range(5):
        t = time.perf_counter()
        for _ in range(repeats):
            fn()
        blocks.append((time.perf_counter() - t) / repeats * 1e3)
    return statistics.median(blocks)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--character", default="human")
    parser.add_argument("--sensors", default="three_point")
    parser.add_argument("--run", help="a trained run (default: an untrained policy)")
    parser.add_argument("--frames", type=int, default=400)
    args = parser.parse_args()
    torch.set_num_threads(1)
    registry = load_plugins()

    if args.run:
        from retarget.train.load import load_run

        loaded = load_run(args.run, registry, num_envs=1, terminations=True)
        env, algorithm = loaded.env, loaded.algorithm
    else:
        from retarget.env.build import env_from_recipe

        shorthands = {"character": args.character, "sensors": args.sensors}
        # deployment computes only what the actor reads: sensors + proprioception (no critic)
        actor = ", ".join([*args.sensors.split(","), "proprio"])
        sets = ["sim.threads=1", f"env.groups={{actor: [{actor}]}}"]
        resolved = load(None, registry, shorthands=shorthands, assignments=sets)
        env = env_from_recipe(resolved, num_envs=1, threads=1)
        algorithm = resolved.component("algorithm").instantiate()
        algorithm.setup(env, torch.Generator().manual_seed(0))
    group, policy = algorithm.policy()
    substeps = env.sim.settings.substeps
    print(
        f"{env.character.name}, obs {env.obs_dims[group]}, actions {env.action_dim}, "
        f"{substeps} substeps at {env.sim.settings.control_hz:.0f} Hz, torch {torch.__version__}"
    )

    # physics floor: one MjData of the same model
    model = env.sim.model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(0)

    def physics() -> None:
        data.ctrl[:] = rng.uniform(-0.05, 0.05, model.nu)
        for _ in range(substeps):
            mujoco.mj_step(model, data)
        if not np.isfinite(data.qpos).all():
            mujoco.mj_resetData(model, data)
            mujoco.mj_forward(model, data)

    physics_ms = per_call_ms(physics, args.frames)

    obs = env.reset()
    one = obs[group][:1].float().contiguous()
    with torch.inference_mode():
        torch_ms = per_call_ms(lambda: policy(one), args.frames)

    onnx_ms = None
    try:
        import tempfile
        from pathlib import Path

        import onnxruntime as ort

        from retarget.deploy import export_onnx

        with tempfile.TemporaryDirectory() as tmp:
            dims = {"obs_dim": int(one.shape[1])}  # an image actor starts with a conv layer
            exported = export_onnx(algorithm, Path(tmp) / "policy.onnx", dims)
            options = ort.SessionOptions()
            options.intra_op_num_threads = options.inter_op_num_threads = 1
            session = ort.InferenceSession(str(exported.onnx), options)
            feed = {"obs": one.numpy()}
            onnx_ms = per_call_ms(lambda: session.run(None, feed), args.frames)
    except ImportError:
        pass

    state = {"obs": obs}

    def frame() -> None:
        with torch.inference_mode():
            action = algorithm.act(state["obs"])
        state["obs"] = env.step(action)[0]

    before = dict(env.seconds)
    start_steps = env.total_steps
    env_ms = per_call_ms(frame, args.frames)
    calls = env.total_steps - start_steps
    obs_ms = (env.seconds["observations"] - before["observations"]) / calls * 1e3

    deploy_ms = physics_ms + (onnx_ms if onnx_ms is not None else torch_ms) + obs_ms
    frame_budget = 1e3 / env.sim.settings.control_hz
    print(f"{'physics (mj_step x substeps)':<34} {physics_ms:7.3f} ms")
    print(f"{'policy (torch, batch 1)':<34} {torch_ms:7.3f} ms")
    if onnx_ms is not None:
        print(f"{'policy (onnxruntime, batch 1)':<34} {onnx_ms:7.3f} ms")
    print(f"{'observations (in env frame)':<34} {obs_ms:7.3f} ms")
    print(f"{'env frame (env.step + policy)':<34} {env_ms:7.3f} ms")
    print(f"{'observations / physics':<34} {obs_ms / physics_ms:7.2f}")
    print(
        f"deploy_ms={deploy_ms:.3f} env_frame_ms={env_ms:.3f} physics_ms={physics_ms:.3f} "
        f"realtime_x={frame_budget / deploy_ms:.1f} env_realtime_x={frame_budget / env_ms:.1f}"
    )


if __name__ == "__main__":
    main()
