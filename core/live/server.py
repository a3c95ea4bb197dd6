"""``retarget serve``: the live session behind a WebSocket server (asyncio, ``websockets``).

``websockets`` is the whole server: one socket per client, JSON text both ways, asyncio all
the way through; a web framework would add routing and a second event loop for nothing.

**Clock.** Steps follow the driver's samples: a step runs when a sample arrives, but never
sooner than half a control period after the previous one (a fast client cannot speed the
simulation up) and at the latest 1.25 periods after it (a client that stalls does not stall
the avatar: it keeps stepping, holding the last poses). So a 36 Hz headset phase-locks the
simulation to its own frames and the latency is the compute, not a wait for the next tick.
Every step's pose goes to every client; one whose socket is backed up skips poses (counted)
instead of filling memory.

**Bad input** is counted and answered with an ``error`` message, never fatal; a driver that
disconnects frees the driver's seat; Ctrl-C stops the loop and closes every socket.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections import Counter, deque
from dataclasses import dataclass, field

from retarget.errors import PluginError
from retarget.live.protocol import BadMessage, Hello, Sample, parse, pose_message
from retarget.live.session import LiveSession

BACKLOG_BYTES = 256 * 1024
"""A client whose unsent data exceeds this skips poses until it catches up."""


@dataclass
class Client:
    role: str = "viewer"
    convention: str = "retarget"
    last_t: float | None = None
    rig: str | None = None


@dataclass
class Stats:
    steps: int = 0
    samples: int = 0
    bad: Counter = field(default_factory=Counter)
    skipped_poses: int = 0
    latencies_ms: deque = field(default_factory=lambda: deque(maxlen=100_000))  # the latest
    connections: int = 0

    def summary(self) -> dict:
        import numpy as np

        lat = np.asarray(self.latencies_ms)
        return {
            "steps": self.steps, "samples": self.samples, "bad_messages": dict(self.bad),
            "skipped_poses": self.skipped_poses, "connections": self.connections,
            "latency_ms_p50": float(np.percentile(lat, 50)) if lat.size else None,
            "latency_ms_p99": float(np.percentile(lat, 99)) if lat.size else None,
        }  # fmt: skip


class LiveServer:
    """Serves one :class:`LiveSession` to any number of clients, one of which drives."""

    def __init__(self, session: LiveSession, control_hz: float, character: str) -> None:
        self.session, self.hz, self.character = session, float(control_hz), character
        self.clients: dict[object, Client] = {}
        self.driver: object | None = None
        self.stats = Stats()
        self._arrived = asyncio.Event()
        self._stop = asyncio.Event()

    async def handler(self, conn) -> None:
        from websockets.exceptions import ConnectionClosed

        me = Client()
        self.clients[conn] = me
        self.stats.connections += 1
        welcomed = False
        try:
            async for text in conn:
                try:
                    msg = parse(text)
                except BadMessage as exc:
                    self._bad(conn, type(exc).__name__, str(exc))
                    continue
                if isinstance(msg, Hello):
                    me.convention, me.rig = msg.convention, msg.rig
                    me.role = msg.role
                    if msg.role == "driver" and self.driver not in (None, conn):
                        me.role = "viewer"
                        await conn.send(json.dumps({"type": "error", "message": "another "
                                                    "client drives; you watch"}))  # fmt: skip
                    elif msg.role == "driver":
                        self.driver = conn
                    await conn.send(self._welcome(me))
                    welcomed = True
                    continue
                if not welcomed:
                    await conn.send(self._welcome(me))
                    welcomed = True
                self._sample(conn, me, msg)
        except ConnectionClosed:
            pass
        finally:
            self.clients.pop(conn, None)
            if self.driver is conn:
                self.driver = None

    def _welcome(self, me: Client) -> str:
        return json.dumps({"type": "welcome", "role": me.role, "convention": me.convention,
                           "control_hz": self.hz, "character": self.character,
                           "bodies": list(self.session.bodies)})  # fmt: skip

    def _bad(self, conn, kind: str, message: str) -> None:
        self.stats.bad[message.split(":")[0][:60]] += 1
        text = json.dumps({"type": "error", "message": message})
        asyncio.get_running_loop().create_task(_send(conn, text))

    def _sample(self, conn, me: Client, msg: Sample) -> None:
        if conn is not self.driver:
            why = "say hello as a driver first" if self.driver is None else "another client drives"
            self._bad(conn, "role", f"devices from a viewer: {why}")
            return
        if me.last_t is not None and msg.t <= me.last_t:
            self._bad(conn, "order", f"out of order: t {msg.t} after {me.last_t}")
            return
        me.last_t = msg.t
        try:
            self.session.push(msg.t, msg.poses, msg.tracked, me.convention, msg.images, me.rig)
        except ValueError as exc:  # calibration refused (a user not standing at the start)
            self._bad(conn, "calibration", f"calibration: {exc}")
            return
        self.stats.samples += 1
        self._arrived.set()

    async def run_clock(self) -> None:
        dt = 1.0 / self.hz
        last = time.perf_counter()
        while not self._stop.is_set():
            wait = max(0.0, last + 1.25 * dt - time.perf_counter())
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(self._arrived.wait(), timeout=wait)
            self._arrived.clear()
            early = last + 0.5 * dt - time.perf_counter()
            if early > 0:
                await asyncio.sleep(early)
            last = time.perf_counter()
            self._step()
            await asyncio.sleep(0)  # let receivers run between steps

    def _step(self) -> None:
        from retarget.errors import RetargetError

        session = self.session
        try:
            pose = session.step()
        except (RetargetError, PluginError) as exc:  # e.g. images of the wrong rig or size
            self.stats.bad[str(exc).split(":")[0][:60]] += 1
            for conn in list(self.clients):
                asyncio.get_running_loop().create_task(
                    _send(conn, json.dumps({"type": "error", "message": str(exc)})))
            session.images = None
            return
        used = session.used
        latency = None
        if used is not None:
            latency = (time.perf_counter() - used.arrived) * 1e3
        texts: dict[str, str] = {}  # one message per convention, whatever the client count
        for conn, me in list(self.clients.items()):
            transport = getattr(conn, "transport", None)
            if transport is not None and transport.get_write_buffer_size() > BACKLOG_BYTES:
                self.stats.skipped_poses += 1
                continue
            if me.convention not in texts:
                room = session.in_room(pose, me.convention)
                texts[me.convention] = pose_message(
                    session.steps, used.t if used else None, latency,
                    room["root"], room["body_pos"], room["body_quat"],
                )  # fmt: skip
            asyncio.get_running_loop().create_task(_send(conn, texts[me.convention]))
        if used is not None and latency is not None:
            self.stats.latencies_ms.append(latency)
            session.latest = None if session.latest is used else session.latest
        self.stats.steps += 1

    def stop(self) -> None:
        self._stop.set()


async def _send(conn, text: str) -> None:
    """Send, forgetting a socket that closed meanwhile (it leaves the client list itself)."""
    from websockets.exceptions import ConnectionClosed

    with contextlib.suppress(ConnectionClosed):
        await conn.send(text)


async def serve_forever(server: LiveServer, host: str, port: int, ready=None) -> None:
    """Run until :meth:`LiveServer.stop` (or Ctrl-C through the caller)."""
    from websockets.asyncio.server import serve

    async with serve(server.handler, host, port, max_size=64 * 1024, compression=None) as ws:
        if ready is not None:
            ready(ws)
        clock = asyncio.create_task(server.run_clock())
        try:
            await server._stop.wait()
        finally:
            clock.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await clock
