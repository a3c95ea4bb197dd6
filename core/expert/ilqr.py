"""iLQR refinement of a tracked path: derivatives where the beam search only samples.

The beam search (:mod:`retarget.expert.beam`) finds a path that stays up, but its actions are
sampled offsets: a few centimetres of tracking error per body are left that no sample happened
to remove. Iterative LQR takes that path as its nominal trajectory and improves it with the
dynamics' derivatives: a Gauss-Newton model of the tracking cost, a Riccati backward pass, and
a forward pass with the feedback gains that keeps the rollout near the nominal path while it
moves. A step is only kept when the real simulation's cost falls, so the refined path is never
worse than the one it started from, and it is still a rollout of the env's own physics.

Between linearisations a kept round may be a chord step (``relinearise``): the derivatives
are kept and only the new path's residuals, which the line search's rollout gives for free,
enter the next backward pass; six rounds with every other one a chord cost what four full
rounds did and end closer (``benchmarks/results/expert_student_2026-12-05.md``).

It works in windows, as model-predictive control does: 18 control steps (half a second)
optimised from the refined path's state at the window's start, 6 of them kept, the rest of
the path re-rolled from there. A linear model of a whole clip does not hold: through a few
seconds of contacts a small change early moves everything after it, so the whole-path model
promised several times the decrease a step delivered and refined a training-style walk from 43 to
41 mm; windows of half a second brought it to 20 mm (``benchmarks/results/expert_ilqr_*.md``).

Derivatives are finite differences of one whole control step (``sim.substeps`` MuJoCo steps
with the env's PD servos) taken as one batch: every state of the path copied ``1 + 2 nv + nu``
times, each copy nudged along one state or action coordinate, all stepped together on MuJoCo's
thread pool. ``mujoco.mjd_transitionFD`` differentiates a single MuJoCo step of a single
``MjData``: chaining it over the substeps costs the same steps serially, and the cost's
derivatives (body positions) would need separate Jacobians; the batch gives both at once.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import torch

from retarget.expert.config import IlqrConfig
from retarget.kinds.track import Track
from retarget.sim.backend import make_sim
from retarget.sim.tangent import Tangent

MAX_DAMPING = 1e6
"""Damping past which a round's step is too small to matter: the refinement stops."""


def _worst_frame(body: np.ndarray, ref_body: np.ndarray) -> float:
    """The largest per-frame mean distance (m) of the bodies from the reference's."""
    return float(np.linalg.norm(body - ref_body, axis=-1).mean(-1).max())


class IlqrRefiner:
    """Refines paths of ``env``'s clips (``env`` as the planner that found them used it)."""

    def __init__(self, env, config: IlqrConfig | None = None, threads: int = 1) -> None:
        self.env = env
        self.config = c = config or IlqrConfig()
        layout = env.layout
        model = env.sim.model
        self.nv, self.nu = model.nv, layout.nu
        self.rows_per_step = 1 + 2 * self.nv + self.nu
        plan = env.sim.settings.model_copy(update={"threads": threads, "backend": "mujoco"})
        self.grad_sim = make_sim(model, layout, c.chunk * self.rows_per_step, plan)
        self.line_sim = make_sim(model, layout, len(c.alphas) * len(c.feedback), plan)
        self.tangent = Tangent(self.grad_sim.model)
        self._bodies = np.asarray(layout.body_ids, dtype=np.intp)
        self._nq_char, self._nv_char = layout.nq, layout.nv
        ranges = np.asarray(layout.actuator_ranges, dtype=np.float64).reshape(-1, 2)
        scale = np.maximum(np.abs(ranges).max(axis=1), 1e-6)
        self._lo = np.clip(ranges[:, 0] / scale, -1, 1)
        self._hi = np.clip(ranges[:, 1] / scale, -1, 1)
        self.history: list[dict[str, float]] = []
        """Per round of the last :meth:`refine`: cost before and after, step size, damping."""

    # ------------------------------------------------------------------ cost

    def _residual(self, sim, rows: np.ndarray, t: np.ndarray) -> np.ndarray:
        """``(N, p)``: the weighted errors of ``sim``'s ``rows`` against reference rows ``t``
        (one per row): half their squared norm is the frame's tracking cost."""
        w, ref = self.config.weights, self.env.reference
        xpos = sim.raw("xpos")[rows][:, self._bodies]
        qpos = sim.raw("qpos")[rows, : self._nq_char]
        qvel = sim.raw("qvel")[rows, : self._nv_char]
        rb = ref.arrays["body_pos"][t].numpy().astype(np.float64)
        nb = len(self._bodies)
        err = xpos - rb
        pose = (xpos - xpos[:, :1]) - (rb - rb[:, :1])
        joints = qpos[:, 7:] - ref.qpos64[t][:, 7:]
        vel = qvel - ref.qvel64[t]
        return np.concatenate((
            np.sqrt(2 * w.body / nb) * err.reshape(len(rows), -1),
            np.sqrt(2 * w.pose / nb) * pose.reshape(len(rows), -1),
            np.sqrt(2 * w.joints / max(joints.shape[1], 1)) * joints,
            np.sqrt(2 * w.velocity / max(vel.shape[1], 1)) * vel,
        ), axis=1)  # fmt: skip

    def _effort(self, du: np.ndarray) -> np.ndarray:
        return self.config.weights.effort / self.nu * np.square(du).sum(-1)

    # ------------------------------------------------------------------ rollouts

    def _forward(
        self,
        placed: dict[str, np.ndarray],
        nominal: dict[str, np.ndarray],
        k: np.ndarray,
        K: np.ndarray | None,
        alphas: np.ndarray,
        rows: np.ndarray,
        start_actions: np.ndarray,
        shares: np.ndarray | None = None,
    ) -> dict[str, np.ndarray]:
        """Roll ``u = nominal u + alpha k + share K (x - nominal x)`` out for every (alpha,
        share) row at once; returns per row its cost, states, actions and body positions."""
        sim = self.line_sim
        A, steps = len(alphas), len(rows) - 1
        live = np.arange(A)
        sim.load_state_dict({f: np.repeat(v, sim.num_envs, axis=0) for f, v in placed.items()})
        states = {f: np.zeros((steps + 1, A, *v.shape[1:])) for f, v in placed.items()}
        for f, v in placed.items():
            states[f][0] = v[0]
        acts = np.zeros((steps, A, self.nu))
        cost = np.zeros(A)
        bad = np.zeros(A, dtype=bool)
        body = np.zeros((steps + 1, A, len(self._bodies), 3))
        body[0] = sim.raw("xpos")[:A][:, self._bodies]
        residuals: list[np.ndarray] = []
        for t in range(steps):
            u = nominal["acts"][t] + alphas[:, None] * k[t]
            if K is not None:
                q, v = sim.raw("qpos")[live], sim.raw("qvel")[live]
                dx = np.concatenate((self.tangent.difference(q, nominal["qpos"][t]),
                                     v - nominal["qvel"][t]), axis=1)  # fmt: skip
                u = u + (shares[:, None] if shares is not None else 1.0) * (dx @ K[t].T)
            u = np.clip(u, self._lo, self._hi)
            acts[t] = u
            ctrl = np.zeros((sim.num_envs, self.nu))
            ctrl[:A] = u
            bad |= sim.step(ctrl)[:A]
            r = self._residual(sim, live, np.full(A, rows[t + 1]))
            residuals.append(r)
            cost += 0.5 * np.square(r).sum(-1) + self._effort(u - start_actions[t])
            for f in states:
                states[f][t + 1] = sim.raw(f)[:A]
            body[t + 1] = sim.raw("xpos")[:A][:, self._bodies]
        cost[bad | ~np.isfinite(cost)] = np.inf
        res = np.stack(residuals) if residuals else np.zeros((0, A, 0))
        return {"cost": cost, "acts": acts, "body": body, "residual": res, **states}

    # ------------------------------------------------------------------ derivatives

    def _linearise(
        self, states: dict[str, np.ndarray], acts: np.ndarray, rows: np.ndarray
    ) -> tuple[np.ndarray, ...]:
        """Per step t: ``A`` (n, n), ``B`` (n, m), the residual ``r`` of frame t+1 and its
        Jacobians ``Rx`` (p, n), ``Ru`` (p, m), by one-sided finite differences."""
        c, sim, nv, nu = self.config, self.grad_sim, self.nv, self.nu
        R, steps = self.rows_per_step, len(acts)
        n = 2 * nv
        out_A = np.zeros((steps, n, n))
        out_B = np.zeros((steps, n, nu))
        out_r, out_Rx, out_Ru = [], [], []
        eye_v, eye_u = np.eye(nv) * c.eps, np.eye(nu) * c.eps
        for s0 in range(0, steps, c.chunk):
            ts = np.arange(s0, min(s0 + c.chunk, steps))
            pick = np.concatenate((ts, np.full(c.chunk - len(ts), ts[-1])))  # pad the batch
            batch = {f: np.repeat(states[f][pick], R, axis=0) for f in states}
            qpos = batch["qpos"].reshape(c.chunk, R, -1)
            qpos[:, 1 : 1 + nv] = self.tangent.integrate(
                qpos[:, 1 : 1 + nv].reshape(-1, qpos.shape[-1]), np.tile(eye_v, (c.chunk, 1))
            ).reshape(c.chunk, nv, -1)
            qvel = batch["qvel"].reshape(c.chunk, R, -1)
            qvel[:, 1 + nv : 1 + n] += eye_v
            batch["qpos"], batch["qvel"] = qpos.reshape(len(pick) * R, -1), qvel.reshape(
                len(pick) * R, -1)
            ctrl = np.repeat(acts[pick], R, axis=0).reshape(c.chunk, R, nu)
            ctrl[:, 1 + n :] += eye_u
            sim.load_state_dict(batch)
            sim.step(ctrl.reshape(-1, nu))
            everyone = np.arange(len(pick) * R)
            q2 = sim.raw("qpos").reshape(c.chunk, R, -1)
            v2 = sim.raw("qvel").reshape(c.chunk, R, -1)
            r = self._residual(sim, everyone, np.repeat(rows[pick + 1], R)).reshape(c.chunk, R, -1)
            for j, t in enumerate(ts):
                dq = self.tangent.difference(q2[j, 1:], q2[j, 0])
                dx = np.concatenate((dq, v2[j, 1:] - v2[j, 0]), axis=1) / c.eps  # (R-1, n)
                out_A[t] = dx[:n].T
                out_B[t] = dx[n:].T
                dr = (r[j, 1:] - r[j, 0]) / c.eps
                out_r.append(r[j, 0])
                out_Rx.append(dr[:n].T)
                out_Ru.append(dr[n:].T)
        return out_A, out_B, np.stack(out_r), np.stack(out_Rx), np.stack(out_Ru)

    def _backward(
        self, lin: tuple[np.ndarray, ...], du: np.ndarray, mu: float
    ) -> tuple[np.ndarray, np.ndarray, float] | None:
        """Riccati recursion of the Gauss-Newton model; None when an action Hessian is not
        positive definite at damping ``mu``. Returns gains ``k``, ``K`` and the model's
        predicted decrease for a full step."""
        A, B, r, Rx, Ru = lin
        steps, n, m = B.shape
        we = self.config.weights.effort * 2.0 / self.nu
        Vx, Vxx = np.zeros(n), np.zeros((n, n))
        k, K = np.zeros((steps, m)), np.zeros((steps, m, n))
        predicted = 0.0
        for t in range(steps - 1, -1, -1):
            Qx = Rx[t].T @ r[t] + A[t].T @ Vx
            Qu = Ru[t].T @ r[t] + we * du[t] + B[t].T @ Vx
            VA, VB = Vxx @ A[t], Vxx @ B[t]
            Qxx = Rx[t].T @ Rx[t] + A[t].T @ VA
            Quu = Ru[t].T @ Ru[t] + we * np.eye(m) + B[t].T @ VB
            Qux = Ru[t].T @ Rx[t] + B[t].T @ VA
            try:
                chol = np.linalg.cholesky(Quu + mu * np.eye(m))
            except np.linalg.LinAlgError:
                return None
            solve = np.linalg.solve(chol.T, np.linalg.solve(chol, np.column_stack((Qu, Qux))))
            k[t], K[t] = -solve[:, 0], -solve[:, 1:]
            Vx = Qx + K[t].T @ Quu @ k[t] + K[t].T @ Qu + Qux.T @ k[t]
            Vxx = Qxx + K[t].T @ Quu @ K[t] + K[t].T @ Qux + Qux.T @ K[t]
            Vxx = 0.5 * (Vxx + Vxx.T)
            predicted += float(k[t] @ Qu + 0.5 * k[t] @ Quu @ k[t])
        return k, K, predicted

    # ------------------------------------------------------------------ the loop

    def _state(self, path: dict[str, np.ndarray], t: int) -> dict[str, np.ndarray]:
        """The simulator state of frame ``t`` of ``path``, as a one-row state dict."""
        return {f: path[f][t][None] for f in self.grad_sim.STATE_FIELDS}

    def _replay(
        self, state: dict[str, np.ndarray], acts: np.ndarray, rows: np.ndarray,
        start_actions: np.ndarray,
    ) -> tuple[dict[str, np.ndarray], float]:
        """``acts`` stepped from ``state`` through reference ``rows``: the path and its cost."""
        run = self._forward(state, {"acts": acts}, np.zeros_like(acts), None, np.zeros(1), rows,
                            start_actions)  # fmt: skip
        path = {f: v[:, 0] for f, v in run.items() if f not in ("cost", "residual")}
        return path, float(run["cost"][0])

    def _optimise(
        self,
        path: dict[str, np.ndarray],
        cost: float,
        rows: np.ndarray,
        start_actions: np.ndarray,
        progress: Callable[[int], None] | None,
    ) -> tuple[dict[str, np.ndarray], float]:
        """iLQR rounds over ``path`` (frames ``rows``) from its first state, which stays."""
        c = self.config
        placed = self._state(path, 0)
        mu = c.regularization
        grid = np.array([(a, f) for f in c.feedback for a in c.alphas], dtype=np.float64)
        alphas, shares = grid[:, 0], grid[:, 1]
        lin = None
        kept = 0
        for _ in range(c.iterations):
            if not np.isfinite(cost) or mu > MAX_DAMPING:
                break
            if lin is None:  # the path moved (a failed round keeps its derivatives)
                states = {f: path[f] for f in self.grad_sim.STATE_FIELDS}
                lin = self._linearise(states, path["acts"], rows)
            found = None
            while found is None and mu <= MAX_DAMPING:
                found = self._backward(lin, path["acts"] - start_actions, mu)
                if found is None:
                    mu *= 10.0
            if found is None:
                break
            k, K, predicted = found
            nominal = {"acts": path["acts"], "qpos": path["qpos"], "qvel": path["qvel"]}
            trial = self._forward(placed, nominal, k, K, alphas, rows, start_actions, shares)
            best = int(np.argmin(trial["cost"]))
            new = float(trial["cost"][best])
            self.history.append({"cost": cost, "trial": new, "alpha": float(alphas[best]),
                                 "feedback": float(shares[best]), "mu": mu,
                                 "predicted": predicted})  # fmt: skip
            if new < cost:
                path = {f: v[:, best] for f, v in trial.items() if f not in ("cost", "residual")}
                cost = new
                mu = max(mu / 3.0, 1e-6)
                kept += 1
                if kept % c.relinearise:  # a chord step: the new path's residuals only
                    lin = (*lin[:2], trial["residual"][:, best], *lin[3:])
                else:
                    lin = None
            else:
                mu *= 10.0
            if progress is not None:
                progress(0)
        return path, cost

    def _given(self, clip: int, track: Track
               ) -> tuple[np.ndarray, dict, np.ndarray, dict, float]:  # fmt: skip
        """``track``'s actions stepped from clip ``clip``'s placed first frame: the reference
        rows, the placed state, the actions as given (float64), the path (every state, body
        positions and the actions as applied) and its cost."""
        rows = int(self.env.library.start[clip]) + np.arange(track.frames)
        self.env.place(torch.tensor([clip]), torch.tensor([0]))
        placed = {f: v[:1].copy() for f, v in self.env.sim.state_dict().items()}
        acts = track.actions.astype(np.float64)
        path, cost = self._replay(placed, acts, rows, acts)
        return rows, placed, acts, path, cost

    def gains(self, clip: int, track: Track, damping: float = 1.0) -> np.ndarray:
        """``(T-1, nu, 2 nv)``: per step of ``track``'s path, the feedback gains of a
        ``window``-step LQR problem of the tracking cost around the path: ``u = u_t + K_t
        (x - x_t)`` (``x`` the tangent-space state: position difference, then velocity) is
        the action that brings a state near the path's back toward the reference.

        They would let a student's own states be relabelled for the cost of one linearisation
        of the path instead of planning again at each state. Their basin is what decides
        whether that holds, and ``benchmarks/expert_basin.py`` measures it (on refined walks,
        turns and runs: joint-velocity pushes of 1e-4 mostly die out with them where three in
        four open-loop replays fall; at 1e-3 most fall either way). Blocks of
        ``commit`` steps take the gains of the window starting at their first step, as the
        refinement commits its windows; a whole-path window (``window`` 0) takes one pass;
        ``damping`` is added to the action Hessian (larger: gentler gains)."""
        c = self.config
        rows, _, acts, path, _ = self._given(clip, track)
        states = {f: path[f] for f in self.grad_sim.STATE_FIELDS}
        lin = self._linearise(states, acts, rows)
        steps = len(acts)
        out = np.zeros((steps, self.nu, 2 * self.nv), dtype=np.float32)
        window, commit = (c.window, c.commit) if c.window else (steps, steps)
        for w0 in range(0, steps, commit):
            w1 = min(w0 + window, steps)
            mu = damping
            found = None
            while found is None and mu <= MAX_DAMPING:
                found = self._backward(tuple(x[w0:w1] for x in lin), np.zeros((w1 - w0, self.nu)),
                                       mu)  # fmt: skip
                mu = max(mu, 1e-6) * 10.0
            if found is not None:
                keep = min(commit, w1 - w0)
                out[w0 : w0 + keep] = found[1][:keep]
        return out

    def refine(
        self, clip: int, track: Track, progress: Callable[[int], None] | None = None
    ) -> Track:
        """``track`` (a path of clip ``clip`` from its first frame) with lower tracking cost;
        the same path when no round lowers it."""
        c = self.config
        cpu0 = time.process_time()
        rows, placed, start_actions, given, cost = self._given(clip, track)
        self.history = []
        if not c.window:
            path, _ = self._optimise(given, cost, rows, start_actions, progress)
        else:
            path = given
            for w0 in range(0, len(start_actions), c.commit):
                w1 = min(w0 + c.window, len(start_actions))
                window = {f: v[w0 : w1 + 1] for f, v in path.items() if f != "acts"}
                window["acts"] = path["acts"][w0:w1]
                _, own = self._replay(self._state(window, 0), window["acts"], rows[w0 : w1 + 1],
                                      start_actions[w0:w1])  # fmt: skip
                window, _ = self._optimise(window, own, rows[w0 : w1 + 1],
                                           start_actions[w0:w1], progress)  # fmt: skip
                rest, _ = self._replay(self._state(window, -1), path["acts"][w1:],
                                       rows[w1:], start_actions[w1:])  # fmt: skip
                acts = np.concatenate((path["acts"][:w0], window["acts"], rest["acts"]))
                path = {f: np.concatenate((path[f][:w0], window[f], rest[f][1:]))
                        for f in path if f != "acts"}  # fmt: skip
                path["acts"] = acts
            _, total = self._replay(placed, path["acts"], rows, start_actions)
            if not total < cost:  # the windows' splices may lose what each window won
                path = given
        ref_body = track.ref_body_pos.astype(np.float64)
        if _worst_frame(given["body"], ref_body) <= c.threshold < _worst_frame(path["body"],
                                                                                ref_body):
            path = given  # a lower cost that loses the clip (one frame too far) is no gain
        return replace(
            track,
            actions=path["acts"].astype(np.float32),
            qpos=path["qpos"],
            qvel=path["qvel"],
            body_pos=path["body"].astype(np.float32),
            cpu_seconds=track.cpu_seconds + time.process_time() - cpu0,
        )
