"""Physics settings: the recipe's ``sim`` section and what the simulator runs with, one model.

The default 36 Hz control (the paper's rate) with 10 substeps gives a 2.78 ms physics step:
under random torques the built-in human and Jesse needed resets at 1/216 s but none at
1/360 s, while Dino and Oppy were stable at both.
"""

from __future__ import annotations

from typing import Literal, get_args

from pydantic import BaseModel, ConfigDict, Field

Actuation = Literal["torque", "pd"]
ACTUATIONS: tuple[str, ...] = get_args(Actuation)
Backend = Literal["mujoco", "warp"]


class SimSettings(BaseModel):
    """Physics timing: ``substeps`` steps of ``1/(control_hz*substeps)`` s per control step."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    control_hz: float = Field(
        36.0, gt=0, le=1000, description="policy rate (the paper uses 36 Hz)"
    )
    substeps: int = Field(10, ge=1, le=1000, description="physics steps per control step")
    threads: int = Field(0, ge=0, le=1024, description="physics threads; 0 uses every core")
    actuation: Actuation = Field(
        "torque",
        description="torque: actions scale each joint's torque limit (the paper); pd: actions "
        "are joint-angle targets of torque-limited PD servos (retarget.sim.actuation)",
    )
    pd_saturation: float = Field(
        0.5, gt=0, le=10,
        description="pd: angle error (rad) at which a servo reaches its torque limit",
    )
    pd_damping: float = Field(0.1, ge=0, le=10, description="pd: kd = pd_damping * kp (seconds)")
    backend: Backend = Field(
        "mujoco",
        description="mujoco: MuJoCo's C engine on a CPU thread pool; warp: MuJoCo Warp "
        "(`pip install 'retarget[warp]'`), for a GPU (runs, slowly, on a CPU too)",
    )
    warp_contacts: int | None = Field(
        None, ge=1, le=100_000,
        description="warp: contacts allocated per world (default: MuJoCo Warp's estimate)",
    )
    warp_constraints: int | None = Field(
        None, ge=1, le=100_000,
        description="warp: constraint rows allocated per world (default: MuJoCo Warp's estimate)",
    )

    @property
    def timestep(self) -> float:
        return 1.0 / (self.control_hz * self.substeps)

    @property
    def control_dt(self) -> float:
        return 1.0 / self.control_hz


ACTION_PHYSICS: tuple[str, ...] = ("control_hz", "substeps", "actuation", "pd_saturation",
                                   "pd_damping")  # fmt: skip
"""The ``sim`` settings an action's meaning depends on: a policy's (or an expert's) actions
replayed or imitated under other values of these do something else, so a student must match
its teacher's or expert's on every one."""
