"""``WarpSim``: the :class:`~retarget.sim.batched.BatchedSim` interface over MuJoCo Warp.

MuJoCo Warp (``mujoco-warp``, the ``warp`` extra) steps every world in one kernel launch per
pipeline stage, which is what makes thousands of worlds cheap on a GPU. Sensors, rewards and
observers do not change: after each control step the same state arrays are copied to the host
and gathered exactly as the C backend's are, so everything downstream sees the same float32
buffers. The copy is the price of keeping plugins engine-agnostic; on a GPU the physics of
``substeps`` steps is one captured CUDA graph.

Differences from the C engine that a user may see, all measured by
``benchmarks/warp_vs_c.py``: MuJoCo Warp computes in float32 (the C engine in float64), its
contact buffers are preallocated (``sim.warp_contacts``/``sim.warp_constraints``; an overflow
is counted in :attr:`WarpSim.overflows`), and it does not reset a world whose state went
non-finite by itself (this class detects that like the C backend and the env resets it).
Per-environment evaluation metrics (:meth:`each_env`, penetration) copy one world into a C
``MjData`` and run C collision on it.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from retarget.errors import RetargetError
from retarget.geometry import rotations
from retarget.sim.batched import BatchedSim

if TYPE_CHECKING:
    import torch

_PULLED = ("qpos", "qvel", "time", "xpos", "xquat", "cvel", "subtree_com", "site_xpos",
           "mocap_pos", "mocap_quat")  # fmt: skip
"""Arrays copied to the host after every step (plus ``site_xmat`` and ``cfrc_ext``)."""


def import_warp() -> tuple[Any, Any]:
    """``(warp, mujoco_warp)``, or a clear error saying how to install them."""
    try:
        import warp

        warp.config.quiet = True  # before MuJoCo Warp initialises it: no per-kernel lines
        import mujoco_warp
    except ImportError as exc:
        raise RetargetError(
            f"sim.backend 'warp' needs MuJoCo Warp, which is not installed ({exc})",
            field="sim.backend",
            hint="pip install 'retarget[warp]' (or set sim.backend: mujoco)",
        ) from None
    return warp, mujoco_warp


class WarpSim(BatchedSim):
    """N worlds of one model on MuJoCo Warp (a GPU when there is one, else the CPU)."""

    def _open(self) -> None:
        wp, mjw = import_warp()
        self._wp, self._mjw = wp, mjw
        self.device = wp.get_preferred_device()
        host = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, host)
        with wp.ScopedDevice(self.device):
            self.warp_model = mjw.put_model(self.model)
            self.data = mjw.put_data(
                self.model,
                host,
                nworld=self.num_envs,
                nconmax=self.settings.warp_contacts,
                njmax=self.settings.warp_constraints,
            )
        self._graph = None
        self.overflows = 0
        """Control steps in which the contacts of all worlds overflowed their buffers."""
        self._ctrl = np.zeros((self.num_envs, self.model.nu))
        self._push("time", np.ones(self.num_envs))  # see BatchedSim: time never restarts
        self._pull()

    # ------------------------------------------------------------------ host mirrors

    def _pull(self) -> None:
        """Copy the state every plugin reads to the host (the C backend's live views)."""
        d = self.data
        for field in _PULLED:
            setattr(self, f"_{field}", getattr(d, field).numpy())
        self._site_xquat = rotations.from_matrix(d.site_xmat.numpy())
        self._cfrc = d.cfrc_ext.numpy()

    def _push(self, field: str, value: np.ndarray) -> None:
        array = getattr(self.data, field)
        array.assign(np.ascontiguousarray(value, dtype=array.numpy().dtype))

    def _physics(self, nstep: int) -> None:
        wp, mjw = self._wp, self._mjw
        with wp.ScopedDevice(self.device):
            if not self.device.is_cuda:
                for _ in range(nstep):
                    mjw.step(self.warp_model, self.data)
                return
            if self._graph is None:  # kernels compiled by one eager step, then captured
                mjw.step(self.warp_model, self.data)
                with wp.ScopedCapture() as capture:
                    for _ in range(nstep):
                        mjw.step(self.warp_model, self.data)
                self._graph = capture.graph
            wp.capture_launch(self._graph)
            wp.synchronize()

    def set_root_wrench(self, wrench: np.ndarray | None) -> None:
        """As :meth:`BatchedSim.set_root_wrench`, written to the device's ``xfrc_applied``."""
        if wrench is None and not getattr(self, "_xfrc_set", False):
            return
        full = np.zeros((self.num_envs, self.model.nbody, 6))
        if wrench is not None:
            full[:, self._bodies[0]] = wrench
        self._push("xfrc_applied", full)
        self._xfrc_set = wrench is not None

    def _forward(self) -> None:
        with self._wp.ScopedDevice(self.device):
            self._mjw.forward(self.warp_model, self.data)

    # ------------------------------------------------------------------ stepping

    def step(self, action: torch.Tensor | np.ndarray) -> np.ndarray:
        """One control step of every world; a bool ``(N,)`` mask of worlds that went
        non-finite (their state is left as it is: the caller resets them)."""
        ctrl = action.numpy() if not isinstance(action, np.ndarray) else action
        self._ctrl[:] = ctrl
        self._push("ctrl", self._ctrl)
        t0 = time.perf_counter()
        self._physics(self.settings.substeps)
        if int(self.data.nacon.numpy()[0]) > self.data.naconmax:
            self.overflows += 1
        self._pull()
        t1 = time.perf_counter()
        # MuJoCo Warp never resets a world itself: only the state tells a blown-up one
        return self._finish_step(np.zeros(self.num_envs, dtype=bool), t0, t1)

    def reset(
        self,
        env_ids: np.ndarray,
        qpos: np.ndarray,
        qvel: np.ndarray | None = None,
        mocap: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """As :meth:`BatchedSim.reset`: the worlds ``env_ids`` back to the model defaults,
        then the given state; derived quantities are recomputed (for every world: one
        forward launch costs what one world's does)."""
        env_ids = np.asarray(env_ids, dtype=np.intp)
        if env_ids.size == 0:
            return
        wp = self._wp
        mask = np.zeros(self.num_envs, dtype=bool)
        mask[env_ids] = True
        keep_time = self.data.time.numpy()
        with wp.ScopedDevice(self.device):
            self._mjw.reset_data(self.warp_model, self.data, reset=wp.array(mask, dtype=bool))
        self._push("time", keep_time)
        full_q, full_v = self.data.qpos.numpy(), self.data.qvel.numpy()
        full_q[env_ids, : qpos.shape[-1]] = qpos
        if qvel is not None:
            full_v[env_ids, : qvel.shape[-1]] = qvel
        self._push("qpos", full_q)
        self._push("qvel", full_v)
        self._ctrl[env_ids] = 0.0
        self._push("ctrl", self._ctrl)
        if mocap is not None and len(mocap[0]):
            self.set_mocap(env_ids, *mocap, forward=False)
        self._forward()
        self._pull()
        self.gather()

    def set_mocap(
        self,
        env_ids: np.ndarray,
        ids: np.ndarray,
        pos: np.ndarray,
        quat: np.ndarray,
        *,
        forward: bool = True,
    ) -> None:
        env_ids = np.asarray(env_ids, dtype=np.intp)
        rows = np.ix_(env_ids, np.asarray(ids, dtype=np.intp))
        mp, mq = self.data.mocap_pos.numpy(), self.data.mocap_quat.numpy()
        mp[rows], mq[rows] = pos, quat
        self._push("mocap_pos", mp)
        self._push("mocap_quat", mq)
        if forward and env_ids.size:
            self._forward()
            self._pull()
            self.gather()

    # ------------------------------------------------------------------ checkpoints

    def state_dict(self) -> dict[str, np.ndarray]:
        return {k: getattr(self.data, k).numpy().copy() for k in self.STATE_FIELDS}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        for key in self.STATE_FIELDS:
            if key in state:
                self._push(key, state[key])
        self._ctrl[:] = self.data.ctrl.numpy()
        self._forward()
        self._pull()
        self.gather()

    # ------------------------------------------------------------------ per-environment

    def _copy_env(self, i: int, data: mujoco.MjData) -> None:
        """World ``i`` in a C ``MjData``: its state, then C's own forward pass (contacts
        included), for evaluation metrics that read one simulation's contact list."""
        data.qpos[:] = self._qpos[i]
        data.qvel[:] = self._qvel[i]
        data.ctrl[:] = self._ctrl[i]
        data.mocap_pos[:] = self._mocap_pos[i]
        data.mocap_quat[:] = self._mocap_quat[i]
        data.time = float(self._time[i])
        mujoco.mj_forward(self.model, data)

    def raw(self, field: str) -> np.ndarray:
        """A host copy of the ``(N, ...)`` MuJoCo Warp array ``field`` (read-only: writing to
        it does not change the simulation, unlike the C backend's live view)."""
        return getattr(self.data, field).numpy()
