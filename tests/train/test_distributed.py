"""Data-parallel training: real torchrun jobs of 2 ranks over gloo on loopback (PPO and DAgger)
keep identical weights on every rank, count every rank's steps, resume with the same and with
another number of ranks; the collectives merge statistics and gradients as pooling the
ranks' samples would; an algorithm that cannot train data-parallel is refused."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch
from helpers import TINY, TINY_TEACHER

from retarget.train.checkpoint import load_checkpoint

STEPS_PER_ITER = 4 * 8  # TINY: 4 envs x 8 rollout steps, per rank


def _torchrun(ranks: int, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone",
           f"--nproc-per-node={ranks}", "-m", "retarget", "train", *args]  # fmt: skip
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done


def _same_weights(state: dict, keys: tuple[str, ...]) -> None:
    """Every rank's networks and statistics in a checkpoint equal rank 0's, bit for bit."""
    assert state["ranks"], "a distributed checkpoint holds the other ranks' states"
    for other in state["ranks"]:
        for key in keys:
            mine, theirs = state["algorithm"][key], other["algorithm"][key]
            for name, tensor in mine.items():
                assert torch.equal(tensor, theirs[name]), f"{key}.{name} differs between ranks"


def _last_checkpoint(run: Path) -> dict:
    return load_checkpoint(sorted((run / "checkpoints").glob("ckpt-*.pt"))[-1])


def test_two_ranks_of_ppo_share_weights_count_steps_and_resume(tmp_path: Path) -> None:
    (tmp_path / "tiny.yaml").write_text(TINY)
    out = _torchrun(2, "tiny.yaml", "--steps", str(4 * STEPS_PER_ITER), "--runs-dir", "runs",
                    "--no-tensorboard", cwd=tmp_path)  # fmt: skip
    assert "2 ranks" in out.stdout
    run = (tmp_path / "runs" / "tiny" / "latest").resolve()
    state = _last_checkpoint(run)
    assert state["world_size"] == 2 and len(state["ranks"]) == 1
    # two iterations of 2 x 32 steps reach the 128-step budget
    assert state["progress"]["iteration"] == 2 and state["progress"]["env_steps"] == 128
    _same_weights(state, ("actor", "critic", "obs_norm", "value_norm"))
    assert not torch.equal(state["env"]["clip"], state["ranks"][0]["env"]["clip"]) or not (
        torch.equal(state["env"]["frame"], state["ranks"][0]["env"]["frame"])
    ), "each rank steps its own episodes"
    assert len(list(run.parent.iterdir())) == 2, "one run directory (and latest), by rank 0"
    # the same number of ranks continues every rank's own state; another number continues too
    _torchrun(2, "--resume", str(run), "--steps", str(2 * STEPS_PER_ITER), cwd=tmp_path)
    state = _last_checkpoint(run)
    assert state["progress"]["iteration"] == 3 and state["progress"]["env_steps"] == 192
    _same_weights(state, ("actor", "critic", "obs_norm", "value_norm"))
    _torchrun(1, "--resume", str(run), "--steps", str(STEPS_PER_ITER), cwd=tmp_path)
    state = _last_checkpoint(run)
    assert state["progress"]["iteration"] == 4 and state["progress"]["env_steps"] == 224
    assert "ranks" not in state, "a one-process run writes a plain checkpoint"


def test_two_ranks_of_dagger_share_the_student(tmp_path: Path) -> None:
    from retarget.cli.main import main

    (tmp_path / "teacher.yaml").write_text(TINY_TEACHER)
    assert main(["train", str(tmp_path / "teacher.yaml"), "--steps", "32", "--runs-dir",
                 str(tmp_path / "runs"), "--no-tensorboard"]) == 0  # fmt: skip
    teacher = tmp_path / "runs" / "teacher" / "latest"
    student = TINY.replace("name: tiny", "name: student").replace(
        "sim: {threads: 1}", "sim: {threads: 1, actuation: pd}"
    ).split("algorithm:")[0] + (
        f"algorithm:\n  type: dagger\n  teacher: {teacher}\n  rollout_steps: 8\n"
        "  actor_hidden: [32]\n  minibatch_size: 16\n  epochs: 2\n"
        "env: {num_envs: 4}\nsim: {threads: 1, actuation: pd}\n"
    )
    (tmp_path / "student.yaml").write_text(student)
    _torchrun(2, "student.yaml", "--steps", str(4 * STEPS_PER_ITER), "--runs-dir", "runs",
              "--no-tensorboard", cwd=tmp_path)  # fmt: skip
    state = _last_checkpoint(tmp_path / "runs" / "student" / "latest")
    assert state["world_size"] == 2
    _same_weights(state, ("actor", "obs_norm"))
    mine, theirs = state["algorithm"]["buffer"], state["ranks"][0]["algorithm"]["buffer"]
    assert mine["obs"] is None or not torch.equal(mine["obs"], theirs["obs"]), (
        "each rank labels the states its own environments visit"
    )


def _collectives(rank: int, size: int, store: str, out: str) -> None:
    """One rank of the collective check (run by torch.multiprocessing)."""
    import torch.distributed as dist

    from retarget.learn.normalizer import RunningNormalizer
    from retarget.train.distributed import Comm

    dist.init_process_group("gloo", init_method=f"file://{store}", rank=rank, world_size=size)
    comm = Comm(rank=rank, size=size, local_size=size)
    data = torch.Generator().manual_seed(rank)
    x = torch.randn(50 + 30 * rank, 3, generator=data, dtype=torch.float64) * (rank + 1)
    norm = RunningNormalizer(3)
    norm.update_ranks(comm, x)
    layer = torch.nn.Linear(3, 1)
    comm.broadcast_modules([layer])
    layer(x.float()).square().mean().backward()
    comm.average_gradients(list(layer.parameters()))
    torch.save({"mean": norm.mean, "var": norm.var, "count": norm.count,
                "grad": layer.weight.grad, "weight": layer.weight.detach(),
                "bias": layer.bias.detach()},
               f"{out}/rank{rank}.pt")  # fmt: skip
    dist.destroy_process_group()


def test_collectives_pool_the_ranks_samples(tmp_path: Path) -> None:
    import torch.multiprocessing as mp

    from retarget.learn.normalizer import RunningNormalizer

    mp.spawn(_collectives, args=(2, str(tmp_path / "store"), str(tmp_path)), nprocs=2)
    got = [torch.load(tmp_path / f"rank{r}.pt") for r in range(2)]
    for key in got[0]:
        assert torch.equal(got[0][key], got[1][key]), f"{key} differs between the ranks"
    xs = [torch.randn(50 + 30 * r, 3, generator=torch.Generator().manual_seed(r),
                      dtype=torch.float64) * (r + 1) for r in range(2)]  # fmt: skip
    pooled = RunningNormalizer(3)
    pooled.update(torch.cat(xs))
    assert float(got[0]["count"]) == 130
    torch.testing.assert_close(got[0]["mean"], pooled.mean)
    torch.testing.assert_close(got[0]["var"], pooled.var)
    # the averaged gradient is the mean of the ranks' own gradients of the shared weights
    layer = torch.nn.Linear(3, 1)
    with torch.no_grad():
        layer.weight.copy_(got[0]["weight"])
        layer.bias.copy_(got[0]["bias"])
    grads = []
    for x in xs:
        layer.zero_grad()
        layer(x.float()).square().mean().backward()
        grads.append(layer.weight.grad.clone())
    torch.testing.assert_close(got[0]["grad"], (grads[0] + grads[1]) / 2)


def test_an_algorithm_that_cannot_train_data_parallel_is_refused(tmp_path: Path) -> None:
    from retarget.errors import RecipeError
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins
    from retarget.train.distributed import Comm
    from retarget.train.load import prepared_recipe
    from retarget.train.runner import Trainer

    registry = load_plugins()
    text = TINY.replace("  type: ppo\n", "  type: estimator\n").split("  rollout_steps")[0]
    (tmp_path / "est.yaml").write_text(text + "env: {num_envs: 4}\nsim: {threads: 1}\n")
    resolved = prepared_recipe(load(tmp_path / "est.yaml", registry), registry)
    with pytest.raises(RecipeError, match="does not train data-parallel"):
        Trainer(resolved, tmp_path / "run", comm=Comm(rank=0, size=2), registry=registry)


def test_two_ranks_of_overlapped_ppo_share_weights(tmp_path: Path) -> None:
    recipe = TINY.replace("  type: ppo\n", "  type: ppo\n  overlap: true\n")
    (tmp_path / "tiny.yaml").write_text(recipe)
    _torchrun(2, "tiny.yaml", "--steps", str(6 * STEPS_PER_ITER), "--runs-dir", "runs",
              "--no-tensorboard", cwd=tmp_path)  # fmt: skip
    state = _last_checkpoint(tmp_path / "runs" / "tiny" / "latest")
    assert state["progress"]["iteration"] == 2  # 4 rollouts of 2 x 32 steps (2 + 1 + 1)
    _same_weights(state, ("actor", "critic", "obs_norm", "value_norm"))
    assert state["algorithm"]["overlap"]["ready"] is not None
