"""``BatchedSim``: N copies of one compiled world stepped on MuJoCo's own thread pool.

It uses ``mujoco.batch.Batch`` (persistent ``MjData`` per environment, C++ threads), which on
this class of machine runs within noise of two processes while keeping everything in one
address space. State is gathered once per control step into preallocated float32 arrays that
are exposed to plugins as torch tensors sharing their memory (no copy).

A backend for another engine subclasses it and gives the same ``step``, ``reset``,
``set_mocap``, ``state_dict`` and bad-state detection over the same arrays
(:class:`retarget.sim.warp_backend.WarpSim` runs MuJoCo Warp); :func:`make_sim` picks one
from the recipe's ``sim.backend``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

import mujoco
import numpy as np
import torch
from mujoco.batch import Batch

from retarget.kinds.state import Layout, SimState
from retarget.settings.sim import SimSettings
from retarget.sim.actuation import apply_actuation

T = TypeVar("T")

HUGE_VELOCITY = 1e4
"""|qvel| above this (rad/s or m/s) counts as a blown-up simulation, like MuJoCo's own check."""


def body_velocities(
    cvel: np.ndarray, xpos: np.ndarray, subtree_com: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World angular and linear velocity at each body's origin from MuJoCo's ``cvel``.

    ``cvel`` ``(..., B, 6)`` is [angular, linear] with the linear part taken at the centre of
    mass of the body's kinematic tree (``subtree_com`` of its root body, ``(..., B, 3)``);
    moving it to the body origin ``xpos`` adds ``w x (p - c)``.
    """
    ang = cvel[..., :3]
    lin = cvel[..., 3:] + np.cross(ang, xpos - subtree_com)
    return ang, lin


def add_contact_force_sensor(spec: mujoco.MjSpec, site: str) -> None:
    """An accelerometer on ``site`` makes MuJoCo compute ``cfrc_ext`` (per-body contact
    forces) every step; without an acceleration-stage sensor that array stays zero."""
    spec.add_sensor(
        name="retarget_contact_forces",
        type=mujoco.mjtSensor.mjSENS_ACCELEROMETER,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname=site,
    )


class BatchedSim:
    """N environments of one model; ``step`` applies actions in [-1, 1] for one control step.

    The model must have been compiled with :func:`add_contact_force_sensor` for
    ``contact_force`` to be meaningful (``retarget.sim.world.build_world`` does this).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        layout: Layout,
        num_envs: int,
        settings: SimSettings | None = None,
    ) -> None:
        self.settings = settings or SimSettings()
        self.model = model
        self.model.opt.timestep = self.settings.timestep
        apply_actuation(
            model,
            self.settings.actuation,
            saturation=self.settings.pd_saturation,
            damping=self.settings.pd_damping,
        )
        self.layout = layout
        self.num_envs = num_envs
        self._open()
        self._nq, self._nv = layout.nq, layout.nv  # the character's block; scene joints follow
        self._bodies = np.asarray(layout.body_ids, dtype=np.intp)
        self._tree_roots = np.asarray(model.body_rootid[self._bodies], dtype=np.intp)
        self._sites = np.asarray(layout.site_ids, dtype=np.intp)
        self._own_geom = np.isin(model.geom_bodyid, self._bodies)  # the character's geoms
        self._scratch: mujoco.MjData | None = None
        n, b, s = num_envs, len(self._bodies), len(self._sites)
        f32 = np.float32
        self._buf = {
            "qpos": np.zeros((n, layout.nq), f32),
            "qvel": np.zeros((n, layout.nv), f32),
            "body_pos": np.zeros((n, b, 3), f32),
            "body_quat": np.zeros((n, b, 4), f32),
            "body_linvel": np.zeros((n, b, 3), f32),
            "body_angvel": np.zeros((n, b, 3), f32),
            "site_pos": np.zeros((n, s, 3), f32),
            "site_quat": np.zeros((n, s, 4), f32),
            "contact_force": np.zeros((n, b), f32),
            "contact_force_up": np.zeros((n, b), f32),
        }
        self.state = SimState(**{k: torch.from_numpy(v) for k, v in self._buf.items()})
        self.bad_count = 0
        self.seconds = {"physics": 0.0, "gather": 0.0}  # cumulative, for `retarget bench env`
        # Simulation time never restarts in our hands, so an auto-reset by MuJoCo (which sets
        # time to 0) is always visible, even in an env's first step.
        self._time[:] = 1.0
        self.gather()

    def _open(self) -> None:
        """Create the engine's batch and the live ``(N, ...)`` views :meth:`gather` reads."""
        self.batch = Batch(self.model, self.num_envs, nthread=self.settings.threads,
                           persistent=True)  # fmt: skip
        for field in ("qpos", "qvel", "ctrl", "time", "xpos", "xquat", "cvel", "subtree_com",
                      "site_xpos", "site_xquat", "mocap_pos", "mocap_quat"):  # fmt: skip
            setattr(self, f"_{field}", self.batch.bind(field))
        self._cfrc = self.batch.bind("cfrc_ext")

    def _copy_env(self, i: int, data: mujoco.MjData) -> None:
        """Environment ``i``'s whole simulation (contacts included) into ``data``."""
        self.batch.get_data(i, data)

    # ------------------------------------------------------------------ stepping

    def step(self, action: torch.Tensor | np.ndarray) -> np.ndarray:
        """One control step for every environment; returns a bool (N,) mask of envs that went
        non-finite (MuJoCo resets those to the model's defaults: the caller must reset them to
        a meaningful state). State is gathered afterwards."""
        self._ctrl[:] = action.numpy() if isinstance(action, torch.Tensor) else action
        before = self._time.copy()
        t0 = time.perf_counter()
        self.batch.step(nstep=self.settings.substeps)
        t1 = time.perf_counter()
        # MuJoCo resets a blown-up env to the model defaults (time restarts) in any substep
        expected = before + self.settings.substeps * self.settings.timestep
        return self._finish_step(self._time < expected - 0.5 * self.settings.timestep, t0, t1)

    def _finish_step(self, bad: np.ndarray, t0: float, t1: float) -> np.ndarray:
        """After the physics (timed ``t0``..``t1``): flag non-finite or exploding states on
        top of the engine's own ``bad`` mask, count them, gather the state."""
        bad = bad | ~np.isfinite(self._qpos).all(axis=1) | ~np.isfinite(self._qvel).all(axis=1)
        bad |= (np.abs(self._qvel) > HUGE_VELOCITY).any(axis=1)
        self.bad_count += int(bad.sum())
        self.gather()
        self.seconds["physics"] += t1 - t0
        self.seconds["gather"] += time.perf_counter() - t1
        return bad

    def set_root_wrench(self, wrench: np.ndarray | None) -> None:
        """World force and torque ``(N, 6)`` on the character's root body for the coming
        steps (held over their substeps); None removes it."""
        if not hasattr(self, "_xfrc"):
            if wrench is None:
                return
            self._xfrc = self.batch.bind("xfrc_applied")
        self._xfrc[:, self._bodies[0]] = 0.0 if wrench is None else wrench

    def reset(
        self,
        env_ids: np.ndarray,
        qpos: np.ndarray,
        qvel: np.ndarray | None = None,
        mocap: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """Put ``env_ids`` into the given state (e.g. a reference frame for RSI) and recompute
        derived quantities for them only.

        ``qpos``/``qvel`` may cover only the leading (character) coordinates: the rest (joints
        of articulated scene props) keep the model's defaults. ``mocap`` is ``(ids, pos, quat)``:
        mocap body ids ``(M,)`` and their poses ``(E, M, 3)``/``(E, M, 4)`` for these envs.
        """
        env_ids = np.asarray(env_ids, dtype=np.intp)
        if env_ids.size == 0:
            return
        time = self._time[env_ids].copy()
        self.batch.reset(env_ids, stage=mujoco.mjtStage.mjSTAGE_NONE)
        self._time[env_ids] = time
        self._qpos[env_ids, : qpos.shape[-1]] = qpos
        if qvel is not None:
            self._qvel[env_ids, : qvel.shape[-1]] = qvel
        self._ctrl[env_ids] = 0.0
        if mocap is not None and len(mocap[0]):
            self.set_mocap(env_ids, *mocap, forward=False)
        self.batch.forward(env_ids)
        self.gather(env_ids)

    def set_mocap(
        self,
        env_ids: np.ndarray,
        ids: np.ndarray,
        pos: np.ndarray,
        quat: np.ndarray,
        *,
        forward: bool = True,
    ) -> None:
        """Write poses ``(E, M, 3)``/``(E, M, 4)`` of mocap bodies ``ids`` ``(M,)`` (indices
        into ``mocap_pos``) for ``env_ids``: one fancy-indexed write per field, no loop."""
        env_ids = np.asarray(env_ids, dtype=np.intp)
        rows = np.ix_(env_ids, np.asarray(ids, dtype=np.intp))
        self._mocap_pos[rows] = pos
        self._mocap_quat[rows] = quat
        if forward and env_ids.size:
            self.batch.forward(env_ids)
            self.gather(env_ids)

    # ------------------------------------------------------------------ gathering

    def gather(self, env_ids: np.ndarray | None = None) -> None:
        """Copy this step's state (of ``env_ids``, default all) into the float32 buffers
        behind ``self.state``."""
        rows: slice | np.ndarray = slice(None) if env_ids is None else env_ids
        sel = np.ix_(np.arange(self.num_envs)[rows], self._bodies)
        buf = self._buf
        buf["qpos"][rows] = self._qpos[rows, : self._nq]
        buf["qvel"][rows] = self._qvel[rows, : self._nv]
        xpos = self._xpos[sel]
        buf["body_pos"][rows] = xpos
        buf["body_quat"][rows] = self._xquat[sel]
        roots = np.ix_(np.arange(self.num_envs)[rows], self._tree_roots)
        ang, lin = body_velocities(self._cvel[sel], xpos, self._subtree_com[roots])
        buf["body_angvel"][rows] = ang
        buf["body_linvel"][rows] = lin
        sites = np.ix_(np.arange(self.num_envs)[rows], self._sites)
        buf["site_pos"][rows] = self._site_xpos[sites]
        buf["site_quat"][rows] = self._site_xquat[sites]
        force = self._cfrc[sel][..., 3:]  # world-frame force part of cfrc_ext
        buf["contact_force"][rows] = np.linalg.norm(force, axis=-1)
        buf["contact_force_up"][rows] = force[..., 2]

    STATE_FIELDS = (
        "qpos",
        "qvel",
        "act",
        "ctrl",
        "time",
        "qacc_warmstart",
        "mocap_pos",
        "mocap_quat",
    )
    """What a checkpoint needs for the next step to be bit-identical to an uninterrupted run."""

    def state_dict(self) -> dict[str, np.ndarray]:
        return {k: self.batch.bind(k).copy() for k in self.STATE_FIELDS}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        for key in self.STATE_FIELDS:
            if key in state:  # checkpoints written before mocap props keep model defaults
                self.batch.bind(key)[:] = state[key]
        self.batch.forward()
        self.gather()

    def penetration(self) -> tuple[np.ndarray, np.ndarray]:
        """Per environment ``(N,)``, the deepest and the mean overlap (metres, 0 when none) of
        the character's geoms into other geoms (scene props and floor) among the contacts of
        the last physics step. MuJoCo's contact list is per simulation and not batched, so
        this copies each environment's data out: an evaluation metric, not a training one."""
        if self._scratch is None:
            self._scratch = mujoco.MjData(self.model)
        deepest = np.zeros(self.num_envs)
        mean = np.zeros(self.num_envs)
        data = self._scratch
        for i in range(self.num_envs):  # BatchedSim is where per-environment loops live
            self._copy_env(i, data)
            deepest[i], mean[i] = self._overlap(data)
        return deepest, mean

    def _overlap(self, data: mujoco.MjData) -> tuple[float, float]:
        """Deepest and mean overlap of the character's geoms into others in ``data``'s
        contact list (0, 0 without any)."""
        n = data.ncon
        if n == 0:
            return 0.0, 0.0
        con = data.contact
        own = self._own_geom[np.asarray(con.geom[:n]).reshape(-1, 2)]
        dist = np.asarray(con.dist[:n])
        depth = -dist[(own[:, 0] != own[:, 1]) & (dist < 0)]
        return (float(depth.max()), float(depth.mean())) if depth.size else (0.0, 0.0)

    def pose_penetration(
        self, qpos: np.ndarray, mocap: tuple[np.ndarray, np.ndarray] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Like :meth:`penetration`, for kinematic poses ``(R, nq)`` of the character (scene
        joints at their defaults, props at ``mocap`` (every mocap body's position and
        quaternion) or their compiled placement): how deep a kinematic pose puts the body
        into the floor and props, without stepping physics. One collision pass per pose."""
        if self._scratch is None:
            self._scratch = mujoco.MjData(self.model)
        data, nq = self._scratch, qpos.shape[1]
        deepest, mean = np.zeros(len(qpos)), np.zeros(len(qpos))
        mujoco.mj_resetData(self.model, data)
        if mocap is not None:
            data.mocap_pos[:], data.mocap_quat[:] = mocap
        for i in range(len(qpos)):  # an evaluation metric, once per estimated frame
            data.qpos[:nq] = qpos[i]
            mujoco.mj_fwdPosition(self.model, data)
            deepest[i], mean[i] = self._overlap(data)
        return deepest, mean

    def each_env(self, fn: Callable[[mujoco.MjData], T]) -> list[T]:
        """``fn`` of every environment's full ``MjData`` (contacts included), in order: for
        evaluation metrics that need MuJoCo's per-simulation contact list, which is not
        batched. Each environment is copied into one scratch ``MjData``, so ``fn`` must not
        keep it."""
        if self._scratch is None:
            self._scratch = mujoco.MjData(self.model)
        out = []
        for i in range(self.num_envs):  # BatchedSim is where per-environment loops live
            self._copy_env(i, self._scratch)
            out.append(fn(self._scratch))
        return out

    def raw(self, field: str) -> np.ndarray:
        """The live ``(N, ...)`` MuJoCo array of ``field`` (tests and backends use this)."""
        return self.batch.bind(field)
