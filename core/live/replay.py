"""``retarget stream``: a recording replayed to a live server as a headset application would.

The reference client: it says hello as the driver in the recording's own convention, sends
each sample at its time (``speed`` times real time), and reads the poses that come back,
matching each to the sample it answers (by ``t``) for the round-trip latency. Optional extra
connections watch as viewers, as a spectator view or a second screen would. This is the code
a Unity or OpenXR application reproduces: one JSON message per tracking frame.
"""

from __future__ import annotations

import asyncio
import base64
import json
import time
from pathlib import Path

import numpy as np

from retarget.motion.device_recording import FORMAT, convert, read_recording
from retarget.motion.devices import DEVICES


def _convention(path: Path) -> str:
    with path.open(encoding="utf-8") as f:
        header = json.loads(f.readline())
    return header.get("convention", "retarget") if header.get("format") == FORMAT else "retarget"


async def _connect(url: str, wait: float):
    """A connection to ``url``, retried for ``wait`` seconds (a server that is still loading)."""
    from websockets.asyncio.client import connect

    deadline = time.perf_counter() + wait
    while True:
        try:
            return await connect(url, max_size=4 * 2**20, compression=None)
        except OSError:
            if time.perf_counter() > deadline:
                raise
            await asyncio.sleep(0.25)


async def replay(path: str | Path, url: str, *, speed: float = 1.0, viewers: int = 0,
                 linger: float = 0.3, wait: float = 10.0) -> dict:  # fmt: skip
    """Stream ``path`` to ``url``; statistics of what was sent and what came back."""
    path = Path(path)
    rec = read_recording(path)  # validated: errors name the file and line
    convention = _convention(path)
    poses = convert(rec.poses, "retarget", convention)
    sent_at: dict[float, float] = {}
    rtt: list[float] = []
    server_ms: list[float] = []
    counts = {"poses": 0, "errors": 0, "viewer_poses": 0}

    async def watch(conn, key: str) -> None:
        async for text in conn:
            msg = json.loads(text)
            if msg.get("type") == "pose":
                counts[key] += 1
                t = msg.get("t")
                if key == "poses" and t in sent_at:
                    rtt.append((time.perf_counter() - sent_at.pop(t)) * 1e3)
                    if msg.get("latency_ms") is not None:
                        server_ms.append(msg["latency_ms"])
            elif msg.get("type") == "error":
                counts["errors"] += 1

    async with await _connect(url, wait) as conn:
        watchers = [await _connect(url, wait) for _ in range(viewers)]
        tasks = [asyncio.create_task(watch(conn, "poses"))]
        tasks += [asyncio.create_task(watch(w, "viewer_poses")) for w in watchers]
        hello = {"type": "hello", "role": "driver", "convention": convention}
        if rec.frames is not None:  # an image student's cameras, with the recording's rig
            hello["rig"] = json.loads(rec.frames.rig)
        await conn.send(json.dumps(hello))
        start = time.perf_counter()
        for k in range(len(rec.time)):
            due = start + (rec.time[k] - rec.time[0]) / speed
            delay = due - time.perf_counter()
            if delay > 0:
                await asyncio.sleep(delay)
            sample: dict[str, object] = {"type": "devices", "t": float(rec.time[k])}
            for d, name in enumerate(DEVICES):
                sample[name] = poses[k, d].tolist() if rec.tracked[k, d] else None
            if rec.frames is not None:
                frame = rec.frames.images[int(rec.frames.latest(rec.time[k : k + 1])[0])]
                sample["images"] = {
                    "shape": list(frame.shape),
                    "data": base64.b64encode(frame.tobytes()).decode(),
                }
            sent_at[float(rec.time[k])] = time.perf_counter()
            await conn.send(json.dumps(sample))
        await asyncio.sleep(linger)
        for task in tasks:
            task.cancel()
        for w in watchers:
            await w.close()
    wall = time.perf_counter() - start
    answered = len(rtt)

    def pct(values: list[float], q: float) -> float | None:
        return float(np.percentile(values, q)) if values else None

    return {
        "samples": len(rec.time), "seconds": wall, "poses": counts["poses"],
        "viewer_poses": counts["viewer_poses"], "errors": counts["errors"],
        "answered_samples": answered, "unanswered_samples": len(rec.time) - answered,
        "round_trip_ms_p50": pct(rtt, 50), "round_trip_ms_p99": pct(rtt, 99),
        "server_ms_p50": pct(server_ms, 50), "server_ms_p99": pct(server_ms, 99),
    }  # fmt: skip
