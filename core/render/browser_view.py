"""``retarget view``: clips, policy rollouts and a live session in the browser (viser).

Each target becomes a *track*: frames of the world (the character's and props' poses), the
human reference and the devices, computed once (a clip is drawn as its skeleton; a run is
rolled out with its policy on a clip, as ``retarget play`` does). The page has a selector
between tracks, play/pause, a speed and a timeline. ``--live URL`` instead follows a
``retarget serve`` session as a viewer: every pose it sends moves the run's character.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from retarget.kinds.capabilities import Acting, require
from retarget.render.browser_scene import BrowserScene, draw_ghost


@dataclass
class Track:
    """What one target shows, frame by frame."""

    name: str
    fps: float
    model: mujoco.MjModel | None  # None: a bare clip (skeleton only)
    qpos: np.ndarray | None  # (F, nq)
    mocap: tuple[np.ndarray, np.ndarray] | None  # (F, M, 3), (F, M, 4)
    joints: np.ndarray  # (F, J, 3) human reference
    devices: np.ndarray  # (F, 3, 7)
    boxes: list = field(default_factory=list)  # a clip's recorded scene (MeshBox)

    @property
    def frames(self) -> int:
        return int(self.joints.shape[0])


def clip_track(path: str, clip) -> Track:
    from retarget.motion.devices import device_poses

    devices = device_poses(clip.global_pos, clip.global_rot, clip.height)
    boxes = []
    if clip.source is not None and clip.source.parent.is_dir():
        from retarget.scene.mesh_boxes import boxes_from_mesh, mesh_beside

        mesh = mesh_beside(clip.source)
        boxes = boxes_from_mesh(mesh) if mesh is not None else []
    return Track(Path(path).name, clip.fps, None, None, None, clip.global_pos, devices, boxes)


def run_track(path: str, loaded, seconds: float) -> Track:
    """The run's policy rolled out on its first clip from the start."""
    import torch

    env = loaded.env
    lib = env.library
    steps = int(min(seconds * env.sim.settings.control_hz, int(lib.length[0]) - 2))
    obs = env.place(torch.zeros(1, dtype=torch.long), torch.zeros(1, dtype=torch.long))
    qpos, mpos, mquat, joints, devices = [], [], [], [], []
    act = require(loaded.algorithm, Acting, hint="view shows a policy driving physics").act
    with torch.no_grad():
        for _ in range(max(steps, 1)):
            obs, *_ = env.step(act(obs))
            row = int(lib.rows(env.clip[:1], env.frame[:1])[0, 0])
            qpos.append(env.sim.raw("qpos")[0].copy())
            mpos.append(env.sim.raw("mocap_pos")[0].copy())
            mquat.append(env.sim.raw("mocap_quat")[0].copy())
            joints.append(lib.global_pos[row].numpy())
            devices.append(lib.devices[row].numpy())
    name = f"{Path(path).resolve().parent.name}: {lib.names[0]}"
    mocap = (np.array(mpos), np.array(mquat))
    return Track(name, env.sim.settings.control_hz, env.world.model, np.array(qpos), mocap,
                 np.array(joints), np.array(devices))  # fmt: skip


class Viewer:
    """A viser server showing tracks with playback controls."""

    def __init__(self, tracks: list[Track], host: str = "127.0.0.1", port: int = 8080) -> None:
        import viser

        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.tracks = tracks
        self.frame, self.playing, self.speed = 0, True, 1.0
        self.scene: BrowserScene | None = None
        gui = self.server.gui
        names = [t.name for t in tracks]
        self.selector = gui.add_dropdown("show", names, initial_value=names[0])
        self.play_box = gui.add_checkbox("playing", initial_value=True)
        self.speed_slider = gui.add_slider("speed", min=0.1, max=4.0, step=0.1, initial_value=1.0)
        self.timeline = gui.add_slider("frame", min=0, max=max(tracks[0].frames - 1, 1), step=1,
                                       initial_value=0)  # fmt: skip
        self.selector.on_update(lambda _: self._select())
        self.play_box.on_update(lambda _: setattr(self, "playing", self.play_box.value))
        self.speed_slider.on_update(lambda _: setattr(self, "speed", self.speed_slider.value))
        self.timeline.on_update(lambda _: self._seek(int(self.timeline.value)))
        self.server.scene.set_up_direction("+z")
        self._data: mujoco.MjData | None = None
        self._select()
        # a new page looks at the character's start from 4 m, slightly above
        start = tracks[0].joints[0, 0]
        camera = self.server.initial_camera
        camera.up = (0.0, 0.0, 1.0)
        camera.look_at = (float(start[0]), float(start[1]), 0.9)
        camera.position = (float(start[0]) + 3.0, float(start[1]) - 2.5, 1.8)

    @property
    def track(self) -> Track:
        return next(t for t in self.tracks if t.name == self.selector.value)

    def _select(self) -> None:
        self.server.scene.reset()
        track = self.track
        self.scene = BrowserScene(self.server, track.model) if track.model is not None else None
        if self.scene is None:
            self.server.scene.add_grid("/world/floor", width=20.0, height=20.0, cell_size=0.5)
        for k, box in enumerate(track.boxes):
            c, s = np.cos(box.yaw / 2), np.sin(box.yaw / 2)
            self.server.scene.add_box(f"/world/box{k}", color=(160, 130, 100),
                                      dimensions=(*box.size, box.height),
                                      position=(*box.position, box.height / 2),
                                      wxyz=(c, 0.0, 0.0, s))  # fmt: skip
        self._data = mujoco.MjData(track.model) if track.model is not None else None
        self.timeline.max = max(track.frames - 1, 1)
        self._seek(0)

    def _seek(self, frame: int) -> None:
        self.frame = int(np.clip(frame, 0, self.track.frames - 1))
        self.draw()

    def draw(self) -> None:
        track, f = self.track, self.frame
        if self.scene is not None and self._data is not None and track.qpos is not None:
            self._data.qpos[:] = track.qpos[f]
            if track.mocap is not None:
                self._data.mocap_pos[:] = track.mocap[0][f]
                self._data.mocap_quat[:] = track.mocap[1][f]
            mujoco.mj_kinematics(track.model, self._data)
            self.scene.show(self._data)
        draw_ghost(self.server, track.joints[f], track.devices[f])

    def play(self, seconds: float | None = None) -> None:
        """Advance the timeline while playing, until ``seconds`` pass (None: forever)."""
        end = None if seconds is None else time.perf_counter() + seconds
        while end is None or time.perf_counter() < end:
            track = self.track
            if self.playing and track.frames > 1:
                self.frame = (self.frame + 1) % track.frames
                self.timeline.value = self.frame  # moves the slider; its callback draws
            time.sleep(1.0 / (track.fps * max(self.speed, 0.05)))


def follow_live(url: str, loaded, host: str, port: int, seconds: float | None = None) -> None:
    """Show a ``retarget serve`` session: connect as a viewer, move the character to every
    pose it sends (in the retarget convention)."""
    import asyncio

    import viser
    from websockets.asyncio.client import connect

    server = viser.ViserServer(host=host, port=port, verbose=False)
    server.scene.set_up_direction("+z")
    model = loaded.env.world.model
    scene = BrowserScene(server, model)
    ids = np.asarray(loaded.env.layout.body_ids)
    status = server.gui.add_markdown(f"following `{url}`")
    counts = {"poses": 0}

    async def main() -> None:
        end = None if seconds is None else time.perf_counter() + seconds
        async with connect(url) as conn:
            await conn.send(json.dumps({"type": "hello", "role": "viewer"}))
            while end is None or time.perf_counter() < end:
                try:
                    text = await asyncio.wait_for(conn.recv(), timeout=1.0)
                except TimeoutError:
                    continue
                msg = json.loads(text)
                if msg.get("type") != "pose":
                    continue
                counts["poses"] += 1
                scene.show_bodies(ids, np.asarray(msg["body_pos"]), np.asarray(msg["body_quat"]))
                if counts["poses"] % 36 == 0:
                    status.content = f"following `{url}`: step {msg['step']}"

    asyncio.run(main())
    server.stop()
