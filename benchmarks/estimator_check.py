"""A pose estimator's uncertainty calibration, its behaviour when controllers are lost, and its
speed (one core, batch 1).

Run: ``.venv/bin/python benchmarks/estimator_check.py RUN --motions DIR [--lost 1.0]``

* **Calibration**: over every frame of the clips, the Spearman rank correlation between each
  joint's predicted position std and its real position error (all joints and frames pooled,
  and the mean of the per-joint correlations over frames), plus which joints the estimator
  is least sure of.
* **Lost controllers**: the same frames with both controllers frozen in blocks of ``--lost``
  seconds (each block holds its first pose, as a headset runtime reports hands that left the
  cameras' view); the hands' predicted std and real error, against the tracked case.
* **Speed**: frames/s of the exported network on one thread, torch and onnxruntime.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import torch
from bench_realtime import per_call_ms  # the same timing as the real-time benchmark

from retarget.learn.estimator import DeployedEstimator
from retarget.learn.pose_samples import forward_kinematics, pose_targets, sensor_inputs
from retarget.motion import skeleton as sk
from retarget.registry.loader import load_plugins
from retarget.train.load import load_run


def spearman(a: np.ndarray, b: np.ndarray) -> float:
    ra = np.argsort(np.argsort(a)).astype(float)
    rb = np.argsort(np.argsort(b)).astype(float)
    return float(np.corrcoef(ra, rb)[0, 1])


def errors(env, learner, rows: torch.Tensor) -> tuple[np.ndarray, np.ndarray]:
    """Per-joint position error and predicted std ``(R, J)``, metres."""
    out, frame = learner.estimate_rows(rows)
    target = pose_targets(env, rows, frame)
    pos = forward_kinematics(out.root_pos, out.matrices, target.heights)
    err = (pos - target.positions).norm(dim=-1).numpy()
    return err, torch.exp(0.5 * out.pos_logvar).numpy()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run")
    parser.add_argument("--motions", required=True)
    parser.add_argument("--lost", type=float, default=1.0, help="seconds the hands are frozen")
    args = parser.parse_args()
    torch.set_num_threads(1)
    loaded = load_run(args.run, load_plugins(), num_envs=1, motions=args.motions)
    env, learner = loaded.env, loaded.algorithm.pose_estimator()
    lib = env.library
    rows = torch.arange(lib.num_frames)
    err, std = errors(env, learner, rows)
    print(f"{loaded.run}: {lib.num_clips} clips, {lib.num_frames} frames at {lib.fps:.0f} Hz")
    print(f"MPJPE {err.mean() * 1e3:.1f} mm; predicted std mean {std.mean() * 1e3:.1f} mm")
    pooled = spearman(std.ravel(), err.ravel())
    print(f"Spearman(std, error), all joints and frames pooled: {pooled:.3f}")
    per_frame = [spearman(std[i], err[i]) for i in range(0, len(rows), 5)]
    print(f"Spearman over joints within a frame, mean: {np.nanmean(per_frame):.3f}")
    by_joint_err, by_joint_std = err.mean(0), std.mean(0)
    joints = spearman(by_joint_std, by_joint_err)
    print(f"Spearman of the joints' mean std vs mean error: {joints:.3f}")
    order = np.argsort(-by_joint_std)
    print(
        "least certain joints (std mm / error mm): "
        + ", ".join(
            f"{sk.JOINT_NAMES[j]} {by_joint_std[j] * 1e3:.0f}/{by_joint_err[j] * 1e3:.0f}"
            for j in order[:5]
        )
    )

    hands = [sk.joint_index("left_wrist"), sk.joint_index("right_wrist")]
    lag = max(1, round(args.lost * lib.fps))
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    frame = rows - lib.start[clip]
    held = lib.start[clip] + (frame // lag) * lag  # the first row of each `lag`-frame block
    saved = lib.devices.clone()
    lib.devices[:, 1:] = saved[held, 1:]  # the hands hold still for up to `lag` frames
    try:
        lost_err, lost_std = errors(env, learner, rows)
    finally:
        lib.devices.copy_(saved)
    print(
        f"hands tracked: std {std[:, hands].mean() * 1e3:.0f} mm, error "
        f"{err[:, hands].mean() * 1e3:.0f} mm; controllers frozen {args.lost:g} s: std "
        f"{lost_std[:, hands].mean() * 1e3:.0f} mm, error {lost_err[:, hands].mean() * 1e3:.0f} mm"
    )
    rank = np.argsort(np.argsort(-lost_std.mean(0)))
    print(
        f"with frozen controllers the wrists rank {rank[hands[0]] + 1} and {rank[hands[1]] + 1} "
        f"of {sk.NUM_JOINTS} joints by predicted std"
    )

    net = DeployedEstimator(learner.net).eval()
    one, _ = sensor_inputs(env, rows[:1])
    with torch.inference_mode():
        torch_ms = per_call_ms(lambda: net(one), 2000)
    line = f"speed, batch 1, one thread: torch {1e3 / torch_ms:,.0f} frames/s ({torch_ms:.3f} ms)"
    try:
        import onnxruntime as ort

        from retarget.deploy import export_onnx

        with tempfile.TemporaryDirectory() as tmp:
            exported = export_onnx(loaded.algorithm, Path(tmp) / "e.onnx",
                                   {"obs_dim": int(one.shape[1])})  # fmt: skip
            options = ort.SessionOptions()
            options.intra_op_num_threads = options.inter_op_num_threads = 1
            session = ort.InferenceSession(str(exported.onnx), options)
            feed = {"obs": one.numpy()}
            onnx_ms = per_call_ms(lambda: session.run(None, feed), 2000)
        line += f"; onnxruntime {1e3 / onnx_ms:,.0f} frames/s ({onnx_ms:.3f} ms)"
    except ImportError:
        pass
    print(line)


if __name__ == "__main__":
    main()
