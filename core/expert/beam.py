"""Beam-search tracking of a reference clip over PD-target actions (SAMCON-style sampling).

Why a beam and not a receding-horizon planner: a fall is decided a second before it shows,
so a planner that commits to its best guess every step (predictive sampling with an 8-step
horizon was tried first) falls within 1.5 s on walks. A beam keeps the ``beam`` best states
after every short segment, each extended by many sampled continuations, and the best path
is read back at the end: a doomed state is simply outrun by others.

Each sample's action at every control step is

    clip(reference angles ``lead`` frames ahead / scale + offset + gain x angle error, range)

in the env's own action space (``sim.actuation: pd``). The offset is Gaussian, scaled per
joint by its strength, and correlated over segments (``carry``): balance needs pushes that
last longer than one segment. All samples step together in one :class:`BatchedSim` of the
env's own model (MuJoCo's threaded ``Batch``), so the world poses every cost term needs come
back with the step and no per-sample loop runs in Python.

A sample is scored after a lookahead past its segment, so that a state about to fall scores
badly before it falls. The lookahead was two thirds of the search's simulation; only the
samples closest to the reference at their segment's end (``lookahead_share``, a quarter by
default) are stepped through it, in a second, smaller batch: the others are the least likely to
be kept, and on held-out clips the Dino's search costs a fifth less for the same errors
(``benchmarks/results/expert_lookahead_share_2026-12-07.md``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from retarget.errors import PluginError
from retarget.expert.config import CostWeights, ExpertConfig
from retarget.kinds.track import Track
from retarget.sim.actuation import describe_actuation
from retarget.sim.backend import make_sim
from retarget.sim.batched import BatchedSim
from retarget.sim.inverse_dynamics import reference_torques


@dataclass(frozen=True)
class _Mode:
    """How one try at a segment samples and scores: the plain settings, or the rescue's."""

    sigma: np.ndarray  # (nu,) offset noise per joint
    lookahead: int
    weights: CostWeights
    running: float


class BeamTracker:
    """Plans one clip of ``env``'s library at a time (``env`` needs ``sim.actuation: pd``)."""

    def __init__(self, env, config: ExpertConfig | None = None, threads: int = 1) -> None:
        self.env = env
        self.config = c = config or ExpertConfig()
        settings = env.sim.settings
        if settings.actuation != "pd":
            raise PluginError(
                "plans PD targets; this recipe has sim.actuation: torque",
                plugin="expert", hint="--set sim.actuation=pd (the teacher recipes have it)",
            )
        layout = env.layout
        if layout.nq < 7 or len(layout.actuator_qpos) != layout.nu:
            raise PluginError("needs a free root and actuators that say which joint they "
                              "drive (layout.actuator_qpos)", plugin="expert")
        if c.beam > c.samples:
            raise ValueError(f"beam {c.beam} is larger than samples {c.samples}")
        ranges = np.asarray(layout.actuator_ranges, dtype=np.float64).reshape(-1, 2)
        self._scale = np.maximum(np.abs(ranges).max(axis=1), 1e-6)
        self._lo = np.clip(ranges[:, 0] / self._scale, -1, 1)
        self._hi = np.clip(ranges[:, 1] / self._scale, -1, 1)
        self._aq = np.asarray(layout.actuator_qpos, dtype=np.intp)
        limits = np.asarray(layout.torque_limits or np.ones(layout.nu), dtype=np.float64)
        if limits.shape != (layout.nu,) or limits.max() <= 0:
            limits = np.ones(layout.nu)
        strength = (limits / limits.max()) ** c.strength_power
        self._modes = (
            _Mode(c.sigma * strength, c.lookahead, c.weights, c.running),
            _Mode(c.rescue.sigma * strength, c.rescue.lookahead,
                  c.weights.model_copy(update={"pose": c.rescue.pose}), c.rescue.running),
        )  # fmt: skip
        self.rescues = 0
        """Segments planned again by the rescue (all clips so far)."""
        plan = settings.model_copy(update={"threads": threads, "backend": "mujoco"})
        self.sim = make_sim(env.sim.model, layout, c.samples, plan)
        self._looked = max(c.beam, math.ceil(c.lookahead_share * c.samples))
        self.look_sim = self.sim
        if self._looked < c.samples:
            self.look_sim = make_sim(env.sim.model, layout, self._looked, plan)
        self._fields = self.sim.STATE_FIELDS
        model = self.sim.model
        self._dof = np.asarray(model.jnt_dofadr[model.actuator_trnid[: layout.nu, 0]], np.intp)
        servo = describe_actuation(model, "pd")
        self._kp = np.asarray(servo["kp"], dtype=np.float64)
        self._damping = np.asarray(servo["kd"]) / self._kp  # seconds
        self._joints = np.asarray(model.actuator_trnid[: layout.nu, 0], np.intp)
        self._inverse: tuple[int, np.ndarray] = (0, np.zeros((0, layout.nu)))
        if self._damping.shape != (layout.nu,):
            raise PluginError("every actuator must be a PD joint servo", plugin="expert")

    def _feedforward(self, row: int) -> np.ndarray:
        """``(nu,)``: what the nominal target gains so that a PD servo moving with the
        reference does not lag it: its damping torque ``kd x qdot`` cancelled by ``kp x
        (damping x qdot)`` more target, in action units; plus the reference's own
        inverse-dynamics offset where ``inverse_ff`` asks for it (:meth:`_prepare_inverse`;
        the current state's gravity torques on every joint were tried first: they made walks
        worse, the stance leg's torque comes through the contacts, not the tree)."""
        c = self.config
        ff = np.zeros(self.env.layout.nu)
        if c.velocity_ff:
            qd = self.env.reference.qvel64[row][self._dof]
            ff = c.velocity_ff * self._damping * qd / self._scale
        first, targets = self._inverse
        if 0 <= row - first < len(targets):
            ff = ff + targets[row - first]
        return ff

    def _prepare_inverse(self, start: int, length: int, placed_qpos: np.ndarray) -> None:
        """The target offsets (action units) of the clip's reference rows that carry their
        inverse-dynamics torques (``inverse_ff`` x torque / kp), the scene's joints held
        where the clip was placed; none when ``inverse_ff`` is 0."""
        self._inverse = (start, np.zeros((0, self.env.layout.nu)))
        if not self.config.inverse_ff:
            return
        ref, lay = self.env.reference, self.env.layout
        rows = np.arange(start, start + length)
        qpos = np.repeat(placed_qpos[None], length, axis=0)
        qpos[:, : lay.nq] = ref.qpos64[rows]
        qvel = np.zeros((length, self.sim.model.nv))
        qvel[:, : lay.nv] = ref.qvel64[rows]
        dt = self.env.sim.settings.control_dt
        torques = reference_torques(self.sim.model, qpos, qvel, dt, self._joints,
                                    support=self.config.inverse_support)  # fmt: skip
        self._inverse = (start, self.config.inverse_ff * torques / (self._kp * self._scale))

    # ------------------------------------------------------------------ helpers

    def _nominal(self, rows: np.ndarray) -> np.ndarray:
        q = self.env.reference.qpos64[rows][:, self._aq]
        return np.clip(q / self._scale, self._lo, self._hi)

    def _cost(self, row: int, w: CostWeights | None = None, sim: BatchedSim | None = None
              ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Every sample's (every row of ``sim``'s, default the samples') cost against
        reference row ``row`` and its mean world distance of the bodies (m)."""
        ref, lay = self.env.reference, self.env.layout
        w = w or self.config.weights
        sim = self.sim if sim is None else sim
        s = sim.state
        bp, rb = s.body_pos.numpy(), ref.arrays["body_pos"][row].numpy()
        body = np.linalg.norm(bp - rb, axis=-1).mean(-1)
        pose = np.linalg.norm((bp - bp[:, :1]) - (rb - rb[:1]), axis=-1).mean(-1)
        q = sim.raw("qpos")[:, : lay.nq]
        v = sim.raw("qvel")[:, : lay.nv]
        rq, rv = ref.qpos64[row], ref.qvel64[row]
        dot = np.minimum(np.abs(q[:, 3:7] @ rq[3:7]), 1.0)
        cost = (
            w.body * body
            + w.orientation * (1.0 - dot**2)
            + w.joints * np.square(q[:, 7:] - rq[7:]).mean(-1)
            + w.height * 10.0 * np.square(q[:, 2] - rq[2])
            + w.velocity * np.square(v - rv).mean(-1)
            + w.pose * pose
        )
        return np.where(np.isfinite(cost), cost, np.inf), body

    # ------------------------------------------------------------------ planning

    def track(
        self,
        clip: int,
        seconds: float | None = None,
        progress: Callable[[int], None] | None = None,
    ) -> Track:
        """Plan clip ``clip`` (library index) from its first frame for ``seconds`` (all of
        it when None); ``progress(frames)`` is called after every segment of every pass."""
        c, env = self.config, self.env
        cpu0 = time.process_time()
        rng = np.random.default_rng([c.seed, clip])
        lib = env.library
        start, length = int(lib.start[clip]), int(lib.length[clip])
        fps = 1.0 / env.sim.settings.control_dt
        if seconds is not None:
            length = max(2, min(length, round(seconds * fps) + 1))
        env.place(torch.tensor([clip]), torch.tensor([0]))
        placed = {k: v.copy() for k, v in env.sim.state_dict().items()}
        first = {
            "qpos": env.sim.raw("qpos")[0].copy(),
            "qvel": env.sim.raw("qvel")[0].copy(),
            "body": env.sim.state.body_pos[0].numpy().astype(np.float64),
        }
        self._prepare_inverse(start, length, first["qpos"])
        best: tuple[float, dict[str, np.ndarray], dict[str, np.ndarray], int] | None = None
        prior: np.ndarray | None = None
        for round_ in range(c.passes):
            noise = 1.0 if round_ == 0 else c.refine
            before = self.rescues
            total, path, demos = self._search(placed, start, length, rng, prior, noise, progress)
            if best is None or total < best[0]:
                best = (total, path, demos, self.rescues - before)
            prior = best[1]["off"]
        assert best is not None
        _, path, demos, rescued = best
        frames = start + np.arange(length)
        return Track(
            clip=lib.names[clip],
            fps=fps,
            actions=path["acts"].astype(np.float32),
            qpos=np.concatenate([first["qpos"][None], path["qpos"]]),
            qvel=np.concatenate([first["qvel"][None], path["qvel"]]),
            body_pos=np.concatenate([first["body"][None], path["body"]]).astype(np.float32),
            ref_body_pos=env.reference.arrays["body_pos"][frames].numpy(),
            ref_qpos0=env.reference.qpos64[start].copy(),
            cpu_seconds=time.process_time() - cpu0,
            demos=demos,
            rescued=rescued,
        )

    def _search(
        self,
        placed: dict[str, np.ndarray],
        start: int,
        length: int,
        rng: np.random.Generator,
        prior: np.ndarray | None,
        noise_scale: float,
        progress: Callable[[int], None] | None,
    ) -> tuple[float, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """One beam-search pass from the placed state. ``prior`` (segments, nu): offsets of a
        previous pass's best path that this pass samples around. Returns the best path's
        summed cost, the path (``acts``, ``qpos``, ``qvel``, ``body``, ``off`` per segment)
        and the beam members kept as demonstrations."""
        c, env = self.config, self.env
        nu = env.layout.nu
        beam = placed
        dev = np.zeros((1, nu))
        last = np.zeros((1, nu))
        spent = np.zeros(1)
        segments: list[dict[str, np.ndarray]] = []
        demos: dict[str, list[np.ndarray]] = {}
        last_row = start + length - 1
        f = 0
        while f < length - 1:
            S = min(c.segment, length - 1 - f)
            rows = start + f + 1 + np.arange(S)
            base = prior[len(segments)][None] if prior is not None else 0.0
            args = (beam, dev, rows, last_row, base, noise_scale, rng)
            seg = self._segment(*args, self._modes[0])
            if c.rescue.threshold and seg["error"][seg["order"][0]] > c.rescue.threshold:
                seg = self._segment(*args, self._modes[1])
                self.rescues += 1
            order, parent, cost = seg["order"], seg["parent"], seg["cost"]
            if c.keep:
                kept = order[: c.keep]
                for k, v in beam.items():
                    demos.setdefault(f"state_{k}", []).append(v[parent[kept]])
                demos.setdefault("frame", []).append(np.full(len(kept), f))
                demos.setdefault("prev_action", []).append(last[parent[kept]])
                padded = np.zeros((len(kept), c.segment, nu))
                padded[:, :S] = seg["acts"][kept]
                demos.setdefault("actions", []).append(padded)
                demos.setdefault("steps", []).append(np.full(len(kept), S))
            segments.append({k: seg[k][order] for k in ("parent", "acts", "qpos", "qvel",
                                                         "body", "off")})  # fmt: skip
            beam = {k: v[order].copy() for k, v in seg["end_state"].items()}
            spent = spent[parent[order]] + np.where(np.isfinite(cost[order]), cost[order], 1e9)
            dev, last = seg["dev"][order], seg["acts"][order, -1]
            f += S
            if progress is not None:
                progress(S)
        # read the best path back, last segment first
        idx = 0
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ("acts", "qpos", "qvel", "body")}
        offsets = []
        for seg in reversed(segments):
            for k in parts:
                parts[k].append(seg[k][idx])
            offsets.append(seg["off"][idx])
            idx = int(seg["parent"][idx])
        path = {k: np.concatenate(v[::-1], axis=0) for k, v in parts.items()}
        path["off"] = np.stack(offsets[::-1])  # (segments, nu)
        return float(spent[0]), path, {k: np.concatenate(v) for k, v in demos.items()}

    def _segment(
        self,
        beam: dict[str, np.ndarray],
        dev: np.ndarray,
        rows: np.ndarray,
        last_row: int,
        base: np.ndarray | float,
        noise_scale: float,
        rng: np.random.Generator,
        mode: _Mode,
    ) -> dict:
        """One try at a segment: ``samples`` continuations of the beam's states through
        reference ``rows``, each continued ``mode.lookahead`` steps and scored. Returns every
        sample's ``parent``, ``dev``, ``off``, ``acts``/``qpos``/``qvel``/``body`` per step,
        ``end_state``, ``cost``, ``error`` (mean body distance after the lookahead, m) and
        ``order`` (the ``beam`` best, lowest cost first)."""
        c, env = self.config, self.env
        nu, K, S = env.layout.nu, c.samples, len(rows)
        ref_q = env.reference.qpos64
        nominal = self._nominal(np.minimum(rows + c.lead, last_row))
        B = len(dev)
        parent = rng.integers(0, B, K)
        parent[: min(B, K)] = np.arange(min(B, K))
        noise = rng.normal(size=(K, nu)) * mode.sigma * noise_scale
        noise[rng.random(K) < c.quiet] = 0.0
        new_dev = c.carry * dev[parent] + noise
        off = base + new_dev
        self.sim.load_state_dict({k: v[parent] for k, v in beam.items()})
        acts = np.zeros((K, S, nu))
        qpos = np.zeros((K, S, self.sim.raw("qpos").shape[1]))
        qvel = np.zeros((K, S, self.sim.raw("qvel").shape[1]))
        body = np.zeros((K, S, *self.sim.state.body_pos.shape[1:]))
        bad = np.zeros(K, dtype=bool)
        running = np.zeros(K)
        for j in range(S):
            angles = self.sim.raw("qpos")[:, self._aq]
            fb = c.gain * (ref_q[rows[j]][self._aq][None] - angles) / self._scale
            ff = self._feedforward(int(rows[j]))[None]
            acts[:, j] = np.clip(nominal[j][None] + off + fb + ff, self._lo, self._hi)
            bad |= self.sim.step(acts[:, j])
            qpos[:, j], qvel[:, j] = self.sim.raw("qpos"), self.sim.raw("qvel")
            body[:, j] = self.sim.state.body_pos.numpy()
            if mode.running:
                running += self._cost(int(rows[j]), mode.weights)[0] / S
        end_state = self.sim.state_dict()
        effort = mode.weights.effort * np.square(off).mean(-1)
        look = np.arange(K)  # the samples continued through the lookahead
        sim = self.sim
        if mode.lookahead and rows[-1] < last_row and self._looked < K:
            early = self._cost(int(rows[-1]), mode.weights)[0] + mode.running * running + effort
            early[bad] = np.inf
            look = np.argsort(early, kind="stable")[: self._looked]
            sim = self.look_sim
            sim.load_state_dict({k: v[look] for k, v in end_state.items()})
        look_bad = bad[look]
        scored = rows[-1].item()
        for _ in range(mode.lookahead):
            row = min(scored + 1, last_row)
            if row == scored:
                break
            angles = sim.raw("qpos")[:, self._aq]
            fb = c.gain * (ref_q[row][self._aq][None] - angles) / self._scale
            target = self._nominal(np.array([min(row + c.lead, last_row)]))[0]
            ff = self._feedforward(row)[None]
            look_bad |= sim.step(np.clip(target[None] + off[look] + fb + ff, self._lo, self._hi))
            scored = row
        end_cost, end_error = self._cost(scored, mode.weights, sim)
        cost, error = np.full(K, np.inf), np.full(K, np.inf)
        cost[look] = end_cost + mode.running * running[look] + effort[look]
        error[look] = end_error
        bad[look] = look_bad
        cost[bad] = np.inf
        return {"parent": parent, "dev": new_dev, "off": off, "acts": acts, "qpos": qpos,
                "qvel": qvel, "body": body, "end_state": end_state, "cost": cost,
                "error": np.where(bad, np.inf, error),
                "order": np.argsort(cost, kind="stable")[: c.beam]}  # fmt: skip
