"""Moving and differencing MuJoCo positions in velocity space, for many rows at once.

``mujoco.mj_integratePos`` and ``mj_differentiatePos`` do this for one ``MjData`` row at a
time; a planner that perturbs every state of a trajectory along every degree of freedom
(finite-difference derivatives) needs it for thousands of rows per call, so this does the same
arithmetic with numpy over rows: hinge and slide joints add, free and ball joints rotate their
quaternion by a rotation vector in the joint's local frame (MuJoCo's convention for their
angular velocity).
"""

from __future__ import annotations

import mujoco
import numpy as np

from retarget.geometry import rotations


class Tangent:
    """``integrate`` and ``difference`` of positions ``(N, nq)`` of one model."""

    def __init__(self, model: mujoco.MjModel) -> None:
        self.nq, self.nv = model.nq, model.nv
        types = np.asarray(model.jnt_type)
        qadr = np.asarray(model.jnt_qposadr)
        vadr = np.asarray(model.jnt_dofadr)
        free, ball = mujoco.mjtJoint.mjJNT_FREE, mujoco.mjtJoint.mjJNT_BALL
        scalar = (types != free) & (types != ball)
        self._q1 = qadr[scalar]  # hinge and slide: one coordinate, one dof
        self._v1 = vadr[scalar]
        self._free = [(int(q), int(v)) for q, v in zip(qadr[types == free], vadr[types == free],
                                                       strict=True)]  # fmt: skip
        self._ball = [(int(q), int(v)) for q, v in zip(qadr[types == ball], vadr[types == ball],
                                                       strict=True)]  # fmt: skip

    def _rotations(self) -> list[tuple[int, int]]:
        """(quaternion address, angular-velocity address) of every rotating joint."""
        return [(q + 3, v + 3) for q, v in self._free] + self._ball

    def integrate(self, qpos: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``qpos ⊕ dq``: positions ``(N, nq)`` moved by velocity-space steps ``(N, nv)``."""
        out = np.array(qpos, dtype=np.float64, copy=True)
        out[:, self._q1] += dq[:, self._v1]
        for q, v in self._free:
            out[:, q : q + 3] += dq[:, v : v + 3]
        for q, v in self._rotations():
            turn = rotations.from_rotation_vector(dq[:, v : v + 3])
            quat = rotations.mul(out[:, q : q + 4], turn)
            out[:, q : q + 4] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
        return out

    def difference(self, qpos: np.ndarray, base: np.ndarray) -> np.ndarray:
        """``qpos ⊖ base``: the velocity-space step ``(N, nv)`` that takes ``base`` to
        ``qpos`` (``base`` may be one row, broadcast over ``qpos``'s)."""
        qpos = np.asarray(qpos, dtype=np.float64)
        base = np.broadcast_to(np.asarray(base, dtype=np.float64), qpos.shape)
        out = np.zeros((len(qpos), self.nv))
        out[:, self._v1] = qpos[:, self._q1] - base[:, self._q1]
        for q, v in self._free:
            out[:, v : v + 3] = qpos[:, q : q + 3] - base[:, q : q + 3]
        for q, v in self._rotations():
            step = rotations.mul(rotations.conj(base[:, q : q + 4]), qpos[:, q : q + 4])
            out[:, v : v + 3] = rotations.to_rotation_vector(step)
        return out
