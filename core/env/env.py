"""``RetargetEnv``: N simulated characters tracking human motion, as a ``VecEnv``.

One control step, in order (DESIGN.md §5):

1. actions in [-1, 1] become torques (actuator gear = per-joint limit) for ``substeps``
   physics steps (:class:`~retarget.sim.BatchedSim`);
2. every environment's reference advances one frame (the library is at the control rate);
3. a frozen :class:`~retarget.kinds.state.StepContext` is built: sim state, reference pose,
   device window, contact labels, and what some plugin ``needs()`` (future reference
   frames, scene contact labels);
4. terminations (failure vs time-out; a clip's end is a time-out), then rewards (weighted
   sum, per-term logs) from a context that says which environments failed
   (``ctx.terminated``: the fail penalty is an ordinary term);
5. if any environment timed out, the observations it ended in are returned as
   ``info["final_obs"]`` (PPO bootstraps time-outs from them; failures need none);
6. finished environments restart from random reference frames (RSI), then every group's
   observation is computed once for all environments.

Environments whose physics blew up are flagged by ``BatchedSim``; they end as failures with a
zero reward and are counted in ``info["nan_resets"]``: no NaN reaches an observation or a
reward. A non-finite action does the same (zero action, failure, ``info["nan_actions"]``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import replace

import mujoco
import numpy as np
import torch

from retarget.character.kinematic import root_height_ratio, scaled_clip
from retarget.env.curriculum import FailureCurriculum
from retarget.env.device_noise import DeviceNoise
from retarget.env.idle_starts import IdleStarts
from retarget.env.managers import RewardManager, TerminationManager
from retarget.env.observation_manager import ObservationManager, PluginSource
from retarget.env.observations import Privileged, Proprio
from retarget.env.reference import CharacterReference
from retarget.env.root_assist import RootAssist
from retarget.errors import PluginError
from retarget.geometry import rotations as rot
from retarget.kinds import Character, Observer, RewardTerm, Scene, Sensor, Termination
from retarget.kinds.state import ReferenceBatch, StepContext
from retarget.kinds.step import StepNeeds, StepPlugin
from retarget.motion.clip import MotionClip
from retarget.motion.devices import device_poses
from retarget.motion.library import MotionLibrary
from retarget.motion.resample import resample
from retarget.scene.ground import Ground
from retarget.settings.env import EnvOptions
from retarget.sim import SimSettings, make_sim
from retarget.sim.world import build_world


class RetargetEnv:
    """Physics tracking environment over a batch of ``num_envs`` worlds (see module doc)."""

    def __init__(
        self,
        character: Character,
        clips: Sequence[MotionClip],
        *,
        sensors: Sequence[Sensor] = (),
        observers: Sequence[Observer] = (),
        rewards: Mapping[str, RewardTerm] | None = None,
        terminations: Mapping[str, Termination] | None = None,
        scene: Scene | None = None,
        options: EnvOptions | None = None,
        sim: SimSettings | None = None,
        seed: int = 0,
        clip_weights: Sequence[float] | None = None,
    ) -> None:
        self.options = opts = options or EnvOptions()
        sim = sim or SimSettings()
        self.num_envs = n = opts.num_envs
        if scene is None:  # the floor alone: every environment has a scene
            scene = Ground()
        self.character, self.scene = character, scene
        fits = type(scene).fit_motion is not Scene.fit_motion
        if fits or opts.devices == "character":
            # the clips as a person of the character's size performs them (its reference root
            # path is scaled by the same ratio): props placed from the motions come before the
            # build, and with devices at the character's size the library holds these clips,
            # so devices, headset views and estimator targets sit on the reference's body
            rest = character.build_spec().compile()
            scaled = [scaled_clip(c, root_height_ratio(rest, c)) for c in clips]
            if fits:
                scene.fit_motion(scaled)
            if opts.devices == "character":
                clips = scaled
        self.world = build_world(character, scene)
        self.layout = layout = self.world.layout
        hz = sim.control_hz
        clips = [resample(c, hz) for c in clips]
        self.library = MotionLibrary(clips, fps=hz, weights=clip_weights)
        self._mocap_ids = self._scene_mocap_ids()
        self.reference = CharacterReference(character, self.world.model, layout, clips,
                                            mocap=self._clip_placements(len(clips)),
                                            ground=opts.ground_feet,
                                            hinge=opts.hinge_elbows)  # fmt: skip
        self._headset_mount: torch.Tensor | None = None
        self.idle_starts = None
        if opts.idle_starts > 0:
            self.idle_starts = IdleStarts(opts.idle_starts, self.library.from_rest,
                                          self.idle_qpos(hz))  # fmt: skip
        self.sim = make_sim(self.world.model, layout, n, sim)
        self.reference.use_servos(self.sim.model)  # the servos exist once the sim set them up
        self.sensors, self.observers = list(sensors), list(observers)
        for plugin in (*self.sensors, *self.observers):
            plugin.bind(layout)
            plugin.prepare(self.library)
        self.rewards = RewardManager(rewards or {}, n)
        for term in self.rewards.terms.values():
            term.bind(layout)
            term.prepare(self.library)
        self.terminations = TerminationManager(terminations or {})
        for term in self.terminations.terms.values():
            term.bind(layout)
            term.prepare(self.library)
        past = max([s.frames_needed()[0] for s in self.sensors] + [0])
        future = max([s.frames_needed()[1] for s in self.sensors] + [0])
        self.window_offsets = tuple(range(-past, future + 1))
        self.observations = ObservationManager(
            [
                *(PluginSource.of(p, layout) for p in (*self.sensors, *self.observers)),
                Proprio(layout),
                Privileged(layout, tuple(opts.privileged_offsets)),
            ],
            opts.groups or self._default_groups(),
        )
        self.groups = self.observations.groups
        self.obs_dims = self.observations.dims
        for plugin in (*self.sensors, *self.observers, *self.rewards.terms.values(),
                       *self.terminations.terms.values()):  # fmt: skip
            _check_needs(plugin)
        self._needs = StepNeeds()
        self.gather(
            self.observations.needs,
            *(t.needs() for t in self.rewards.terms.values()),
            *(t.needs() for t in self.terminations.terms.values()),
        )
        self.action_dim = layout.nu
        self.curriculum = (FailureCurriculum(self.library, opts.curriculum, n)
                           if opts.curriculum is not None else None)  # fmt: skip
        self.root_assist = None
        if opts.root_assist is not None:
            root = layout.body_ids[0]
            mass = float(self.world.model.body_subtreemass[root])
            height = 1.9 * float(np.median(self.reference.qpos64[:, 2]))
            self.root_assist = RootAssist(opts.root_assist, mass, height)
        self.device_noise = (DeviceNoise(opts.device_noise, n, seed, self.sim.settings.control_dt)
                             if opts.device_noise is not None else None)  # fmt: skip
        self.generator = torch.Generator().manual_seed(seed)
        self.clip = torch.zeros(n, dtype=torch.long)
        self.frame = torch.zeros(n, dtype=torch.long)
        self.episode_step = torch.zeros(n, dtype=torch.long)
        self.episode_return = torch.zeros(n)
        self.prev_action = torch.zeros(n, layout.nu)
        self.last_context: StepContext | None = None
        """The last step's state before its resets (evaluation reads it); None before one."""
        self.nan_resets = 0
        self.nan_actions = 0  # actions with NaN/inf (those environments end as failures)
        self.total_steps = 0  # environment steps taken (num_envs per call of step)
        self.seconds = dict.fromkeys(
            ("reference", "rewards", "terminations", "observations", "resets"), 0.0
        )

    def gather(self, *needs: StepNeeds) -> None:
        """Gather more for every later step (evaluation asks for the scene contact labels its
        metrics read); offsets are frames ``>= 1`` ahead."""
        for need in needs:
            _check_offsets(need.reference_offsets, None)
            self._needs = self._needs | need

    @property
    def step_needs(self) -> StepNeeds:
        """What each step gathers beyond the state and the reference pose."""
        return self._needs

    def _clip_placements(self, count: int) -> list[tuple[np.ndarray, np.ndarray] | None] | None:
        """Every mocap body's pose per clip where the scene places its props per clip."""
        if not self._mocap_ids.size:
            return None
        model = self.world.model
        data = mujoco.MjData(model)
        out: list[tuple[np.ndarray, np.ndarray] | None] = []
        for c in range(count):
            placed = self.scene.reference_placement(c)
            if placed is None:
                out.append(None)
                continue
            pos, quat = data.mocap_pos.copy(), data.mocap_quat.copy()
            pos[self._mocap_ids], quat[self._mocap_ids] = placed[0].numpy(), placed[1].numpy()
            out.append((pos, quat))
        return out

    def _scene_mocap_ids(self) -> np.ndarray:
        """Indices into ``mocap_pos`` of the scene's props, resolved once; sizes the scene's
        per-environment placement state."""
        scene, model = self.scene, self.world.model
        scene.allocate(self.num_envs)
        ids = []
        for body in scene.mocap_bodies():
            bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
            if bid < 0 or model.body_mocapid[bid] < 0:
                raise PluginError(
                    f"mocap_bodies() names '{body}', which is not a mocap body of the model",
                    plugin=f"scene {scene.name}",
                )
            ids.append(int(model.body_mocapid[bid]))
        return np.asarray(ids, dtype=np.intp)

    # ------------------------------------------------------------------ observations

    def observation_size(self, source: str) -> int:
        """Width of one observation source (``proprio``, a sensor's or observer's name)."""
        return int(self.observations.sources[source].size)

    @property
    def obs_shapes(self) -> dict[str, list[tuple[str, tuple[int, ...]]]]:
        """Each group's sources in column order, ``(name, shape)`` (images as ``(C, H, W)``)."""
        return self.observations.shapes

    @property
    def obs_layout(self) -> dict[str, list[tuple[str, int]]]:
        """Each group's sources in column order, ``(name, size)``: which columns of a group
        come from which sensor or observer (used to carry weights between recipes)."""
        return self.observations.layout

    def idle_qpos(self, hz: float) -> np.ndarray:
        """The character's idle standing pose: where ``retarget serve`` and ``play --input``
        start (the same frame of the same generated idle clip, retargeted as the library)."""
        ref, _, frame = self._idle_reference(hz)
        return ref.qpos64[frame].copy()

    @property
    def headset_mount(self) -> torch.Tensor:
        """Where the headset sits on this character, ``(3,)`` metres in its ``head`` site's
        frame: measured on the idle pose against the headset the idle clip gives (the
        calibrated start of ``play --input`` and ``serve``).

        A human's head site is the headset mount (a few millimetres off), but a character
        shaped unlike the person is not: the Dino's head stands 0.6 m from the headset of the
        person it is retargeted from. SimXR's rule (head farther than 0.5 m from the headset)
        reads the gap from this point on the head instead, so a Dino standing still under
        its calibrated headset is not counted as lost."""
        if self._headset_mount is None:
            ref, clip, frame = self._idle_reference(self.library.fps)
            head = self.layout.site("head")
            headset = device_poses(clip.global_pos[frame], clip.global_rot[frame], clip.height)
            pos = ref.arrays["site_pos"][frame, head].double().numpy()
            quat = ref.arrays["site_quat"][frame, head].double().numpy()
            local = rot.apply(rot.conj(quat), headset[0, :3] - pos)
            self._headset_mount = torch.as_tensor(local, dtype=torch.float32)
        return self._headset_mount

    def _idle_reference(self, hz: float) -> tuple[CharacterReference, MotionClip, int]:
        """The generated idle clip at ``hz`` (scaled like the library's clips), its reference
        on this character, and the frame live sessions start at."""
        from retarget.motion.procedural import idle_clip

        idle = idle_clip(1.0)
        if self.options.devices == "character":
            idle = scaled_clip(idle, root_height_ratio(self.character.build_spec().compile(), idle))
        idle = resample(idle, hz)
        ref = CharacterReference(self.character, self.world.model, self.layout, [idle],
                                 ground=self.options.ground_feet,
                                 hinge=self.options.hinge_elbows)  # fmt: skip
        return ref, idle, min(2, len(ref.qpos64) - 1)

    def _default_groups(self) -> dict[str, list[str]]:
        actor = [s.name for s in self.sensors] + ["proprio"] + [o.name for o in self.observers]
        return {"actor": actor, "critic": [*actor, "privileged"]}

    def observe(self, ctx: StepContext) -> dict[str, torch.Tensor]:
        """Every group's ``(N, D)`` observation; each source is computed once per step."""
        return self.observations.compute(ctx)

    # ------------------------------------------------------------------ reference

    def _noisy_devices_at(self, frames: torch.Tensor) -> torch.Tensor:
        """``(N, D, 7)`` devices of each environment's clip at ``frames``, calibration noise
        included (where a lost controller is held)."""
        lib = self.library
        devices = lib.devices[lib.rows(self.clip, frames)[:, 0]][:, None]
        return self.device_noise.apply(devices)[:, 0]

    def _context(self, action: torch.Tensor) -> StepContext:
        lib = self.library
        rows = lib.rows(self.clip, self.frame)[:, 0]
        window = lib.rows(self.clip, self.frame, self.window_offsets)
        devices, tracked = lib.devices[window], lib.devices_tracked[window]
        if self.device_noise is not None:
            devices = self.device_noise.apply(devices)
            devices, tracked = self.device_noise.hold(devices, tracked, self.frame,
                                                      self.window_offsets,
                                                      self._noisy_devices_at)  # fmt: skip
        need = self._needs
        ahead = {}
        if need.reference_offsets:
            ahead_rows = lib.rows(self.clip, self.frame, need.reference_offsets)
            ahead = {
                k: self.reference.pose(ahead_rows[:, i])
                for i, k in enumerate(need.reference_offsets)
            }
        ref = ReferenceBatch(
            pose=self.reference.pose(rows),
            devices=devices,
            window_offsets=self.window_offsets,
            contacts=lib.contacts[rows],
            future=ahead,
            rows=rows,
            scene_contacts=self.reference.scene_contacts[rows] if need.scene_contacts else None,
            devices_tracked=tracked,
        )
        return StepContext(
            layout=self.layout,
            sim=self.sim.state,
            ref=ref,
            action=action,
            prev_action=self.prev_action,
            episode_step=self.episode_step,
            dt=self.sim.settings.control_dt,
            scene=self.scene,
        )

    # ------------------------------------------------------------------ resets

    def _reset_envs(
        self,
        env_ids: torch.Tensor,
        clip: torch.Tensor | None = None,
        frame: torch.Tensor | None = None,
    ) -> None:
        """Reference state initialisation: random (clip, frame) unless given, and the
        kinematic pose there."""
        if env_ids.numel() == 0:
            return
        idle = None
        if clip is None or frame is None:
            sampler = self.curriculum or self.library
            clip, frame = sampler.sample(int(env_ids.numel()), self.generator, margin=2)
            if self.idle_starts is not None:
                idle = self.idle_starts.choose(clip, frame, self.generator).numpy()
        self.clip[env_ids], self.frame[env_ids] = clip, frame
        rows = self.library.rows(clip, frame)[:, 0].numpy()
        qpos = self.reference.qpos64[rows].copy()
        qvel = self.reference.qvel64[rows].copy()
        if idle is not None and idle.any():
            qpos[idle] = self.idle_starts.pose(qpos[idle])
            qvel[idle] = 0.0
        qpos[:, 2] += self.options.reset_lift
        mocap = None
        # a new episode gets new prop placements (Sec. 3.4)
        seconds = frame.double() * self.sim.settings.control_dt
        self.scene.start_episodes(env_ids, clip, seconds)
        self.scene.randomize(env_ids, self.generator)
        if self._mocap_ids.size:
            pos, quat = self.scene.mocap_poses(env_ids)
            mocap = (self._mocap_ids, pos.numpy(), quat.numpy())
        self.sim.reset(env_ids.numpy(), qpos, qvel, mocap)
        if self.device_noise is not None:
            self.device_noise.redraw(env_ids)
        self.episode_step[env_ids] = 0
        self.episode_return[env_ids] = 0.0
        self.prev_action[env_ids] = 0.0
        for manager in (self.rewards, self.terminations, self.observations):
            manager.reset(env_ids)

    def place(self, clip: torch.Tensor, frame: torch.Tensor) -> dict[str, torch.Tensor]:
        """Start every environment at the given reference (clip, frame): evaluation uses this
        to start from every k-th frame instead of random ones."""
        self._reset_envs(torch.arange(self.num_envs), clip.long(), frame.long())
        self.rewards.episode_sums.zero_()
        return self.observe(self._context(torch.zeros(self.num_envs, self.action_dim)))

    def place_state(
        self,
        env_ids: torch.Tensor,
        clip: torch.Tensor,
        frame: torch.Tensor,
        qpos: np.ndarray,
        qvel: np.ndarray,
        prev_action: torch.Tensor | None = None,
    ) -> None:
        """Start ``env_ids`` at reference (clip, frame) in a given physical state instead of
        the reference pose: a recorded state of a tracking expert (``retarget.expert``), whose
        actions a student then learns on the states they were planned from. ``qpos``/``qvel``
        may cover the whole model or the character only (as in :meth:`BatchedSim.reset`);
        ``prev_action`` is what the expert did the step before. Call :meth:`observe_now`
        for the observation afterwards."""
        env_ids = env_ids.long()
        self._reset_envs(env_ids, clip.long(), frame.long())
        mocap = None
        if self._mocap_ids.size:  # the props stay where this episode's placement put them
            ids = env_ids.numpy()
            mocap = (self._mocap_ids, self.sim.raw("mocap_pos")[ids][:, self._mocap_ids],
                     self.sim.raw("mocap_quat")[ids][:, self._mocap_ids])  # fmt: skip
        self.sim.reset(env_ids.numpy(), qpos, qvel, mocap)
        if prev_action is not None:
            self.prev_action[env_ids] = prev_action.float()

    def observe_now(self, groups: Sequence[str] | None = None) -> dict[str, torch.Tensor]:
        """The observation (of ``groups``, default all) of the current simulation and
        reference rows, recomputed: a live stream writes its newest device poses into the
        library and acts on them at once."""
        return self.observations.compute(self._context(self.prev_action), groups)

    def step_physics(self, action: torch.Tensor) -> torch.Tensor:
        """Advance the simulation one control step with ``action`` and nothing else: no
        reference advance, terminations, rewards or observations (a live session computes
        the observation it acts on itself, :meth:`observe_now`). Environments whose physics
        went non-finite are put back at their current reference frame; returns which."""
        action = torch.nan_to_num(torch.as_tensor(action, dtype=torch.float32), 0.0, 0.0, 0.0)
        action = action.clamp(-1.0, 1.0)
        bad = torch.from_numpy(self.sim.step(action))
        self.total_steps += self.num_envs
        self.episode_step += 1
        self.prev_action = action.clone()
        ids = bad.nonzero().flatten()
        if ids.numel():
            self._reset_envs(ids, self.clip[ids], self.frame[ids])
        return bad

    def reset(self) -> dict[str, torch.Tensor]:
        self._reset_envs(torch.arange(self.num_envs))
        return self.observe(self._context(torch.zeros(self.num_envs, self.action_dim)))

    # ------------------------------------------------------------------ stepping

    def step(self, action: torch.Tensor):
        action = torch.as_tensor(action, dtype=torch.float32)
        broken = ~torch.isfinite(action).all(dim=-1)  # a policy that output NaN/inf
        action = torch.nan_to_num(action, 0.0, 0.0, 0.0).clamp(-1.0, 1.0)
        self.total_steps += self.num_envs
        if self.root_assist is not None:
            self._assist()
        bad = torch.from_numpy(self.sim.step(action)) | broken
        sec, t0 = self.seconds, time.perf_counter()
        self.frame, clip_end = self.library.advance(self.clip, self.frame)
        self.episode_step += 1
        ctx = self._context(action)
        t1 = time.perf_counter()
        failed, timed_out = self.terminations.check(ctx)
        failed |= bad
        timed_out = (timed_out | clip_end) & ~failed
        if self.curriculum is not None:
            self.curriculum.record(self.clip, self.frame, failed)
        t2 = time.perf_counter()
        # rewards come after terminations, so a term paid on failure is an ordinary term
        ctx = replace(ctx, terminated=failed)
        self.last_context = ctx  # the step's state before any reset (evaluation reads it)
        reward = self.rewards.compute(ctx, valid=~bad)
        reward = torch.where(bad, torch.zeros_like(reward), torch.nan_to_num(reward))
        self.episode_return += reward
        done = failed | timed_out
        ids = done.nonzero().flatten()
        info: dict = {"nan_resets": int(bad.sum()), "nan_actions": int(broken.sum())}
        self.nan_resets += info["nan_resets"]
        self.nan_actions += info["nan_actions"]
        self.prev_action = action.clone()
        final_obs = 0.0
        if ids.numel():
            if timed_out.any():  # only time-outs bootstrap from the observation they ended in
                t_obs = time.perf_counter()
                info["final_obs"] = self.observe(ctx)
                final_obs = time.perf_counter() - t_obs
            info["episode"] = {
                "return": self.episode_return[ids].clone(),
                "length": self.episode_step[ids].clone(),
                "terms": self.rewards.pop_episodes(ids),
            }
            t4 = time.perf_counter()
            self._reset_envs(ids)
            ctx = self._context(self.prev_action)
        else:
            t4 = time.perf_counter()
        t5 = time.perf_counter()
        obs = self.observe(ctx)
        t6 = time.perf_counter()
        sec["reference"] += t1 - t0
        sec["terminations"] += t2 - t1
        sec["rewards"] += t4 - t2 - final_obs  # the terms, the returns and episode logs
        sec["observations"] += t6 - t5 + final_obs
        sec["resets"] += t5 - t4
        return obs, reward, failed, timed_out, info

    def _assist(self) -> None:
        """The root wrench toward the next reference frame for this control step (zero while
        no trainer has set a scale: every evaluation)."""
        assert self.root_assist is not None
        if self.root_assist.scale <= 0.0:
            self.sim.set_root_wrench(None)
            return
        rows = self.library.rows(self.clip, self.frame, (1,))[:, 0]
        ref, sim, a = self.reference.arrays, self.sim.state, self.root_assist
        wrench = a.wrench(
            sim.body_pos[:, 0], sim.body_quat[:, 0], sim.body_linvel[:, 0],
            sim.body_angvel[:, 0], ref["body_pos"][rows, 0], ref["body_quat"][rows, 0],
            ref["body_linvel"][rows, 0], ref["body_angvel"][rows, 0],
        )  # fmt: skip
        self.sim.set_root_wrench(wrench.double().numpy())

    def state_dict(self) -> dict:
        """Everything needed to continue stepping exactly where this env is (checkpoints)."""
        return {
            "sim": self.sim.state_dict(),
            "clip": self.clip.clone(),
            "frame": self.frame.clone(),
            "episode_step": self.episode_step.clone(),
            "episode_return": self.episode_return.clone(),
            "prev_action": self.prev_action.clone(),
            "reward_sums": self.rewards.episode_sums.clone(),
            "generator": self.generator.get_state(),
            "nan_resets": self.nan_resets,
            "nan_actions": self.nan_actions,
            "total_steps": self.total_steps,
            "curriculum": self.curriculum.state_dict() if self.curriculum is not None else {},
            "scene": self.scene.state_dict(),
            "device_noise": {} if self.device_noise is None else self.device_noise.state_dict(),
        }

    def load_state_dict(self, state: Mapping) -> dict[str, torch.Tensor]:
        """Restore :meth:`state_dict`; returns the observations of the restored state."""
        if state["clip"].shape[0] != self.num_envs:
            raise ValueError(
                f"checkpoint has {state['clip'].shape[0]} environments, this env {self.num_envs}"
            )
        self.sim.load_state_dict(state["sim"])
        self.clip, self.frame = state["clip"].clone(), state["frame"].clone()
        self.episode_step = state["episode_step"].clone()
        self.episode_return = state["episode_return"].clone()
        self.prev_action = state["prev_action"].clone()
        self.rewards.episode_sums = state["reward_sums"].clone()
        self.rewards.reset(torch.arange(self.num_envs))  # terms' own state is not saved
        self.generator.set_state(state["generator"])
        self.nan_resets = int(state["nan_resets"])
        self.nan_actions = int(state.get("nan_actions", 0))
        self.total_steps = int(state["total_steps"])
        if state.get("curriculum") and self.curriculum is not None:
            self.curriculum.load_state_dict(state["curriculum"])
        if state.get("scene"):
            self.scene.load_state_dict(state["scene"])
        if state.get("device_noise") and self.device_noise is not None:
            self.device_noise.load_state_dict(state["device_noise"])
        return self.observe(self._context(self.prev_action))

    @property
    def termination_counts(self) -> dict[str, int]:
        return dict(self.terminations.counts)


def random_actions(
    env: RetargetEnv, generator: torch.Generator, scale: float = 1.0
) -> torch.Tensor:
    """Uniform actions in ``[-scale, scale]`` for every environment (benchmarks, smoke tests)."""
    return (torch.rand(env.num_envs, env.action_dim, generator=generator) * 2 - 1) * scale


def _check_needs(plugin: StepPlugin) -> None:
    _check_offsets(plugin.needs().reference_offsets, f"{plugin.kind} {plugin.name}")


def _check_offsets(offsets: Sequence[object], plugin: str | None) -> None:
    """Reference offsets are ints >= 1 (frames ahead); a bool is not a frame count."""
    bad = [k for k in offsets if not isinstance(k, int) or isinstance(k, bool) or k < 1]
    if bad:
        raise PluginError(
            f"needs() asks for reference offsets {bad}; offsets are ints >= 1 (frames ahead)",
            plugin=plugin,
        )
