"""``retarget train --init-from``: a run that starts from another run's weights, with inputs
matched by name (a flat-ground walker given a height map computes what it did before)."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch
from helpers import TINY
from torch import nn

from retarget.cli.main import main
from retarget.learn.widen import widen_module, widen_normalizer
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.load import load_run
from retarget.train.run_dir import new_run_dir
from retarget.train.runner import Budget, Trainer
from retarget.train.warm_start import INIT_FROM, input_maps, warm_start


def test_input_maps_match_sources_by_name_and_size() -> None:
    old = {"actor": [("three_point", 6), ("proprio", 4), ("height_map", 3)]}
    new = {"actor": [("proprio", 4), ("three_point", 6), ("height_map", 5), ("point_cloud", 2)]}
    maps, info = input_maps(new, old)
    assert maps["actor"].tolist() == [6, 7, 8, 9, 0, 1, 2, 3, 4, 5] + [-1] * 7
    assert info.kept["actor"] == ["proprio", "three_point"]
    assert info.new["actor"] == ["height_map", "point_cloud"]  # height_map changed size
    assert info.dropped["actor"] == ["height_map"]


def test_widened_network_ignores_new_inputs_until_trained() -> None:
    torch.manual_seed(0)
    old = nn.Sequential(nn.Linear(3, 8), nn.Tanh(), nn.Linear(8, 2))
    new = nn.Sequential(nn.Linear(5, 8), nn.Tanh(), nn.Linear(8, 2))
    index = torch.tensor([2, -1, 0, 1, -1])
    widen_module(new, old.state_dict(), index)
    x = torch.randn(10, 5)
    assert torch.allclose(new(x), old(x[:, [2, 3, 0]]), atol=1e-6)
    with pytest.raises(ValueError, match=r"'2\.weight'"):
        widen_module(nn.Sequential(nn.Linear(5, 8), nn.Tanh(), nn.Linear(8, 3)),
                     old.state_dict(), index)  # fmt: skip


@pytest.fixture(scope="module")
def flat_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("flat")
    recipe = root / "flat.yaml"
    recipe.write_text(TINY.replace("name: tiny", "name: flat"))
    assert main(["train", str(recipe), "--steps", "64", "--runs-dir", str(root),
                 "--no-tensorboard"]) == 0  # fmt: skip
    return root / "flat" / "latest"


def test_flat_walker_given_a_height_map_acts_as_before_then_trains(
    flat_run: Path, tmp_path: Path
) -> None:
    registry = load_plugins()
    resolved = load(str(flat_run / "recipe.lock.yaml"), registry, shorthands={"scene": "boxes"},
                    assignments=["observers=[height_map]"])  # fmt: skip
    trainer = Trainer(resolved, new_run_dir(tmp_path, "boxes"), tensorboard=False)
    info = warm_start(trainer.algorithm, trainer.env.obs_layout, flat_run, registry)
    assert info.new == {"actor": ["height_map"], "critic": ["height_map"]}
    assert info.kept["actor"] == ["three_point", "proprio"]

    old = load_run(flat_run, registry, num_envs=trainer.env.num_envs)
    maps, _ = input_maps(trainer.env.obs_layout, old.env.obs_layout)
    obs = {k: v.float() for k, v in trainer.env.reset().items()}
    obs["actor"][:, maps["actor"] < 0] = torch.rand(obs["actor"].shape[0], 1) + 0.5
    known = maps["actor"] >= 0
    old_actor = torch.zeros(obs["actor"].shape[0], old.env.obs_dims["actor"])
    old_actor[:, maps["actor"][known]] = obs["actor"][:, known]
    assert torch.allclose(trainer.algorithm.act(obs), old.algorithm.act({"actor": old_actor}),
                          atol=1e-5)  # fmt: skip

    trainer.train(Budget(steps=64))
    assert trainer.progress.env_steps == 64
    for p in trainer.algorithm.learner.actor.parameters():  # type: ignore[attr-defined]
        assert torch.isfinite(p).all()


def test_cli_init_from_records_the_source_and_refuses_other_networks(
    flat_run: Path, tmp_path: Path, capsys
) -> None:
    recipe = flat_run / "recipe.lock.yaml"
    assert main(["train", str(recipe), "--init-from", str(flat_run), "--observers", "height_map",
                 "--scene", "boxes", "--steps", "32", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    run = tmp_path / "flat" / "latest"
    assert "ckpt-" in (run / INIT_FROM).read_text()
    assert (run / "checkpoints" / "ckpt-0000000.pt").exists(), "the starting weights are saved"

    rc = main(["train", str(recipe), "--init-from", str(flat_run),
               "--set", "algorithm.actor_hidden=[16]",
               "--steps", "32", "--runs-dir", str(tmp_path)])  # fmt: skip
    err = capsys.readouterr().err
    assert rc != 0 and "cannot start from" in err and "actor_hidden" in err

    rc = main(["train", "--resume", str(run), "--init-from", str(flat_run)])
    err = capsys.readouterr().err
    assert rc != 0 and "--init-from and --teacher/--expert start a new one" in err


def test_new_inputs_learn_their_scale_while_kept_ones_stay() -> None:
    from retarget.learn.normalizer import RunningNormalizer

    old = RunningNormalizer(2)
    old.update(torch.tensor([[0.0, 10.0], [2.0, 30.0]]).repeat(5000, 1))  # mean 1, 20; var 1, 100
    new = RunningNormalizer(3)
    widen_normalizer(new, old.state_dict(), torch.tensor([1, -1, 0]), count=1000.0)
    assert new.mean.tolist() == [20.0, 0.0, 1.0] and new.var.tolist() == [100.0, 0.0, 1.0]
    assert float(new.count) == 1000.0
    same = torch.tensor([[10.0, 2.0], [30.0, 0.0]]).repeat(500, 1)  # the kept inputs as before
    batch = torch.stack([same[:, 0], torch.rand(1000) * 0.1, same[:, 1]], 1)
    for _ in range(10):  # ten rollouts with a new height-map-like input (0-10 cm)
        new.update(batch)
    assert torch.allclose(new.mean[[0, 2]], torch.tensor([20.0, 1.0], dtype=torch.float64))
    assert torch.allclose(new.var[[0, 2]], torch.tensor([100.0, 1.0], dtype=torch.float64))
    assert abs(float(new.mean[1]) - 0.05 * 10 / 11) < 0.01
    assert 1e-4 < float(new.var[1]) < 0.01  # its own scale, not the unit variance of a default


def test_kept_inputs_keep_their_statistics_when_the_new_run_visits_other_states() -> None:
    """A warm-started network reads its kept inputs as it was trained to, however different
    the new run's states are (a distilled student fine-tuned with PPO falls where it never
    did); a new input still learns its scale; a state saved before freezing loads."""
    from retarget.learn.normalizer import RunningNormalizer

    old = RunningNormalizer(2)
    old.update(torch.tensor([[0.0, 10.0], [2.0, 30.0]]).repeat(5000, 1))  # mean 1, 20; var 1, 100
    new = RunningNormalizer(3)
    widen_normalizer(new, old.state_dict(), torch.tensor([1, -1, 0]), count=1000.0)
    assert new.frozen.tolist() == [True, False, True]
    far = torch.full((1000,), 80.0), torch.rand(1000), torch.full((1000,), 5.0)
    shifted = torch.stack(far, 1)
    for _ in range(10):
        new.update(shifted)
    assert new.mean[[0, 2]].tolist() == [20.0, 1.0] and new.var[[0, 2]].tolist() == [100.0, 1.0]
    assert 0.4 < float(new.mean[1]) < 0.5  # 10 of 11 parts new data around 0.5
    legacy = {k: v for k, v in new.state_dict().items() if k != "frozen"}
    loaded = RunningNormalizer(3)
    loaded.load_state_dict(legacy)
    assert not loaded.frozen.any() and loaded.mean.tolist() == new.mean.tolist()
    loaded.update(shifted)
    assert float(loaded.mean[0]) > 20.0  # nothing frozen: every column follows the data
