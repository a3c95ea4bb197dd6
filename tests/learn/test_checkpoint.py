"""Checkpoints: exact round trip, and a SIGKILL in the middle of a write keeps the old one."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from retarget.errors import RetargetError
from retarget.train.checkpoint import load_checkpoint, save_checkpoint


def test_round_trip_is_exact(tmp_path: Path) -> None:
    g = torch.Generator().manual_seed(3)
    state = {
        "weights": torch.randn(17, 5, generator=g),
        "int": torch.arange(4),
        "rng": {
            "torch": torch.get_rng_state(),
            "numpy": np.random.get_state(),
            "generator": g.get_state(),
        },
        "counters": {"iteration": 7, "env_steps": 1234},
        "algorithm": {"actor": {"w": torch.ones(2)}},
    }
    path = save_checkpoint(tmp_path / "a" / "ckpt.pt", state)
    back = load_checkpoint(path)
    assert torch.equal(back["weights"], state["weights"])
    assert torch.equal(back["rng"]["torch"], state["rng"]["torch"])
    assert torch.equal(back["rng"]["generator"], state["rng"]["generator"])
    assert all(
        np.array_equal(np.asarray(a), np.asarray(b))
        for a, b in zip(back["rng"]["numpy"], state["rng"]["numpy"], strict=True)
    )
    assert back["counters"] == state["counters"]
    assert [p.name for p in path.parent.iterdir()] == ["ckpt.pt"]  # no temp file left


def test_unreadable_checkpoint_names_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(RetargetError, match=r"bad\.pt"):
        load_checkpoint(bad)
    with pytest.raises(RetargetError, match="not found"):
        load_checkpoint(tmp_path / "missing.pt")


WRITER = textwrap.dedent(
    """
    import sys, torch
    from retarget.train.checkpoint import save_checkpoint
    big = {"algorithm": {"w": torch.ones(150_000_000 // 4 * 2)}}  # ~300 MB: a write takes a while
    save_checkpoint(sys.argv[1], big)
    """
)


def _kill_mid_write(path: Path) -> bool:
    """Start a large save and SIGKILL it while its temp file is partly written."""
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(path)])
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            temps = list(path.parent.glob(f".{path.name}.*.tmp"))
            if temps and temps[0].stat().st_size > 1_000_000:
                os.kill(proc.pid, signal.SIGKILL)
                proc.wait()
                return bool(list(path.parent.glob(f".{path.name}.*.tmp")))
            time.sleep(0.001)
        return False
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_sigkill_mid_write_keeps_the_previous_checkpoint(tmp_path: Path) -> None:
    path = tmp_path / "ckpt.pt"
    save_checkpoint(path, {"iteration": 1, "algorithm": {"w": torch.arange(10.0)}})
    killed = any(_kill_mid_write(path) for _ in range(3))
    assert killed, "could not catch the writer mid-write"
    back = load_checkpoint(path)
    assert back["iteration"] == 1 and torch.equal(back["algorithm"]["w"], torch.arange(10.0))


def test_a_full_disk_names_the_file_and_keeps_the_previous_checkpoint(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "ckpt.pt"
    save_checkpoint(path, {"algorithm": {"w": torch.arange(3.0)}})

    def full(obj, handle) -> None:
        handle.write(b"x" * 100_000)  # part of the file made it before the disk filled
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(torch, "save", full)
    with pytest.raises(RetargetError, match="No space left on device") as err:
        save_checkpoint(path, {"algorithm": {"w": torch.zeros(3)}})
    monkeypatch.undo()
    assert err.value.file == str(path) and "previous checkpoint is intact" in err.value.hint
    assert torch.equal(load_checkpoint(path)["algorithm"]["w"], torch.arange(3.0))
    assert [p.name for p in tmp_path.iterdir()] == ["ckpt.pt"]  # no temporary file left
