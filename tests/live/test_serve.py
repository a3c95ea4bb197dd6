"""The live server on loopback: a recording streamed in and poses out, bad messages and a
disconnect survived, a second driver refused, and the session's poses equal to an offline
`play --input` rollout of the same recording."""

from __future__ import annotations

import asyncio
import json
import threading
from pathlib import Path

import numpy as np
import pytest
import torch
from helpers import REPO, TINY

pytest.importorskip("websockets")

from retarget.cli.main import build_parser, main
from retarget.registry.loader import load_plugins

RECORDING = REPO / "examples" / "recordings" / "walk_openxr.jsonl"


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("live")
    recipe = root / "tiny.yaml"
    recipe.write_text(TINY)
    assert main(["train", str(recipe), "--steps", "32", "--runs-dir", str(root),
                 "--no-tensorboard"]) == 0  # fmt: skip
    return root / "tiny" / "latest"


class Running:
    """A live server on a free loopback port, in its own thread and event loop."""

    def __init__(self, run: Path) -> None:
        from retarget.cli.serve_cmd import build_server

        self.server = build_server(str(run), load_plugins())
        self.port: int | None = None
        self.ready = threading.Event()
        self.thread = threading.Thread(target=self._main, daemon=True)

    def _main(self) -> None:
        from retarget.live.server import serve_forever

        def ready(ws) -> None:
            self.port = next(iter(ws.sockets)).getsockname()[1]
            self.ready.set()

        self.loop = asyncio.new_event_loop()
        self.loop.run_until_complete(serve_forever(self.server, "127.0.0.1", 0, ready))

    def __enter__(self) -> Running:
        self.thread.start()
        assert self.ready.wait(60), "the server did not start"
        return self

    def __exit__(self, *exc) -> None:
        self.loop.call_soon_threadsafe(self.server.stop)
        self.thread.join(10)
        assert not self.thread.is_alive(), "the server did not shut down"

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"


def test_a_recording_streams_in_and_poses_come_back_to_driver_and_viewer(run) -> None:
    from retarget.live.replay import replay

    with Running(run) as live:
        stats = asyncio.run(replay(RECORDING, live.url, speed=4.0, viewers=1))
        summary = live.server.stats.summary()
    assert stats["errors"] == 0 and stats["samples"] == summary["samples"]
    assert stats["poses"] > 20 and stats["viewer_poses"] > 20
    assert stats["answered_samples"] > 10 and stats["round_trip_ms_p50"] is not None
    assert summary["bad_messages"] == {}


def test_bad_messages_are_counted_and_a_disconnect_frees_the_driver_seat(run) -> None:
    from websockets.asyncio.client import connect

    sample = {"type": "devices", "t": 1.0, "hmd": [0, 0, 1.6, 1, 0, 0, 0], "left": None,
              "right": None}  # fmt: skip

    async def session(url: str) -> dict:
        got: dict = {"errors": [], "poses": 0}
        async with connect(url) as a:
            await a.send(json.dumps({"type": "hello", "role": "driver"}))
            sitting = {**sample, "t": 0.2, "hmd": [0, 0, 0.1, 1, 0, 0, 0]}  # not standing
            for bad in (json.dumps(sitting), "not json", "[1, 2]", json.dumps({"type": "dance"}),
                        json.dumps({**sample, "hmd": [0, 0, 1]}),
                        json.dumps({**sample, "hmd": [0, 0, 1e6, 1, 0, 0, 0]}),
                        json.dumps({"type": "hello", "role": "boss"}),
                        json.dumps({**sample, "t": 0.5, "images": {"shape": [2, 4, 4],
                                                                    "data": "!!"}})):  # fmt: skip
                await a.send(bad)
            await a.send(b"\x00binary")
            await a.send(json.dumps(sample))
            await a.send(json.dumps(sample))  # the same time again: out of order
            async with connect(url) as b:  # a second driver watches instead
                await b.send(json.dumps({"type": "hello", "role": "driver"}))
                while True:
                    msg = json.loads(await b.recv())
                    if msg["type"] == "error":
                        got["second"] = msg["message"]
                        break
            for _ in range(80):
                msg = json.loads(await asyncio.wait_for(a.recv(), 5))
                if msg["type"] == "error":
                    got["errors"].append(msg["message"])
                elif msg["type"] == "pose":
                    got["poses"] += 1
                if len(got["errors"]) >= 10 and got["poses"] >= 3:
                    break
        async with connect(url) as c:  # the seat is free again
            await c.send(json.dumps({"type": "hello", "role": "driver"}))
            welcome = json.loads(await c.recv())
            got["again"] = welcome["role"]
        return got

    with Running(run) as live:
        got = asyncio.run(session(live.url))
        summary = live.server.stats.summary()
    assert sum(summary["bad_messages"].values()) == 10, summary
    assert got["poses"] >= 3, "the server kept stepping and answering"
    assert "another client drives" in got["second"]
    assert got["again"] == "driver"
    assert any("out of order" in e for e in got["errors"])
    assert any("standing" in e for e in got["errors"]), "a sitting start is refused, then "\
        "the standing samples calibrate"


def test_the_session_follows_a_recording_as_play_input_does(run) -> None:
    """Sample by sample at the control rate, the live session's bodies equal an offline
    rollout of the recording made the way `play --input` makes it."""
    from retarget.cli.play_cmd import _driven_by
    from retarget.live.session import LiveSession
    from retarget.motion.device_recording import read_recording
    from retarget.motion.device_stream import resample_stream
    from retarget.motion.procedural import idle_clip
    from retarget.train.load import load_run

    registry = load_plugins()
    rec = read_recording(RECORDING)
    args = build_parser(registry).parse_args(["play", str(run), "--input", str(RECORDING),
                                              "--out", "x.png", "--seconds", "2"])  # fmt: skip
    offline, _ = _driven_by(rec, str(run), registry, args)
    env = offline.env
    start = round(args.start * env.sim.settings.control_hz)
    obs = env.place(torch.zeros(1, dtype=torch.long), torch.tensor([start]))
    want = []
    with torch.no_grad():
        for _ in range(40):
            obs, *_ = env.step(offline.algorithm.act(obs))
            want.append(env.sim.state.body_pos[0].numpy().copy())

    live = LiveSession(load_run(run, registry, num_envs=1, clips=[idle_clip(4.0)]))
    hz = live.env.sim.settings.control_hz
    stream = resample_stream(rec, hz)  # already in the retarget convention
    got = []
    for k in range(40):
        live.push(k / hz, stream[k], np.ones(3, dtype=bool), "retarget")
        got.append(live.step()["body_pos"])
    np.testing.assert_allclose(np.array(got), np.array(want), atol=1e-4)


def test_an_untracked_controller_is_held_and_flagged_in_the_sensors_window(run) -> None:
    from retarget.live.session import LiveSession
    from retarget.motion.procedural import idle_clip
    from retarget.train.load import load_run

    live = LiveSession(load_run(run, load_plugins(), num_envs=1, clips=[idle_clip(4.0)]))
    lib, rows = live.env.library, live.rows
    poses = lib.devices[rows[-1]].double().numpy()
    live.push(0.0, poses, np.ones(3, dtype=bool), "retarget")
    live.step()
    assert lib.devices_tracked[rows].all()
    moved = poses.copy()
    moved[2, 0] += 0.3  # the right controller's last reading is not its pose: it is lost
    live.push(0.03, moved, np.array([True, True, False]), "retarget")
    live.step()
    assert lib.devices_tracked[rows[:-1]].all()
    assert lib.devices_tracked[rows[-1]].tolist() == [True, True, False]
    torch.testing.assert_close(lib.devices[rows[-1], 2], lib.devices[rows[-2], 2])  # held


def test_an_image_student_is_served_with_the_headsets_camera_frames(tmp_path) -> None:
    """A recording with frames streams to an image student: every step answered, no error."""
    from helpers import image_student

    from retarget.live.replay import replay

    run = image_student(tmp_path, steps=32)
    assert main(["motion", "generate", "--out", str(tmp_path / "clips"), "--names", "walk"]) == 0
    rec = tmp_path / "me.jsonl"
    assert main(["motion", "record", str(tmp_path / "clips" / "walk.bvh"), "--out", str(rec),
                 "--cameras", "aria", "--size", "24x16"]) == 0  # fmt: skip
    with Running(run) as live:
        stats = asyncio.run(replay(rec, live.url, speed=8.0))
        summary = live.server.stats.summary()
    assert stats["errors"] == 0 and summary["bad_messages"] == {}, (stats, summary)
    assert stats["poses"] > 10
    session = live.server.session
    sensor = session.image_sensors[0]
    seen = sensor._images[session.rows[-1]].numpy()
    assert seen.shape == (2, 16, 24) and seen.any(), "the last frame sent is what it reads"
