"""iLQR refinement of a planned path and the planner plugins: real MuJoCo physics."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from retarget.env.build import env_from_recipe
from retarget.expert import BeamTracker, ExpertConfig
from retarget.expert.config import IlqrConfig
from retarget.expert.ilqr import IlqrRefiner
from retarget.expert.store import settings_key
from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import idle_clip
from retarget.recipe import load
from retarget.registry.loader import load_plugins

SLOPPY = {"samples": 16, "beam": 2, "keep": 0, "sigma": 0.4, "lookahead_share": 1.0}
"""A beam with few, noisy samples, every one scored after its lookahead: a path that stays
up with room to improve (the gains' test below is about one such path's tiny basin)."""


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    registry = load_plugins()
    clip = write_bvh(idle_clip(1.0), tmp_path_factory.mktemp("clips") / "idle.bvh")
    recipe = load("teacher", registry, shorthands={"motions": str(clip)},
                  assignments=["env.num_envs=1"])  # fmt: skip
    env = env_from_recipe(recipe, registry=registry, threads=1)
    path = BeamTracker(env, ExpertConfig(**SLOPPY)).track(0, seconds=0.5)
    refiner = IlqrRefiner(env, IlqrConfig(iterations=4, chunk=6), threads=1)
    return env, path, refiner, refiner.refine(0, path)


def test_refinement_lowers_the_simulated_cost_and_the_pose_error(planned) -> None:
    _, path, refiner, refined = planned
    history = refiner.history
    assert history and any(h["trial"] < h["cost"] for h in history), history
    first, last = history[0]["cost"], min(min(h["trial"], h["cost"]) for h in history)
    assert last < 0.9 * first, history
    before, after = path.metrics(), refined.metrics()
    assert after["success_clip"] and after["mpjpe_mm"] < before["mpjpe_mm"], (before, after)
    assert refined.cpu_seconds > path.cpu_seconds


def test_the_refined_actions_replay_to_its_states(planned) -> None:
    import torch

    env, _, _, refined = planned
    env.place(torch.tensor([0]), torch.tensor([0]))
    for t, action in enumerate(refined.actions):
        env.sim.step(action[None].astype(np.float64))
        assert np.abs(env.sim.raw("qpos")[0] - refined.qpos[t + 1]).max() < 1e-4, t
    assert np.allclose(env.sim.state.body_pos[0].numpy(), refined.body_pos[-1], atol=1e-4)


def test_no_round_that_raises_the_cost_is_kept(planned) -> None:
    """With steps far too long (damping near zero, fifty times the model's step, the whole
    path at once) the refinement must return the path it was given rather than a worse one."""
    env, path, _, _ = planned
    reckless = IlqrRefiner(env, IlqrConfig(iterations=2, alphas=(50.0,), regularization=1e-6,
                                           chunk=6, window=0), threads=1)  # fmt: skip
    out = reckless.refine(0, path)
    kept = [h for h in reckless.history if h["trial"] < h["cost"]]
    if not kept:
        assert np.array_equal(out.actions, path.actions)
    assert out.metrics()["mpjpe_mm"] <= path.metrics()["mpjpe_mm"] + 1e-3


def test_the_planner_joins_the_directory_settings() -> None:
    """``beam`` keeps the key that directories written before planners were plugins have
    (they resume); another planner has its own."""
    header = {"recipe": {"character": "human"}, "planner": ExpertConfig().model_dump(mode="json")}
    assert settings_key({**header, "method": "beam"}) == settings_key(header)
    assert settings_key({**header, "method": "beam_ilqr"}) != settings_key(header)


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "retarget", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600)  # fmt: skip


def test_cli_plans_with_a_planner_plugin_and_names_bad_ones(tmp_path) -> None:
    clip = write_bvh(idle_clip(1.0), tmp_path / "idle.bvh")
    out = tmp_path / "expert"
    sets = ["--planner=beam.samples=16", "--planner=beam.beam=2", "--planner=beam.keep=0",
            "--planner=ilqr.iterations=1", "--planner=ilqr.chunk=6"]
    done = _cli("expert", str(clip), "--out", str(out), "--seconds", "0.3", "--method",
                "beam_ilqr", *sets, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert json.loads((out / "expert.json").read_text())["method"] == "beam_ilqr"
    assert json.loads((out / "report.json").read_text())["summary"]["clips"] == 1
    unknown = _cli("expert", str(clip), "--out", str(tmp_path / "x"), "--method", "bean",
                   cwd=tmp_path)  # fmt: skip
    assert unknown.returncode == 2 and "did you mean 'beam'" in unknown.stderr
    wrong = _cli("expert", str(clip), "--out", str(tmp_path / "y"), "--method", "beam_ilqr",
                 "--planner", "samples=16", cwd=tmp_path)  # fmt: skip
    assert wrong.returncode == 2 and "beam_ilqr" in wrong.stderr and "samples" in wrong.stderr
    beam = ["--planner=samples=16", "--planner=beam=2", "--planner=keep=0"]
    other = _cli("expert", str(clip), "--out", str(out), "--seconds", "0.3", *beam,
                 cwd=tmp_path)  # fmt: skip
    assert other.returncode != 0 and "expert.json" in other.stderr  # planned by beam_ilqr


def test_refined_paths_form_an_expert_directory_a_student_reads(tmp_path) -> None:
    """``benchmarks/expert_refine.py --write`` turns a beam directory into the one
    ``beam_ilqr`` writes: same clips, the refined paths, and it resumes clip by clip;
    ``--include`` and ``--shard`` pick the clips a process refines."""
    from helpers import REPO

    clip = write_bvh(idle_clip(1.0), tmp_path / "idle.bvh")
    beam = tmp_path / "beam"
    small = ["--planner=samples=16", "--planner=beam=2", "--planner=keep=2"]
    assert _cli("expert", str(clip), "--out", str(beam), "--seconds", "0.3", *small,
                cwd=tmp_path).returncode == 0  # fmt: skip
    refined = tmp_path / "refined"
    cmd = [sys.executable, str(REPO / "benchmarks" / "expert_refine.py"), str(beam), "--write",
           str(refined), "--set", "iterations=1", "--set", "chunk=6"]  # fmt: skip
    for narrow in (["--include", "*_walk_*"], ["--shard", "1/2"]):  # the one clip left out
        skip = subprocess.run(cmd + narrow, cwd=tmp_path, capture_output=True, text=True,
                              timeout=600)  # fmt: skip
        assert skip.returncode == 0 and "idle:" not in skip.stdout, skip.stderr
        assert json.loads((refined / "report.json").read_text())["summary"]["clips"] == 0
    bad = subprocess.run([*cmd, "--shard", "2/2"], cwd=tmp_path, capture_output=True, text=True)
    assert bad.returncode == 2 and "--shard '2/2'" in bad.stderr
    done = subprocess.run([*cmd, "--shard", "0/2"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    header = json.loads((refined / "expert.json").read_text())
    assert header["method"] == "beam_ilqr" and header["planner"]["ilqr"]["iterations"] == 1
    assert (refined / "motions" / "idle.bvh").exists()
    report = json.loads((refined / "report.json").read_text())
    assert report["summary"]["clips"] == 1
    with np.load(refined / "clips" / "idle.npz") as z:
        assert "demo_actions" in z.files and z["actions"].shape[0] == 11  # 0.3 s at 36 Hz
    again = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0 and "idle:" not in again.stdout  # nothing planned again
    train = _cli("train", "--sensors", "three_point", "--expert", str(refined), "--steps", "256",
                 "--num-envs", "4", "--threads", "1", "--runs-dir", str(tmp_path / "runs"),
                 cwd=tmp_path)  # fmt: skip
    assert train.returncode == 0, train.stderr + train.stdout


def test_a_refinement_that_loses_the_clip_is_dropped(planned) -> None:
    """Success comes before cost: a refined path with any frame past PHC's 0.5 m (here a
    stand-in whose bodies are a metre off) is dropped for the path that tracked the clip."""
    env, path, _, _ = planned

    class Drifting(IlqrRefiner):
        def _optimise(self, path, cost, rows, start_actions, progress):
            moved = {**path, "body": path["body"] + 1.0, "acts": path["acts"] * 0.9}
            return moved, 0.0

    out = Drifting(env, IlqrConfig(iterations=1, chunk=6, window=0), threads=1).refine(0, path)
    assert path.metrics()["success_clip"]
    assert np.array_equal(out.actions, path.actions) and out.metrics()["success_clip"]


def test_the_path_feedback_gains_bring_a_pushed_body_back(planned) -> None:
    """``IlqrRefiner.gains``: the LQR gains around a refined path, one block per committed
    window. A small push of every joint velocity, replayed with them, must end nearer the path
    than the same push replayed open loop. The push is tiny because the gains' basin is:
    ``benchmarks/expert_basin.py`` measures it (pushes of 1e-2 already escape it)."""
    sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
    from expert_basin import follow

    _, _, refiner, refined = planned
    gains = refiner.gains(0, refined)
    assert gains.shape == (len(refined.actions), refiner.nu, 2 * refiner.nv)
    assert np.isfinite(gains).all() and np.abs(gains).max() > 0
    still = follow(refiner, 0, refined, gains, trials=2)
    assert still["deviation"].max() < 1e-3  # no push, no noise: the path itself
    open_loop = follow(refiner, 0, refined, None, push=1e-4, trials=4, seed=3)
    closed = follow(refiner, 0, refined, gains, push=1e-4, trials=4, seed=3)
    assert closed["deviation"][:, -1].mean() < 0.8 * open_loop["deviation"][:, -1].mean(), (
        closed["deviation"][:, -1], open_loop["deviation"][:, -1])


def _header(beam: dict, ilqr: dict) -> dict:
    """An expert directory's header for ``beam_ilqr`` with these beam and refinement settings."""
    return {"recipe": {"character": "human"}, "method": "beam_ilqr",
            "planner": {"beam": beam, "ilqr": ilqr}}  # fmt: skip


def test_a_refinement_field_added_later_keeps_old_directories_resuming() -> None:
    """``relinearise`` at 1 (how every directory was refined before it existed) leaves the
    settings key as it was; another value (the default now) is another key."""
    beam = ExpertConfig().model_dump(mode="json")
    ilqr = IlqrConfig().model_dump(mode="json")
    old = {k: v for k, v in ilqr.items() if k != "relinearise"}
    assert settings_key(_header(beam, {**ilqr, "relinearise": 1})) == settings_key(
        _header(beam, old))
    assert settings_key(_header(beam, {**ilqr, "relinearise": 2})) != settings_key(
        _header(beam, old))


def test_chord_rounds_still_lower_the_cost(planned) -> None:
    """With ``relinearise`` 2 every other kept round reuses the derivatives with the new
    path's residuals: the rounds still only ever lower the simulated cost, and the path
    still improves on the beam's."""
    env, path, _, _ = planned
    chord = IlqrRefiner(env, IlqrConfig(iterations=4, chunk=6, relinearise=2, window=0),
                        threads=1)  # fmt: skip
    out = chord.refine(0, path)
    kept = [h for h in chord.history if h["trial"] < h["cost"]]
    assert len(kept) >= 2, chord.history
    costs = [h["cost"] for h in chord.history]
    assert all(b <= a for a, b in itertools.pairwise(costs)), costs
    assert out.metrics()["mpjpe_mm"] < path.metrics()["mpjpe_mm"]


def test_a_beam_field_added_later_keeps_refined_directories_resuming(tmp_path) -> None:
    """``beam_ilqr`` records the beam's settings under ``beam``: a directory written before
    ``lookahead_share`` existed keeps its key with the field at 1.0 (how it planned); another
    value is another key, and resuming with it names the field and both values."""
    from retarget.errors import RecipeError
    from retarget.expert.store import write_header

    beam = ExpertConfig().model_dump(mode="json")
    ilqr = IlqrConfig().model_dump(mode="json")
    before = {k: v for k, v in beam.items() if k != "lookahead_share"}

    def header(b):
        return _header(b, ilqr)

    assert settings_key(header({**beam, "lookahead_share": 1.0})) == settings_key(header(before))
    assert settings_key(header({**beam, "lookahead_share": 0.25})) != settings_key(header(before))
    write_header(tmp_path, header(before))
    write_header(tmp_path, header({**beam, "lookahead_share": 1.0}))  # resumes
    with pytest.raises(RecipeError) as err:
        write_header(tmp_path, header({**beam, "lookahead_share": 0.25, "samples": 256}))
    text = str(err.value)
    assert "planner.beam.lookahead_share: 1.0 in the directory, 0.25 now" in text, text
    assert "planner.beam.samples: 512 in the directory, 256 now" in text, text
    assert "expert.json" in text
