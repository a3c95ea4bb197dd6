"""End-to-end latency of ``retarget serve`` over loopback, and a soak with bad input.

Run: ``.venv/bin/python benchmarks/live_latency.py RUN [--recording REC.jsonl] [--viewers 4]
[--repeat 3] [--soak-minutes 0]``

The server runs in this process (its own thread and event loop, torch on one thread); the
recording is streamed at real speed by the reference client (``retarget stream``, another
process) with
``--viewers`` extra watching connections. Reported: the server's latency (sample arrival to
its pose message), the client's round trip (send to pose received), samples that got no pose
of their own (``unanswered``: a newer sample won), poses viewers missed, CPU seconds per
simulated second. ``--soak-minutes`` then streams for that long with 5 % malformed messages
and a reconnect every 20 s, and prints memory at the start and end and every bad message the
server counted.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import torch

from retarget.cli.serve_cmd import build_server
from retarget.live.server import serve_forever
from retarget.registry.loader import load_plugins

REPO = Path(__file__).resolve().parents[1]


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def start(run: str):
    server = build_server(run, load_plugins())
    box: dict = {}
    ready = threading.Event()

    def main() -> None:
        def on_ready(ws) -> None:
            box["port"] = next(iter(ws.sockets)).getsockname()[1]
            ready.set()

        box["loop"] = asyncio.new_event_loop()
        box["loop"].run_until_complete(serve_forever(server, "127.0.0.1", 0, on_ready))

    thread = threading.Thread(target=main, daemon=True)
    thread.start()
    ready.wait(120)
    return server, f"ws://127.0.0.1:{box['port']}", lambda: box["loop"].call_soon_threadsafe(
        server.stop
    )


async def drain(conn) -> None:
    """Read the poses a connection receives (a client that does not read is backed up)."""
    async for _ in conn:
        pass


async def soak(url: str, recording: Path, minutes: float) -> dict:
    from websockets.asyncio.client import connect

    from retarget.motion.device_recording import read_recording
    from retarget.motion.devices import DEVICES

    rec = read_recording(recording)
    rng = random.Random(0)
    sent = bad = reconnects = 0
    end = time.perf_counter() + 60 * minutes
    t = 0.0
    while time.perf_counter() < end:
        async with connect(url) as conn:
            reader = asyncio.create_task(drain(conn))
            await conn.send(json.dumps({"type": "hello", "role": "driver"}))
            until = time.perf_counter() + 20.0
            k = 0
            while time.perf_counter() < min(until, end):
                k = (k + 1) % len(rec.time)
                t += 1 / 72
                if rng.random() < 0.05:
                    junk = rng.choice(["{", "[]", '{"type": "devices"}', '{"type": "x"}',
                                       json.dumps({"type": "devices", "t": t, "hmd": [1]})])
                    await conn.send(junk)
                    bad += 1
                else:
                    msg = {"type": "devices", "t": t}
                    for d, name in enumerate(DEVICES):
                        msg[name] = rec.poses[k, d].tolist()
                    await conn.send(json.dumps(msg))
                    sent += 1
                await asyncio.sleep(1 / 72)
            reader.cancel()
        reconnects += 1
    return {"sent": sent, "bad_sent": bad, "reconnects": reconnects}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run")
    parser.add_argument("--recording",
                        default=str(REPO / "examples/recordings/walk_openxr.jsonl"))
    parser.add_argument("--viewers", type=int, default=4)
    parser.add_argument("--rate", type=float, default=None,
                        help="resample the recording to this many samples/s (a headset's "
                        "rate; default: as recorded)")  # fmt: skip
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--soak-minutes", type=float, default=0.0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    recording = args.recording
    if args.rate:
        from retarget.motion.device_recording import (
            DeviceRecording,
            read_recording,
            write_recording,
        )
        from retarget.motion.device_stream import resample_stream

        poses = resample_stream(read_recording(recording), args.rate)
        times = np.arange(len(poses)) / args.rate
        recording = f"/tmp/live_latency_{os.getpid()}_{args.rate:g}hz.jsonl"
        write_recording(recording, DeviceRecording(times, poses, np.ones(poses.shape[:2], bool)))
    args.recording = recording
    server, url, stop = start(args.run)
    print(f"{args.run}: {server.character}, {server.hz:.0f} Hz, {args.viewers} viewers, "
          f"{Path(args.recording).name}")
    for k in range(args.repeat):
        steps0 = server.stats.steps
        cpu0, wall0 = time.process_time(), time.perf_counter()
        server.stats.latencies_ms.clear()
        # the client in its own process, as a headset application would be
        out_json = Path(f"/tmp/live_latency_{os.getpid()}.json")
        subprocess.run([str(Path(sys.executable).parent / "retarget"), "stream", args.recording,
                        "--to", url, "--viewers", str(args.viewers), "--json", str(out_json)],
                       check=True, capture_output=True)  # fmt: skip
        stats = json.loads(out_json.read_text())
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        steps = server.stats.steps - steps0
        summary = server.stats.summary()
        missed = stats["poses"] * args.viewers - stats["viewer_poses"]  # vs what the driver got
        print(f"run {k + 1}: {stats['samples']} samples in {stats['seconds']:.1f} s, "
              f"{steps} steps; server p50 {summary['latency_ms_p50']:.2f} ms p99 "
              f"{summary['latency_ms_p99']:.2f} ms; "
              f"round trip p50 {stats['round_trip_ms_p50']:.2f} ms p99 "
              f"{stats['round_trip_ms_p99']:.2f} ms; unanswered samples "
              f"{stats['unanswered_samples']}; viewer poses missed {missed}; errors "
              f"{stats['errors']}; CPU {cpu / wall:.2f} cores")
    if args.soak_minutes > 0:
        before = rss_mb()
        out = asyncio.run(soak(url, Path(args.recording), args.soak_minutes))
        summary = server.stats.summary()
        print(f"soak {args.soak_minutes:g} min: {out}; server counted "
              f"{sum(summary['bad_messages'].values())} bad messages "
              f"({summary['bad_messages']}); RSS {before:.0f} -> {rss_mb():.0f} MB; "
              f"{summary['steps']} steps, {summary['connections']} connections")
    stop()


if __name__ == "__main__":
    main()
