"""Run directories from elsewhere: a lock file that is not text or asks YAML to build Python
objects, and a checkpoint that is not a retarget checkpoint, are refused naming the file."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from retarget.cli.main import main


def _run(tmp_path: Path, lock: bytes) -> Path:
    run = tmp_path / "runs" / "odd" / "20260101-000000"
    (run / "checkpoints").mkdir(parents=True)
    (run / "recipe.lock.yaml").write_bytes(lock)
    return run


@pytest.mark.parametrize(
    "argv", [["eval"], ["play", "--out", "x.gif"], ["export", "--onnx"]]
)
def test_a_lock_file_that_is_not_utf8_is_refused(tmp_path, capsys, argv) -> None:
    run = _run(tmp_path, b"character: human\n\xff\xfe\x00 name: \x81\n")
    assert main([argv[0], str(run), *argv[1:]]) == 2
    err = capsys.readouterr().err
    assert "not UTF-8" in err and "recipe.lock.yaml" in err and "Traceback" not in err


def test_a_lock_file_with_python_tags_builds_nothing(tmp_path, capsys) -> None:
    target = tmp_path / "pwned"
    lock = f"character: !!python/object/apply:os.system ['touch {target}']\n".encode()
    run = _run(tmp_path, lock)
    assert main(["eval", str(run)]) == 2
    err = capsys.readouterr().err
    assert "invalid YAML" in err and "recipe.lock.yaml" in err
    assert not target.exists()


def test_a_checkpoint_that_is_not_retargets_is_refused(tmp_path, capsys) -> None:
    run = _run(tmp_path, b"character: human\nsensors: [three_point]\nalgorithm: ppo\n")
    torch.save({"state_dict": {"w": torch.zeros(2)}}, run / "checkpoints" / "ckpt-0000001.pt")
    assert main(["eval", str(run), "--num-envs", "2"]) == 2
    err = capsys.readouterr().err
    assert "not a retarget checkpoint" in err and "ckpt-0000001.pt" in err
