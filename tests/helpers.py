"""What tests share: the repository, the shared motion-capture clips, state comparison."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from retarget.motion.shared_data import shared_data

REPO = Path(__file__).resolve().parents[1]
SHARED_MOCAP = shared_data("mocap")

# A recipe that trains in a second: human, three-point sensors, tiny networks, 4 environments.
TINY = """\
extends: null
name: tiny
seed: 7
character: human
sensors: [three_point]
rewards:
  joint_pos: {weight: 4.0, k: 25.0}
  link_pos: {weight: 2.5, k: 6.0}
  action_diff: {weight: 1.5, k: 10.0}
  fail_penalty: {weight: 1.0, value: -5.0}
terminations:
  fall: {}
  episode_cap: {max_steps: 20}
algorithm:
  type: ppo
  rollout_steps: 8
  actor_hidden: [32]
  critic_hidden: [32]
  minibatch_size: 16
  epochs: 2
env: {num_envs: 4}
sim: {threads: 1}
"""


# The tiny recipe as a residual full-body teacher (PD targets, reference + residual actions).
TINY_TEACHER = (
    TINY.replace("name: tiny", "name: teacher")
    .replace("sensors: [three_point]", "sensors: [full_body, reference_action]")
    .replace("  type: ppo\n", "  type: ppo\n  residual: reference_action\n")
    .replace("sim: {threads: 1}", "sim: {threads: 1, actuation: pd}")
)


def assert_state_equal(a: Any, b: Any, where: str = "state") -> None:
    """Bit-for-bit equality of nested checkpoint states (tensors, arrays, dicts, lists),
    naming the first differing entry."""
    import torch

    if isinstance(a, torch.Tensor):
        assert torch.equal(a, b), where
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            assert_state_equal(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_state_equal(x, y, f"{where}[{i}]")
    elif hasattr(a, "shape"):  # numpy arrays inside env state
        assert (a == b).all(), where
    else:
        assert a == b, where


def image_student(tmp_path: Path, steps: int) -> Path:
    """A tiny headset + aria-camera (2 x 16 x 24) student distilled from a tiny teacher."""
    teacher = tmp_path / "teacher.yaml"
    teacher.write_text(TINY_TEACHER)
    from retarget.cli.main import main

    assert main(["train", str(teacher), "--steps", str(steps), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    student = tmp_path / "student.yaml"
    cams = "{type: ego_cameras, rig: aria, width: 24, height: 16}"
    student.write_text(TINY.replace("name: tiny", "name: eyes")
                       .replace("sensors: [three_point]", f"sensors: [hmd, {cams}]"))
    assert main(["train", str(student), "--teacher", str(tmp_path / "teacher" / "latest"),
                 "--steps", str(steps), "--runs-dir", str(tmp_path), "--no-tensorboard",
                 "--set", "algorithm.minibatch_size=16",
                 "--set", "sim.actuation=pd"]) == 0  # fmt: skip
    return tmp_path / "eyes" / "latest"
