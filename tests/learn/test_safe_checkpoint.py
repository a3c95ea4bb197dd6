"""Loading a checkpoint never runs code from the file, and a file that is not a checkpoint is
refused naming it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from retarget.errors import RetargetError
from retarget.train.checkpoint import load_checkpoint, save_checkpoint


class _Payload:
    """Unpickling this creates a file: what a crafted checkpoint would do."""

    def __init__(self, target: Path) -> None:
        self.target = target

    def __reduce__(self):
        return (Path.touch, (self.target,))


def test_a_crafted_checkpoint_does_not_run_its_payload(tmp_path: Path) -> None:
    target = tmp_path / "pwned"
    bad = tmp_path / "ckpt-0000001.pt"
    torch.save({"algorithm": _Payload(target)}, bad)
    with pytest.raises(RetargetError, match="refused") as err:
        load_checkpoint(bad)
    assert not target.exists(), "the payload ran"
    assert str(bad) in str(err.value.file)


def test_real_checkpoint_contents_round_trip(tmp_path: Path) -> None:
    state = {
        "algorithm": {"w": torch.randn(3, 2), "steps": 5, "names": ["a", "b"]},
        "rng": {"torch": torch.get_rng_state(), "numpy": np.random.get_state()},
        "env": {"sim": np.zeros((2, 3)), "flags": np.ones(4, dtype=bool)},
    }
    path = save_checkpoint(tmp_path / "ckpt.pt", state)
    back = load_checkpoint(path)
    assert torch.equal(back["algorithm"]["w"], state["algorithm"]["w"])
    np.testing.assert_array_equal(back["rng"]["numpy"][1], state["rng"]["numpy"][1])
    assert back["env"]["flags"].dtype == bool


def test_not_a_checkpoint(tmp_path: Path) -> None:
    path = tmp_path / "x.pt"
    torch.save([1, 2, 3], path)
    with pytest.raises(RetargetError, match="not a retarget checkpoint"):
        load_checkpoint(path)
    path.write_bytes(b"garbage")
    with pytest.raises(RetargetError, match="cannot read"):
        load_checkpoint(path)


def test_a_mapping_without_algorithm_state_is_not_a_checkpoint(tmp_path: Path) -> None:
    path = tmp_path / "x.pt"
    torch.save({"weights": torch.zeros(2)}, path)
    with pytest.raises(RetargetError, match="no 'algorithm' state"):
        load_checkpoint(path)


def test_non_finite_weights_are_refused_naming_the_tensor(tmp_path: Path) -> None:
    w = torch.zeros(3)
    w[1] = float("nan")
    path = save_checkpoint(tmp_path / "ckpt.pt", {"algorithm": {"actor": {"0.weight": w}}})
    with pytest.raises(RetargetError, match=r"algorithm\.actor\.0\.weight holds NaN") as err:
        load_checkpoint(path)
    assert err.value.hint and "earlier checkpoint" in err.value.hint
