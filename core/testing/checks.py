"""The plugin contract, one function per check, grouped by plugin kind.

Each check takes the plugin (a class, or an instance whose ``config`` is used) and raises
``AssertionError`` with a message that says what to fix. Third-party packages run the same
checks through :func:`retarget.testing.parametrize_with_checks`.
"""

from __future__ import annotations

import argparse
import inspect
import io
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np
import pluggy
import torch
import yaml
from pydantic import ValidationError

from retarget.errors import MotionError
from retarget.kinds import KINDS, Plugin, PluginConfig
from retarget.kinds.base import NAME_RE
from retarget.kinds.capabilities import Acting, PoseEstimating
from retarget.kinds.iteration import IterationResult, as_result
from retarget.kinds.step import StepNeeds
from retarget.motion.clip import MotionClip
from retarget.motion.skeleton import NUM_JOINTS
from retarget.registry import hookspecs
from retarget.registry.loader import load_plugins
from retarget.sim.world import build_world
from retarget.testing.fakes import (
    FakeVecEnv,
    TinyCharacter,
    fake_context,
    fake_library,
    kinematic_env,
    tiny_world,
)
from retarget.testing.guard import NoPerEnvLoops
from retarget.testing.toolkit import check_uses_toolkit
from retarget.train.checkpoint import SAFE_GLOBALS

Check = Callable[[object], None]
BATCH_SIZES = (1, 4, 7)
GUARD_BATCH = 13  # a size no tiny-character dimension has, so integer indexing is attributable


def plugin_class(plugin: object) -> type[Plugin]:
    return plugin if isinstance(plugin, type) else type(plugin)


def kind_of(plugin: object) -> str:
    cls = plugin_class(plugin)
    for kind, base in KINDS.items():
        if kind != "sensor" and issubclass(cls, base):
            return kind
    if issubclass(cls, KINDS["sensor"]):
        return "sensor"
    raise AssertionError(f"{cls.__name__} subclasses none of retarget.kinds' base classes")


def make(plugin: object) -> Plugin:
    """A fresh instance with the plugin's config (so stateful plugins start clean)."""
    cls = plugin_class(plugin)
    if isinstance(plugin, Plugin):
        return cls(plugin.config)
    return cls.example()


# ---------------------------------------------------------------- every kind


def check_name(plugin: object) -> None:
    cls = plugin_class(plugin)
    name = getattr(cls, "name", None)
    assert isinstance(name, str), f"{cls.__name__} must set a class attribute `name`"
    assert NAME_RE.match(name), f"name {name!r} of {cls.__name__} must be snake_case"


def check_docstring(plugin: object) -> None:
    cls = plugin_class(plugin)
    assert (cls.__doc__ or "").strip(), (
        f"{cls.__name__} needs a class docstring: it is the help `retarget plugins show` prints"
    )


def check_config_strict(plugin: object) -> None:
    cls = plugin_class(plugin)
    config_cls = cls.Config
    assert isinstance(config_cls, type) and issubclass(config_cls, PluginConfig), (
        f"{cls.__name__}.Config must subclass retarget.PluginConfig"
    )
    assert config_cls.model_config.get("extra") == "forbid", "Config must forbid unknown fields"
    assert config_cls.model_config.get("frozen") is True, "Config must be frozen"
    try:
        default = config_cls()
    except ValidationError as exc:
        # a required field (a teacher run) is fine when example() shows a working config
        try:
            example = cls.example().config
        except ValidationError:
            example = None
        if type(example) is config_cls:
            default = example
        else:
            raise AssertionError(
                f"{cls.__name__}.Config() must work with defaults only, or example() must "
                f"give a config for its required fields: {exc.errors()[0]['msg']}"
            ) from None
    try:
        config_cls(__retarget_unknown_field__=1)
    except ValidationError:
        pass
    else:
        raise AssertionError("Config accepted an unknown field")
    text = yaml.safe_dump(default.model_dump(mode="json"))
    assert config_cls.model_validate(yaml.safe_load(text)) == default, (
        "Config does not survive a YAML round trip (recipe.lock.yaml relies on it)"
    )


def check_config_schema(plugin: object) -> None:
    try:
        schema = plugin_class(plugin).Config.model_json_schema()
    except Exception as exc:
        raise AssertionError(f"Config has no JSON Schema: {exc}") from exc
    assert schema.get("type") == "object", "Config JSON Schema must describe an object"


def check_registers_cleanly(plugin: object) -> None:
    """The plugin's module registers it through a hook, with no validation errors."""
    cls = plugin_class(plugin)
    module = sys.modules[cls.__module__]
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    pm.register(module, name=f"check::{cls.__module__}")
    pm.check_pending()
    found = []
    for hook_name in hookspecs.HOOK_KINDS:
        getattr(pm.hook, hook_name)(register=lambda c, **_: found.append(c))
    assert cls in found, (
        f"module {cls.__module__} has no @retarget.hookimpl that registers {cls.__name__}"
    )


def check_entry_point(plugin: object) -> None:
    """The plugin is reachable through installed entry-point metadata (the real load path)."""
    cls = plugin_class(plugin)
    registry = load_plugins(strict=True)
    kind = kind_of(plugin)
    entries = [e for e in registry.entries[kind].values() if e.cls is cls]
    assert entries, (
        f"{cls.__name__} is not registered through any installed entry point of group "
        "'retarget': add it to [project.entry-points.retarget] and reinstall"
    )


# ---------------------------------------------------------------- batched step plugins


def _bound(plugin: object, layout):
    inst = make(plugin)
    inst.bind(layout)
    inst.prepare(fake_library())  # what the env does before the first step
    return inst


def _run(inst: Plugin, kind: str, ctx) -> torch.Tensor:
    if kind == "reward":
        return inst.compute(ctx)
    if kind == "termination":
        return inst.check(ctx)
    return inst.observe(ctx)


def _expected(inst: Plugin, kind: str, layout) -> tuple[tuple[int, ...], torch.dtype]:
    if kind == "reward":
        return (), torch.float32
    if kind == "termination":
        return (), torch.bool
    spec = inst.spec(layout)
    return tuple(spec.shape), spec.torch_dtype


def check_batched_shapes(plugin: object) -> None:
    kind = kind_of(plugin)
    layout = tiny_world().layout
    for n in BATCH_SIZES:
        inst = _bound(plugin, layout)
        ctx = _context(plugin, layout, n, n)
        out = _run(inst, kind, ctx)
        shape, dtype = _expected(inst, kind, layout)
        assert isinstance(out, torch.Tensor), f"returned {type(out).__name__}, not a tensor"
        assert tuple(out.shape) == (n, *shape), f"N={n}: shape {tuple(out.shape)} != {(n, *shape)}"
        assert out.dtype == dtype, f"N={n}: dtype {out.dtype}, expected {dtype}"


def _future(plugin: object) -> tuple[int, ...]:
    """Frames ahead the plugin reads ``ctx.ref.future`` at (its ``needs()``), else 1-3."""
    inst = make(plugin)
    return tuple(inst.needs().reference_offsets) or (1, 2, 3)


def _window(plugin: object, layout) -> tuple[int, ...]:
    """The device window the environment gathers for this plugin alone: a bound sensor's
    ``frames_needed()`` (past, future) as offsets, as ``RetargetEnv`` sizes it."""
    inst = _bound(plugin, layout)
    past, future = inst.frames_needed() if hasattr(inst, "frames_needed") else (0, 0)
    return tuple(range(-int(past), int(future) + 1))


def _context(plugin: object, layout, n: int, seed: int):
    """A fake step shaped for ``plugin``: its future offsets and its device window."""
    return fake_context(layout, n, seed=seed, future_offsets=_future(plugin),
                        window_offsets=_window(plugin, layout))  # fmt: skip


def check_finite(plugin: object) -> None:
    kind = kind_of(plugin)
    layout = tiny_world().layout
    ctx = _context(plugin, layout, 7, 3)
    out = _run(_bound(plugin, layout), kind, ctx)
    if out.is_floating_point():
        assert torch.isfinite(out).all(), "output has NaN or Inf on valid input"


def check_batch_invariance(plugin: object) -> None:
    """Computing a subset of environments equals slicing the whole: no coupling across envs."""
    kind = kind_of(plugin)
    layout = tiny_world().layout
    ctx = _context(plugin, layout, 7, 11)
    full = _run(_bound(plugin, layout), kind, ctx)
    idx = torch.tensor([1, 3, 4, 6])
    part = _run(_bound(plugin, layout), kind, ctx.select(idx))
    same = (
        torch.equal(part, full[idx])
        if not part.is_floating_point()
        else torch.allclose(part, full[idx], atol=1e-5, rtol=1e-5)
    )
    assert same, "result for a subset of environments differs from the same rows of the full batch"


def check_deterministic(plugin: object) -> None:
    kind = kind_of(plugin)
    layout = tiny_world().layout
    ctx = _context(plugin, layout, 4, 5)
    a = _run(_bound(plugin, layout), kind, ctx)
    b = _run(_bound(plugin, layout), kind, ctx)
    assert torch.equal(a, b), "two fresh instances disagree on the same input"


def check_subset_reset(plugin: object) -> None:
    kind = kind_of(plugin)
    layout = tiny_world().layout
    inst = _bound(plugin, layout)
    ctx = _context(plugin, layout, 7, 2)
    _run(inst, kind, ctx)
    rows = torch.tensor([0, 5])
    inst.reset(rows)
    out = _run(inst, kind, ctx)
    assert out.shape[0] == 7, "after reset(subset) the batch size changed"
    fresh = _run(_bound(plugin, layout), kind, ctx)
    same = (torch.equal(out[rows], fresh[rows]) if not out.is_floating_point()
            else torch.allclose(out[rows], fresh[rows], atol=1e-5, rtol=1e-5))  # fmt: skip
    assert same, ("rows reset with reset(env_ids) differ from a fresh instance's on the same "
                  "step: reset must clear every per-environment state of those rows")


def check_vectorised(plugin: object) -> None:
    """No per-environment Python access in ``compute``/``check``/``observe``."""
    kind = kind_of(plugin)
    layout = tiny_world().layout
    inst = _bound(plugin, layout)
    ctx = _context(plugin, layout, GUARD_BATCH, 7)
    with NoPerEnvLoops(GUARD_BATCH):
        _run(inst, kind, ctx)


def check_recorded(plugin: object) -> None:
    """A sensor that declares a recorded stream (``recorded = "images"``) implements
    ``replay``, which ``retarget play --input`` calls with the recording's values."""
    from retarget.kinds.sensor import Sensor

    cls = plugin_class(plugin)
    if cls.recorded is None:
        return
    assert isinstance(cls.recorded, str) and NAME_RE.match(cls.recorded), (
        f"recorded = {cls.recorded!r}: name the stream, e.g. 'images'"
    )
    assert cls.replay is not Sensor.replay, (
        f"declares recorded = {cls.recorded!r} but does not implement replay(rows, stream)"
    )


def check_spec(plugin: object) -> None:
    inst = make(plugin)
    spec = inst.spec(tiny_world().layout)
    assert all(isinstance(s, int) and s > 0 for s in spec.shape), f"bad ObsSpec shape {spec.shape}"


# ---------------------------------------------------------------- characters


def _world(plugin: object):
    return build_world(make(plugin))


def check_character_compiles(plugin: object) -> None:
    world = _world(plugin)
    assert world.model.nu > 0, "a character needs at least one actuator"
    assert world.layout.num_bodies > 1, "a character needs more than a root body"


def check_character_retargets(plugin: object) -> None:
    """The character has a joint map and a generated walk retargets onto it as
    ``retarget train`` does (finite poses inside the joint limits)."""
    import numpy as np

    from retarget.character.kinematic import retarget_clip
    from retarget.motion.procedural import default_motions

    inst = make(plugin)
    joint_map = inst.joint_map()
    assert joint_map is not None, ("joint_map() returns None: a character needs a joint map "
                                   "to be trained on human motion (retarget.character.joint_map)")
    world = _world(plugin)
    walk = next(c for c in default_motions() if c.name.startswith("walk"))
    motion = retarget_clip(walk, world.model, joint_map)
    assert motion.qpos.shape == (walk.num_frames, world.model.nq), "retargeted poses' shape"
    assert np.isfinite(motion.qpos).all(), "retargeting a generated walk gives NaN/Inf poses"


def check_character_passive_unactuated(plugin: object) -> None:
    world = _world(plugin)
    m = world.model
    actuated = {
        mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, m.actuator_trnid[a, 0]) for a in range(m.nu)
    }
    both = sorted(set(world.layout.passive_joints) & actuated)
    assert not both, f"passive joints must have no actuator: {', '.join(both)}"
    for joint in world.layout.passive_joints:
        assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint) >= 0, (
            f"passive joint '{joint}' does not exist"
        )


def check_character_torque_limits(plugin: object) -> None:
    m = _world(plugin).model
    for a in range(m.nu):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        assert m.actuator_ctrllimited[a], f"actuator '{name}' must have ctrlrange [-1, 1]"
        assert np.allclose(m.actuator_ctrlrange[a], [-1, 1]), (
            f"actuator '{name}' ctrlrange {m.actuator_ctrlrange[a]} must be [-1, 1] "
            "(the torque limit is the gear)"
        )
        assert m.actuator_gear[a, 0] > 0, f"actuator '{name}' needs a positive gear (torque limit)"


def check_character_zero_torque_steps(plugin: object) -> None:
    world = _world(plugin)
    data = mujoco.MjData(world.model)
    mujoco.mj_forward(world.model, data)
    for _ in range(10):
        mujoco.mj_step(world.model, data)
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all(), (
        "10 zero-torque steps produced non-finite state"
    )
    assert data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number == 0, (
        "10 zero-torque steps hit MuJoCo's bad-acceleration reset: the model is unstable"
    )


# ---------------------------------------------------------------- scenes


def check_scene_composes(plugin: object) -> None:
    scene = make(plugin)
    world = build_world(TinyCharacter(), scene)
    data = mujoco.MjData(world.model)
    for _ in range(10):
        mujoco.mj_step(world.model, data)
    assert np.isfinite(data.qpos).all(), "tiny character in this scene went non-finite"


def check_scene_queries(plugin: object) -> None:
    scene = make(plugin)
    for n in BATCH_SIZES:
        xy = torch.rand(n, 9, 2) * 2 - 1
        h = scene.height_at(xy)
        assert tuple(h.shape) == (n, 9), f"height_at shape {tuple(h.shape)} != {(n, 9)}"
        assert h.dtype == torch.float32 and torch.isfinite(h).all(), "height_at must be finite f32"
    pts = scene.surface_points(64, np.random.default_rng(0))
    assert pts.shape == (1, 64, 3) and np.isfinite(pts).all(), (
        f"surface_points before allocate() must be (1, count, 3), got {pts.shape}"
    )
    scene.randomize(torch.tensor([0, 2]), torch.Generator().manual_seed(0))
    local = scene.local_surface_points(32, np.random.default_rng(0))
    if local is not None:  # prop-frame samples: (count, 4), placed as (N, count, 3)
        assert local.shape == (32, 4), f"local_surface_points shape {local.shape} != (32, 4)"
        placed = scene.place_surface_points(torch.from_numpy(local).float(), torch.float32)
        assert tuple(placed.shape[1:]) == (32, 3) and torch.isfinite(placed).all(), (
            f"place_surface_points must give finite (N, 32, 3), got {tuple(placed.shape)}"
        )


def check_needs(plugin: object) -> None:
    """``needs()`` is a :class:`~retarget.kinds.step.StepNeeds` with offsets ``>= 1``."""
    need = make(plugin).needs()
    assert isinstance(need, StepNeeds), f"needs() returned {type(need).__name__}, not StepNeeds"
    bad = [k for k in need.reference_offsets if not isinstance(k, int) or k < 1]
    assert not bad, f"needs() asks for reference offsets {bad}; frames ahead are ints >= 1"


def check_scene_placement(plugin: object) -> None:
    """Per-environment placement: allocate, randomize, query all envs and a subset, and the
    mocap bodies the scene names exist in the compiled world as mocap bodies."""
    scene = make(plugin)
    world = build_world(TinyCharacter(), scene)
    m = world.model
    ids = []
    for body in scene.mocap_bodies():
        bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
        assert bid >= 0 and m.body_mocapid[bid] >= 0, (
            f"mocap_bodies() names '{body}', which is not a mocap body of the compiled world"
        )
        ids.append(bid)
    n = 5
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(1))
    pos, quat = scene.mocap_poses(torch.arange(n))
    k = len(ids)
    assert tuple(pos.shape) == (n, k, 3) and tuple(quat.shape) == (n, k, 4), (
        f"mocap_poses shapes {tuple(pos.shape)}, {tuple(quat.shape)} != {(n, k, 3)}, {(n, k, 4)}"
    )
    assert torch.isfinite(pos).all() and torch.allclose(
        quat.norm(dim=-1), torch.ones(()).to(quat.dtype), atol=1e-6
    ), "mocap_poses must be finite positions and unit quaternions"
    xy = torch.rand(n, 11, 2, generator=torch.Generator().manual_seed(2)) * 6 - 3
    h = scene.height_at(xy)
    assert tuple(h.shape) == (n, 11) and torch.isfinite(h).all(), "height_at after allocate()"
    sub = torch.tensor([1, 4])
    assert torch.allclose(scene.select(sub).height_at(xy[sub]), h[sub], atol=1e-6), (
        "select(ids).height_at differs from the same rows of the full batch"
    )
    pts = scene.surface_points(32, np.random.default_rng(0))
    assert pts.shape in ((n, 32, 3), (1, 32, 3)) and np.isfinite(pts).all(), (
        f"surface_points after allocate({n}) must be ({n} or 1, count, 3), got {pts.shape}"
    )
    pts = np.broadcast_to(pts, (n, 32, 3))
    part = scene.select(sub).surface_points(32, np.random.default_rng(0))
    if part.shape[0] != len(sub):  # a static scene: one row, or select() is the scene itself
        part = np.broadcast_to(part, (n, 32, 3))[sub.numpy()]
    assert np.allclose(part, pts[sub.numpy()], atol=1e-6), (
        "select(ids).surface_points differs from the same rows of the full batch"
    )


# ---------------------------------------------------------------- algorithms


def _estimates(env, algo) -> torch.Tensor:
    """A kinematic algorithm's estimate of every library frame, flattened (root + joints)."""
    from retarget.eval.kinematic import estimate_library

    est = estimate_library(env, algo.pose_estimator())
    parts = [np.concatenate([c.root_pos, c.local_rot.reshape(c.num_frames, -1)], -1)
             for c in est.clips]  # fmt: skip
    return torch.from_numpy(np.concatenate([*parts], 0))


def _iteration(value: object) -> IterationResult:
    """An iteration's return, checked: statistics present and finite."""
    try:
        result = as_result(value)  # type: ignore[arg-type]
    except TypeError as exc:
        raise AssertionError(str(exc)) from None
    assert result.stats, "train_iteration must return statistics"
    assert not result.non_finite(), f"non-finite training statistics: {result.non_finite()}"
    return result


def check_algorithm_update(plugin: object) -> None:
    cls = plugin_class(plugin)
    assert issubclass(cls, Acting) or issubclass(cls, PoseEstimating), (
        "an algorithm acts (act(obs)) or estimates poses (pose_estimator()): retarget can "
        "neither evaluate nor deploy one that does neither"
    )
    if issubclass(cls, PoseEstimating):
        env = kinematic_env()
        algo = make(plugin)
        algo.setup(env, torch.Generator().manual_seed(0))
        result = _iteration(algo.train_iteration(env))
        assert result.samples, (
            "a kinematic algorithm steps no environment: its IterationResult must say how "
            "many samples it learnt from (samples=...), or the run's budget never advances"
        )
        assert algo.pose_estimator() is not None, "a kinematic algorithm gives pose_estimator()"
        est = _estimates(env, algo)
        assert torch.isfinite(est).all(), "the pose estimate is not finite"
        return
    env = FakeVecEnv(num_envs=4)
    algo = make(plugin)
    algo.setup(env, torch.Generator().manual_seed(0))
    _iteration(algo.train_iteration(env))
    obs = env.reset()
    action = algo.act(obs)
    assert tuple(action.shape) == (4, env.action_dim), f"act shape {tuple(action.shape)}"
    assert torch.isfinite(action).all(), "act returned non-finite actions"


def check_algorithm_checkpoint(plugin: object) -> None:
    kinematic = issubclass(plugin_class(plugin), PoseEstimating)
    env = kinematic_env() if kinematic else FakeVecEnv(num_envs=4, seed=1)
    algo = make(plugin)
    algo.setup(env, torch.Generator().manual_seed(0))
    algo.train_iteration(env)
    buffer = io.BytesIO()
    torch.save(algo.state_dict(), buffer)
    buffer.seek(0)
    other = make(plugin)
    other.setup(env, torch.Generator().manual_seed(123))
    try:  # checkpoints are read without running code: the state must be plain data
        with torch.serialization.safe_globals(SAFE_GLOBALS):
            state = torch.load(buffer, weights_only=True)
    except Exception as exc:
        raise AssertionError(
            f"state_dict() holds something a safe checkpoint load refuses: {exc}"
        ) from None
    other.load_state_dict(state)
    if kinematic:
        assert torch.equal(_estimates(env, algo), _estimates(env, other)), (
            "a restored checkpoint estimates differently"
        )
        return
    obs = env.reset()
    assert torch.equal(algo.act(obs), other.act(obs)), "a restored checkpoint acts differently"


# ---------------------------------------------------------------- motion formats


def check_motion_format_reads_sample(plugin: object) -> None:
    fmt = make(plugin)
    with tempfile.TemporaryDirectory() as tmp:
        path = plugin_class(plugin).write_sample(Path(tmp))
        clip = fmt.read(path)
    assert isinstance(clip, MotionClip), f"read() returned {type(clip).__name__}, not MotionClip"
    assert float(clip.fps) > 0, "clip.fps must be positive"
    assert clip.local_rot.shape[1:] == (NUM_JOINTS, 4), "clip must be on the canonical skeleton"
    for key, value in vars(clip).items():
        if isinstance(value, np.ndarray) and value.dtype.kind == "f":
            assert np.isfinite(value).all(), f"clip.{key} has non-finite values"


def check_motion_format_rejects_garbage(plugin: object) -> None:
    cls = plugin_class(plugin)
    fmt = make(plugin)
    suffix = cls.suffixes[0] if cls.suffixes else ".dat"
    with tempfile.TemporaryDirectory() as tmp:
        for label, content in (("empty", b""), ("garbage", b"\x00\xff not a motion file {[")):
            path = Path(tmp) / f"{label}{suffix}"
            path.write_bytes(content)
            try:
                fmt.read(path)
            except MotionError as exc:
                assert exc.file is not None and Path(exc.file).name == path.name, (
                    f"MotionError for the {label} file must name the file"
                )
            except Exception as exc:
                raise AssertionError(
                    f"{label} file raised {type(exc).__name__}, expected retarget.MotionError"
                ) from exc
            else:
                raise AssertionError(f"reading an {label} file did not raise MotionError")


# ---------------------------------------------------------------- commands


def check_command_arguments(plugin: object) -> None:
    cmd = make(plugin)
    parser = argparse.ArgumentParser(prog=f"retarget {plugin_class(plugin).name}")
    cmd.add_arguments(parser)
    assert callable(cmd.run), "a command needs run(args)"
    assert len(inspect.signature(cmd.run).parameters) == 1, "run takes exactly (args)"


# ---------------------------------------------------------------- planners


def _planned(plugin: object):
    from retarget.testing.fakes import planning_env

    env = planning_env()
    return env, make(plugin).track(env, 0, seconds=0.25, threads=1)


def check_planner_tracks(plugin: object) -> None:
    """A quarter second of a generated walk: the path has one action per step, finite states
    of the whole model, actions in [-1, 1], the reference's bodies beside its own, and the
    actions stepped in the env from the placed first frame reproduce its states."""
    from retarget import Track

    env, track = _planned(plugin)
    assert isinstance(track, Track), f"track() returned {type(track).__name__}, not a Track"
    T, sim = track.frames, env.sim
    assert 2 <= T <= 10, f"0.25 s at 36 Hz is at most 10 frames, got {T}"
    assert track.actions.shape == (T - 1, env.action_dim), f"actions {track.actions.shape}"
    assert track.qpos.shape == (T, sim.raw("qpos").shape[1]), f"qpos {track.qpos.shape}"
    assert track.qvel.shape == (T, sim.raw("qvel").shape[1]), f"qvel {track.qvel.shape}"
    bodies = len(env.layout.body_ids)
    for name in ("body_pos", "ref_body_pos"):
        shape = getattr(track, name).shape
        assert shape == (T, bodies, 3), f"{name} {shape} != {(T, bodies, 3)}"
    for name in ("actions", "qpos", "qvel", "body_pos"):
        assert np.isfinite(getattr(track, name)).all(), f"non-finite {name}"
    assert np.abs(track.actions).max() <= 1.0 + 1e-6, "actions outside [-1, 1]"
    env.place(torch.tensor([0]), torch.tensor([0]))
    assert np.allclose(sim.raw("qpos")[0], track.qpos[0], atol=1e-6), (
        "frame 0 is not the env's placed first frame"
    )
    for t, action in enumerate(track.actions):
        sim.step(action[None].astype(np.float64))
        gap = float(np.abs(sim.raw("qpos")[0] - track.qpos[t + 1]).max())
        assert gap < 1e-4, f"replaying the actions leaves the path at step {t} (by {gap:.2e})"
    figures = track.metrics()
    assert {"success_clip", "mpjpe_mm", "cpu_s_per_motion_s"} <= set(figures), figures


def check_planner_deterministic(plugin: object) -> None:
    """The same planner settings plan the same actions twice (resumed runs rely on it)."""
    _, first = _planned(plugin)
    _, second = _planned(plugin)
    assert np.array_equal(first.actions, second.actions), "two plans of one clip differ"


# ---------------------------------------------------------------- the table


def check_callback_events(plugin: object) -> None:
    """Every event of a short run, with a read-only copy of the statistics, returns quietly
    (the trainer switches off a callback that raises)."""
    from types import MappingProxyType

    inst = make(plugin)
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp)
        inst.on_train_start(run, {"character": {"type": "tiny"}}, False)
        for i in (1, 2):
            inst.on_iteration(i, 100 * i, MappingProxyType({"loss": 0.5, "odd": float("nan")}))
        ckpt = run / "checkpoints" / "ckpt-0000002.pt"
        inst.on_checkpoint(ckpt, 2)
        inst.on_train_end("budget", ckpt)


COMMON: tuple[Check, ...] = (
    check_name,
    check_docstring,
    check_config_strict,
    check_config_schema,
    check_registers_cleanly,
    check_uses_toolkit,
)
STEP: tuple[Check, ...] = (
    check_needs,
    check_batched_shapes,
    check_finite,
    check_batch_invariance,
    check_deterministic,
    check_subset_reset,
    check_vectorised,
)
BY_KIND: dict[str, tuple[Check, ...]] = {
    "reward": STEP,
    "termination": STEP,
    "sensor": (check_spec, check_recorded, *STEP),
    "observer": (check_spec, check_recorded, *STEP),
    "character": (
        check_character_compiles,
        check_character_retargets,
        check_character_passive_unactuated,
        check_character_torque_limits,
        check_character_zero_torque_steps,
    ),
    "scene": (check_scene_composes, check_scene_queries, check_scene_placement),
    "algorithm": (check_algorithm_update, check_algorithm_checkpoint),
    "motion_format": (check_motion_format_reads_sample, check_motion_format_rejects_garbage),
    "command": (check_command_arguments,),
    "callback": (check_callback_events,),
    "planner": (check_planner_tracks, check_planner_deterministic),
}


def checks_for(plugin: object, *, installed: bool = True) -> list[Check]:
    """Every check that applies to ``plugin``; ``installed=False`` skips the entry-point check."""
    found = [*COMMON, *BY_KIND[kind_of(plugin)]]
    if installed:
        found.append(check_entry_point)
    return found
