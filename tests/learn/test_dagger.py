"""Teacher and student: a full-body residual imitator, DAgger distillation into sparse sensors,
exact resume, ONNX parity, a PPO fine-tune of the student, and mismatched teachers refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml
from helpers import TINY, TINY_TEACHER, assert_state_equal, image_student

from retarget.cli.main import main
from retarget.learn.dagger import DaggerConfig, DaggerLearner
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.load import load_run, prepared_recipe
from retarget.train.run_dir import new_run_dir
from retarget.train.runner import Budget, Trainer

SAMPLES = 4 * 8  # TINY: 4 envs x 8 rollout steps

TEACHER = TINY_TEACHER
STUDENT = (
    TINY.replace("name: tiny", "name: student")
    .replace("sim: {threads: 1}", "sim: {threads: 1, actuation: pd}")
)
STUDENT_DAGGER = """\
  rollout_steps: 8
  actor_hidden: [32]
  minibatch_size: 16
  epochs: 2
"""


@pytest.fixture(scope="module")
def teacher(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("teacher")
    recipe = root / "teacher.yaml"
    recipe.write_text(TEACHER)
    assert main(["train", str(recipe), "--steps", str(2 * SAMPLES), "--runs-dir", str(root),
                 "--no-tensorboard"]) == 0  # fmt: skip
    return root / "teacher" / "latest"


def student_recipe(tmp: Path, teacher: Path, extra: str = "") -> Path:
    """The tiny student recipe distilling from ``teacher`` with small networks."""
    text = STUDENT.split("algorithm:")[0] + (
        f"algorithm:\n  type: dagger\n  teacher: {teacher}\n{STUDENT_DAGGER}{extra}"
        + "env: {num_envs: 4}\nsim: {threads: 1, actuation: pd}\n"
    )
    path = tmp / "student.yaml"
    path.write_text(text)
    return path


def test_untrained_residual_teacher_acts_as_the_reference(teacher: Path) -> None:
    run = load_run(teacher, load_plugins(), num_envs=4)
    obs = run.env.reset()
    cols = run.algorithm.learner.residual  # type: ignore[attr-defined]
    base = obs["actor"][:, cols]
    assert base.abs().max() > 0.05, "the reference's joint targets are not all zero"
    act = run.algorithm.act(obs)
    assert (act - base.clamp(-1, 1)).abs().max() < 0.1, "a barely trained residual stays small"
    group, policy = run.algorithm.policy()
    assert torch.allclose(policy(obs[group]), act, atol=1e-6)


def test_cli_teacher_shorthand_writes_an_explicit_recipe(teacher: Path, tmp_path: Path) -> None:
    recipe = tmp_path / "s.yaml"
    recipe.write_text(STUDENT)
    assert main(["train", str(recipe), "--teacher", str(teacher), "--steps", str(SAMPLES),
                 "--runs-dir", str(tmp_path), "--no-tensorboard"]) == 0  # fmt: skip
    lock = yaml.safe_load((tmp_path / "student" / "latest" / "recipe.lock.yaml").read_text())
    assert lock["algorithm"]["type"] == "dagger"
    assert lock["algorithm"]["teacher"] == str(teacher.resolve())  # not the moving 'latest'
    assert lock["algorithm"]["teacher_checkpoint"].startswith("checkpoints/ckpt-")
    assert lock["env"]["groups"]["actor"] == ["three_point", "proprio"]
    assert lock["env"]["groups"]["teacher"] == ["full_body", "reference_action", "proprio"]
    assert [s["type"] for s in lock["sensors"]] == ["three_point", "full_body", "reference_action"]
    assert lock["motions"]["level_feet"] is True  # the teacher's references, as it learned them
    assert lock["env"]["hinge_elbows"] is True


def test_a_student_reads_references_as_its_teacher_learned_them(
    teacher: Path, tmp_path: Path
) -> None:
    """A teacher recorded before ``motions.level_feet`` learned on the file's foot tilt (and
    before ``env.hinge_elbows`` on elbows bent by the angle alone): its students' references
    keep both, whatever the student's recipe says."""
    import shutil

    old = tmp_path / "old_teacher"
    shutil.copytree(teacher.resolve(), old)
    lock = yaml.safe_load((old / "recipe.lock.yaml").read_text())
    del lock["motions"]["level_feet"]
    del lock["env"]["hinge_elbows"]
    (old / "recipe.lock.yaml").write_text(yaml.safe_dump(lock, sort_keys=False))
    recipe = tmp_path / "s.yaml"
    recipe.write_text(STUDENT)
    assert main(["train", str(recipe), "--teacher", str(old), "--steps", str(SAMPLES),
                 "--runs-dir", str(tmp_path), "--no-tensorboard"]) == 0  # fmt: skip
    got = yaml.safe_load((tmp_path / "student" / "latest" / "recipe.lock.yaml").read_text())
    assert got["motions"]["level_feet"] is False
    assert got["env"]["hinge_elbows"] is False  # and its elbows bent by the angle alone


def test_teacher_sensors_label_with_the_base_further_ahead(
    teacher: Path, tmp_path: Path, capsys
) -> None:
    """``algorithm.teacher_sensors`` changes a teacher's own sensor while it labels (its
    residual's base a frame further ahead): the lock says so, the teacher group reads the
    later frame, the rest of its input is unchanged; a sensor the teacher lacks is refused."""
    runs = {}
    for name, extra in (("plain", ""),
                        ("lead", "  teacher_sensors: {reference_action: {offset: 2}}\n")):
        where = tmp_path / name
        where.mkdir()
        recipe = student_recipe(where, teacher, extra)
        assert main(["train", str(recipe), "--steps", str(SAMPLES), "--runs-dir", str(where),
                     "--no-tensorboard"]) == 0  # fmt: skip
        runs[name] = where / "student" / "latest"
    lock = yaml.safe_load((runs["lead"] / "recipe.lock.yaml").read_text())
    base = next(s for s in lock["sensors"] if s["type"] == "reference_action")
    assert base["offset"] == 2
    assert lock["algorithm"]["teacher_sensors"] == {"reference_action": {"offset": 2}}
    obs = {}
    for name, run in runs.items():
        loaded = load_run(run, load_plugins(), num_envs=4)
        obs[name] = (loaded.env.reset()["teacher"], dict(loaded.env.obs_layout)["teacher"])
    (plain, layout), (lead, _) = obs["plain"], obs["lead"]
    at, cols = 0, {}
    for source, size in layout:
        cols[source] = slice(at, at + size)
        at += size
    same = cols["full_body"]
    assert torch.equal(plain[:, same], lead[:, same]), "the reference body is read as before"
    moved = cols["reference_action"]
    assert (plain[:, moved] - lead[:, moved]).abs().max() > 1e-3, "the base reads a later frame"
    again = tmp_path / "again"  # from the plain student's lock, which lists the teacher's
    assert main(["train", str(runs["plain"] / "recipe.lock.yaml"), "--set",
                 'algorithm.teacher_sensors={"reference_action": {"offset": 2}}', "--steps",
                 str(SAMPLES), "--runs-dir", str(again), "--no-tensorboard"]) == 0  # fmt: skip
    relock = yaml.safe_load(next(again.glob("*/latest/recipe.lock.yaml")).read_text())
    assert [s.get("offset") for s in relock["sensors"] if s["type"] == "reference_action"] == [2]
    clash = tmp_path / "clash"  # the student's own copy set otherwise: refused, saying why
    clash.mkdir()
    recipe = student_recipe(clash, teacher, "  teacher_sensors: {reference_action: {offset: 2}}\n")
    recipe.write_text(recipe.read_text().replace(
        "sensors: [three_point]", "sensors: [three_point, {type: reference_action, offset: 5}]"))
    rc = main(["train", str(recipe), "--steps", "8", "--runs-dir", str(clash)])
    err = capsys.readouterr().err
    assert rc != 0 and "configured differently" in err and "with algorithm.teacher_sensors" in err
    recipe = student_recipe(tmp_path, teacher, "  teacher_sensors: {three_point: {past: 3}}\n")
    rc = main(["train", str(recipe), "--steps", "8", "--runs-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert rc != 0 and "teacher_sensors" in err and "'three_point'" in err
    assert "full_body" in err and "reference_action" in err


def test_student_learns_resumes_exactly_and_needs_no_teacher(
    teacher: Path, tmp_path: Path
) -> None:
    registry = load_plugins()
    resolved = prepared_recipe(load(str(student_recipe(tmp_path, teacher)), registry), registry)

    def trainer(name: str) -> Trainer:
        return Trainer(resolved, new_run_dir(tmp_path, name), checkpoint_every=2,
                       tensorboard=False, registry=registry)  # fmt: skip

    straight = trainer("straight")
    straight.train(Budget(steps=4 * SAMPLES))
    assert float(straight.progress.last["distill_loss"]) >= 0
    half = trainer("half")
    half.train(Budget(steps=2 * SAMPLES))
    again = trainer("again")
    again.restore(half.run / "checkpoints" / "ckpt-0000002.pt")
    again.train(Budget(steps=4 * SAMPLES))
    assert_state_equal(again.algorithm.state_dict(), straight.algorithm.state_dict(), "student")

    # evaluating and exporting the student never loads the teacher: move the teacher away
    moved = teacher.resolve().with_name("gone")
    teacher.resolve().rename(moved)
    try:
        run = load_run(straight.run, registry, num_envs=2)
        obs = run.env.reset()
        assert run.algorithm.act(obs).shape == (2, run.env.action_dim)
        ort = pytest.importorskip("onnxruntime")
        assert main(["export", str(straight.run), "--onnx"]) == 0
        onnx_path = straight.run / "export" / "policy.onnx"
        meta = json.loads(onnx_path.with_suffix(".json").read_text())
        assert meta["obs_dim"] == run.env.obs_dims["actor"]
        batch = obs["actor"].float()
        batch = torch.cat([batch, batch + 30 * torch.randn(batch.shape)])
        (got,) = ort.InferenceSession(str(onnx_path)).run(None, {"obs": batch.numpy()})
        np.testing.assert_allclose(got, run.algorithm.act({"actor": batch}).numpy(), atol=1e-5)
    finally:
        moved.rename(teacher.resolve())


def test_student_loss_falls_on_a_fixed_batch() -> None:
    config = DaggerConfig(teacher="unused", actor_hidden=(64,), learning_rate=3e-3)
    learner = DaggerLearner(config, {"actor": 12, "teacher": 5}, 3, num_envs=8,
                            generator=torch.Generator().manual_seed(0))  # fmt: skip
    g = torch.Generator().manual_seed(1)
    obs = torch.randn(256, 12, generator=g) * 3 + 1
    labels = torch.tanh(obs[:, :3] * 0.5 - obs[:, 3:6] * 0.3)
    learner.obs_norm.update({"actor": obs})
    first = float(learner.loss(obs, labels).detach())
    for _ in range(200):
        loss = learner.loss(obs, labels)
        learner.optimizer.zero_grad()
        loss.backward()
        learner.optimizer.step()
    assert float(learner.loss(obs, labels).detach()) < 0.1 * first

    kl = DaggerLearner(config.model_copy(update={"loss": "kl"}), {"actor": 12, "teacher": 5}, 3,
                       num_envs=8)  # fmt: skip
    assert kl.actor.log_std.requires_grad, "the KL loss learns the student's spread"
    assert float(kl.loss(obs, labels).detach()) > 0


def test_mismatched_teacher_is_refused_naming_both(
    teacher: Path, tmp_path: Path, capsys
) -> None:
    recipe = student_recipe(tmp_path, teacher)
    rc = main(["train", str(recipe), "--character", "jesse", "--steps", "8",
               "--runs-dir", str(tmp_path)])  # fmt: skip
    err = capsys.readouterr().err
    assert rc != 0 and "human" in err and "jesse" in err and "teacher" in err
    rc = main(["train", str(recipe), "--set", "sim.actuation=torque", "--steps", "8",
               "--runs-dir", str(tmp_path)])  # fmt: skip
    err = capsys.readouterr().err
    assert rc != 0 and "sim.actuation=pd" in err and "sim.actuation=torque" in err
    rc = main(["train", str(recipe), "--set", f"algorithm.teacher={tmp_path}", "--steps", "8",
               "--runs-dir", str(tmp_path)])  # fmt: skip
    assert rc != 0 and "not a run directory" in capsys.readouterr().err


def test_ppo_fine_tunes_a_distilled_student(teacher: Path, tmp_path: Path) -> None:
    recipe = student_recipe(tmp_path, teacher)
    assert main(["train", str(recipe), "--steps", str(2 * SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard", "--set", "algorithm.actor_hidden=[32]"]) == 0  # fmt: skip
    student = tmp_path / "student" / "latest"
    ppo = tmp_path / "ppo.yaml"
    ppo.write_text(STUDENT.replace("name: student", "name: tuned").replace(
        "  type: ppo\n", "  type: ppo\n  critic_warmup: 3\n"))  # fmt: skip
    assert main(["train", str(ppo), "--init-from", str(student), "--steps", str(2 * SAMPLES),
                 "--runs-dir", str(tmp_path), "--no-tensorboard"]) == 0  # fmt: skip
    registry = load_plugins()
    source = load_run(student, registry, num_envs=4)
    checkpoints = tmp_path / "tuned" / "latest" / "checkpoints"
    # the fine-tune starts as the student acts (same actor inputs, same weights), and still
    # does after the rollouts of its critic's warm-up: the student's input statistics are
    # kept, not merged with the states the new run visits
    for checkpoint in ("ckpt-0000000.pt", "ckpt-0000002.pt"):
        tuned = load_run(tmp_path / "tuned" / "latest", registry, num_envs=4,
                         checkpoint=checkpoints / checkpoint)  # fmt: skip
        obs = tuned.env.reset()
        assert torch.allclose(tuned.algorithm.act(obs),
                              source.algorithm.act({"actor": obs["actor"]}), atol=1e-5), checkpoint


def test_an_image_student_distils_exports_and_matches_its_onnx(tmp_path) -> None:
    """A headset + camera-image student (SimXR): the actor gets a CNN for the ego_cameras
    source, learns from the teacher, and its ONNX export (image columns inside the flat
    input) gives the same actions."""
    import json

    import numpy as np

    ort = pytest.importorskip("onnxruntime")
    from retarget.learn.encoders import InputEncoder
    from retarget.train.load import load_run

    run = image_student(tmp_path, steps=64)
    loaded = load_run(run, load_plugins(), num_envs=3)
    actor = loaded.algorithm.learner.actor
    assert isinstance(actor.encoder, InputEncoder) and actor.encoder.images[0].shape == (2, 16, 24)
    assert main(["export", str(run), "--onnx"]) == 0
    onnx_path = run / "export" / "policy.onnx"
    meta = json.loads(onnx_path.with_suffix(".json").read_text())
    assert [s["name"] for s in meta["observation_sources"]] == ["hmd", "ego_cameras", "proprio"]
    obs = loaded.env.reset()["actor"].float()
    expected = loaded.algorithm.act({"actor": obs}).numpy()
    (got,) = ort.InferenceSession(str(onnx_path)).run(None, {"obs": obs.numpy()})
    np.testing.assert_allclose(got, expected, atol=1e-5, rtol=0)


def test_a_recorded_headset_capture_drives_the_image_student(tmp_path) -> None:
    """`motion record --cameras` writes poses + frames; `play --input --cameras` drives an
    image student from them; a recording without frames, or of other cameras, is refused
    naming the file; replayed frames are exactly what the student reads."""
    from retarget import PluginError, RecordedStream
    from retarget.learn.columns import image_inputs
    from retarget.motion.camera_rigs import RIGS

    run = image_student(tmp_path, steps=32)
    assert main(["motion", "generate", "--out", str(tmp_path / "clips"), "--names", "walk"]) == 0
    walk = tmp_path / "clips" / "walk.bvh"
    rec = tmp_path / "me.jsonl"
    assert main(["motion", "record", str(walk), "--out", str(rec), "--cameras", "aria",
                 "--size", "24x16"]) == 0  # fmt: skip
    assert rec.with_name("me.frames.npz").is_file()
    sheet = tmp_path / "play.png"
    assert main(["play", str(run), "--input", str(rec), "--cameras", "--seconds", "1",
                 "--size", "96x72", "--out", str(sheet)]) == 0  # fmt: skip
    assert sheet.stat().st_size > 1000

    # poses only: the image student cannot run from it
    bare = tmp_path / "bare.jsonl"
    assert main(["motion", "record", str(walk), "--out", str(bare)]) == 0
    assert main(["play", str(run), "--input", str(bare), "--out", str(sheet)]) == 2
    # frames of another rig / size are refused by the sensor, naming the frames file
    other = tmp_path / "other.jsonl"
    assert main(["motion", "record", str(walk), "--out", str(other), "--cameras", "quest2",
                 "--size", "24x16"]) == 0  # fmt: skip
    assert main(["play", str(run), "--input", str(other), "--out", str(sheet)]) == 2

    loaded = load_run(run, load_plugins(), num_envs=2)
    env = loaded.env
    sensor = next(s for s in env.sensors if s.name == "ego_cameras")
    rows = env.library.rows(torch.zeros(1, dtype=torch.long), torch.arange(6))[:, 0]
    values = np.random.default_rng(0).integers(0, 256, (6, 2, 16, 24), dtype=np.uint8)
    aria, quest2 = ({"rig": RIGS[r].model_dump_json()} for r in ("aria", "quest2"))
    source = Path("x.frames.npz")
    with pytest.raises(PluginError, match=r"x\.frames\.npz.*other cameras"):
        sensor.replay(rows, RecordedStream(values, quest2, source))
    with pytest.raises(PluginError, match=r"x\.frames\.npz: frames are uint8 2x16x23"):
        sensor.replay(rows, RecordedStream(values[..., :23], aria, source))
    sensor.replay(rows, RecordedStream(values, aria, source))
    (image,) = image_inputs(env, "actor")
    obs = env.place(torch.zeros(2, dtype=torch.long), torch.tensor([2, 5]))["actor"]
    seen = obs[:, image.start : image.start + image.size].reshape(2, *image.shape).numpy()
    np.testing.assert_allclose(seen, values[[2, 5]] / 255.0, atol=1e-6)


def test_a_student_is_redistilled_from_another_students_weights(
    teacher: Path, tmp_path: Path
) -> None:
    """``--init-from`` a student into a new DAgger run (a better teacher, more motions): it
    starts acting exactly as that student, with fresh counters."""
    recipe = student_recipe(tmp_path, teacher)
    assert main(["train", str(recipe), "--steps", str(2 * SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    student = tmp_path / "student" / "latest"
    assert main(["train", str(recipe), "--init-from", str(student), "--set", "name=again",
                 "--steps", str(SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    again = tmp_path / "again" / "latest"
    assert (again / "init_from.txt").is_file()
    registry = load_plugins()
    first = load_run(again, registry, num_envs=4,
                     checkpoint=again / "checkpoints" / "ckpt-0000000.pt")
    source = load_run(student, registry, num_envs=4)
    assert first.algorithm.learner.env_steps == 0  # type: ignore[attr-defined]
    obs = first.env.reset()
    assert torch.allclose(first.algorithm.act(obs), source.algorithm.act(obs), atol=1e-5)
