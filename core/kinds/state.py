"""What a reward term, sensor, observer or termination sees each control step.

Every tensor has the environment as its leading dimension ``N``. Plugins resolve names to
indices once (``bind(layout)``) and then only index tensors, so a step never matches strings
and never loops over environments in Python.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import torch

    from retarget.kinds.scene import Scene


@dataclass(frozen=True)
class Layout:
    """Names and index groups of one compiled character, shared by every environment.

    ``sites`` are the role sites every plugin may rely on (``head`` is the headset mount,
    ``left_hand``/``right_hand`` the controller mounts, ``root``); ``body_groups`` name sets of
    bodies (``feet``, ``upper_body`` for fall detection, ...). Arrays in :class:`SimState` are
    ordered as these tuples.
    """

    body_names: tuple[str, ...]
    body_ids: tuple[int, ...]  # MuJoCo body ids, in the order of the (N, B, ...) arrays
    joint_names: tuple[str, ...]
    actuator_names: tuple[str, ...]
    site_names: tuple[str, ...]  # role names, in the order of site_pos/site_quat
    site_ids: tuple[int, ...]  # MuJoCo site ids of those roles in the compiled model
    body_groups: Mapping[str, tuple[int, ...]]
    nq: int  # the character's generalized coordinates: qpos[:nq] (scene joints come after)
    nv: int  # the character's degrees of freedom: qvel[:nv]
    joint_weights: tuple[float, ...] = ()
    torque_limits: tuple[float, ...] = ()
    passive_joints: tuple[str, ...] = ()
    # per actuator: the qpos address of the joint it drives and that joint's range (rad), so
    # a plugin can turn joint angles into PD-target actions (retarget.sim.actuation)
    actuator_qpos: tuple[int, ...] = ()
    actuator_ranges: tuple[tuple[float, float], ...] = ()

    @property
    def nu(self) -> int:
        return len(self.actuator_names)

    @property
    def num_bodies(self) -> int:
        return len(self.body_names)

    def site(self, role: str) -> int:
        """Index of a role site in ``site_pos``/``site_quat``; raises with the known roles."""
        try:
            return self.site_names.index(role)
        except ValueError:
            raise KeyError(f"no site role '{role}'; known: {', '.join(self.site_names)}") from None

    def group(self, name: str) -> tuple[int, ...]:
        """Body indices of a named group; raises with the known groups."""
        try:
            return self.body_groups[name]
        except KeyError:
            known = ", ".join(sorted(self.body_groups))
            raise KeyError(f"no body group '{name}'; known: {known}") from None


def _select(obj: object, idx: torch.Tensor) -> object:
    """Rows ``idx`` of every tensor field of a frozen dataclass (other fields kept)."""
    import torch
    changes: dict[str, object] = {}
    for f in fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        if isinstance(value, torch.Tensor) and value.ndim > 0:
            changes[f.name] = value[idx]
        elif isinstance(value, Mapping):
            changes[f.name] = {
                k: v[idx] if isinstance(v, torch.Tensor) and v.ndim > 0 else v
                for k, v in value.items()
            }
    return replace(obj, **changes)  # type: ignore[type-var]


@dataclass(frozen=True)
class SimState:
    """Simulated character state gathered once per control step (world frame, Z up)."""

    qpos: torch.Tensor  # (N, nq), free root first: xyz + wxyz quaternion
    qvel: torch.Tensor  # (N, nv)
    body_pos: torch.Tensor  # (N, B, 3)
    body_quat: torch.Tensor  # (N, B, 4) wxyz
    body_linvel: torch.Tensor  # (N, B, 3)
    body_angvel: torch.Tensor  # (N, B, 3)
    site_pos: torch.Tensor  # (N, S, 3)
    site_quat: torch.Tensor  # (N, S, 4)
    contact_force: torch.Tensor  # (N, B) normal force magnitude on each body, newtons
    # (N, B) upward (+Z) component of the net contact force on each body, newtons: what
    # carries the body's weight (QuestEnvSim's contact rule thresholds it)
    contact_force_up: torch.Tensor
    pd_feedforward: torch.Tensor | None = None
    """``(N, nu)`` radians, on reference states only (None on the simulated body): what each
    PD target adds to its joint's reference angle so that the servo, on the reference, gives
    the joint the reference's inverse-dynamics torque (gravity, inertia, the load its contacts
    carry) and cancels its own damping; zero under torque actuation. A servo given only the
    reference angle sags by ``torque / kp`` and lags by its damping."""

    @property
    def num_envs(self) -> int:
        return int(self.qpos.shape[0])

    def select(self, idx: torch.Tensor) -> SimState:
        return _select(self, idx)  # type: ignore[return-value]


@dataclass(frozen=True)
class ReferenceBatch:
    """The reference each environment tracks at this step.

    ``pose`` is the kinematically retargeted character (same layout as :class:`SimState`),
    ``devices`` the synthesised device poses over the sensor time window
    ``(N, W, D, 7)`` (D devices: headset, left, right; position + wxyz quaternion), with
    ``window_offsets`` the frame offsets of the W entries (0 is now). ``contacts`` ``(N, 2)``
    are the human reference's foot-contact labels (left, right), from the clip, whatever the
    character's feet. What only some
    plugins read is gathered when one of them :meth:`~retarget.kinds.step.StepPlugin.needs`
    it: ``future`` and ``scene_contacts``.
    """

    pose: SimState
    devices: torch.Tensor  # (N, W, D, 7)
    window_offsets: tuple[int, ...]
    contacts: torch.Tensor  # (N, 2) bool: left, right foot of the human reference
    future: Mapping[int, SimState] = field(default_factory=dict)
    """The reference state ``k`` frames ahead, for each offset ``k`` some plugin asked for in
    ``needs().reference_offsets`` (clamped at the clip's last frame)."""
    rows: torch.Tensor | None = None
    """``(N,)`` long: the motion library row each environment's reference is at, for data a
    plugin precomputed per frame in :meth:`~retarget.kinds.step.StepPlugin.prepare`."""
    scene_contacts: torch.Tensor | None = None
    """``(N, G)`` bool when some plugin needs it: whether the kinematic reference touches the
    scene (floor included) with each body group, one column per group of
    ``Layout.body_groups`` in its order (computed once per library frame, not per step)."""
    devices_tracked: torch.Tensor | None = None
    """``(N, W, D)`` bool: whether each device was tracked at each entry of ``devices``
    (false: the runtime lost it and ``devices`` holds its last tracked pose, as a headset
    runtime reports and holds it); ``None`` means every device was tracked."""

    def tracked(self) -> torch.Tensor:
        """``devices_tracked``, or all true when the reference gives none."""
        import torch

        if self.devices_tracked is not None:
            return self.devices_tracked
        return torch.ones(self.devices.shape[:-1], dtype=torch.bool, device=self.devices.device)

    def select(self, idx: torch.Tensor) -> ReferenceBatch:
        return replace(
            self,
            pose=self.pose.select(idx),
            future={k: v.select(idx) for k, v in self.future.items()},
            devices=self.devices[idx],
            contacts=self.contacts[idx],
            scene_contacts=None if self.scene_contacts is None else self.scene_contacts[idx],
            rows=None if self.rows is None else self.rows[idx],
            devices_tracked=None if self.devices_tracked is None else self.devices_tracked[idx],
        )


@dataclass(frozen=True)
class StepContext:
    """Everything one control step exposes to plugins; frozen so no plugin can mutate it."""

    layout: Layout
    sim: SimState
    ref: ReferenceBatch
    action: torch.Tensor  # (N, nu) in [-1, 1]
    prev_action: torch.Tensor  # (N, nu)
    episode_step: torch.Tensor  # (N,) int64
    dt: float
    scene: Scene[Any]
    """The scene plugin, for observers' batched geometry queries: every environment has one
    (the floor alone, :class:`retarget.scene.ground.Ground`, when the recipe names none)."""
    terminated: torch.Tensor | None = None
    """``(N,)`` bool: environments whose episode failed this step (time-outs excluded). Set
    for rewards, which run after terminations; None for terminations and observations."""

    @property
    def num_envs(self) -> int:
        return self.sim.num_envs

    def select(self, idx: torch.Tensor) -> StepContext:
        """The same step restricted to environments ``idx`` (used to check batch invariance)."""
        return replace(
            self,
            scene=self.scene.select(idx),
            sim=self.sim.select(idx),
            ref=self.ref.select(idx),
            action=self.action[idx],
            prev_action=self.prev_action[idx],
            episode_step=self.episode_step[idx],
            terminated=None if self.terminated is None else self.terminated[idx],
        )
