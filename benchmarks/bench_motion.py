"""Motion pipeline: reading the shared clips, and sampling reference batches vs. physics.

Run: ``.venv/bin/python benchmarks/bench_motion.py [--clips DIR] [--threads T]``

1. Reading: every BVH clip in ``--clips`` (default ``../shared/data/mocap``) parsed, mapped onto
   the canonical skeleton, floor-aligned and contact-labelled; then one library at 36 Hz.
2. Sampling: per control step the environment draws (clip, frame) for the environments that
   reset and gathers the reference window. Timed for N = 256 and 4096 with a 1 s window
   (37 frames at 36 Hz), both for the device window alone (what the sensors need) and for every
   field over the whole window (an upper bound), and compared with one physics control step of
   the project's human character for the same N on ``BatchedSim`` (36 Hz, default substeps),
   measured in the same run: the ratio is what matters, not the absolute times.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from retarget.motion.import_bvh import load_bvh
from retarget.motion.library import MotionLibrary, window_offsets
from retarget.motion.shared_data import require_clips, shared_data

REPO = Path(__file__).resolve().parents[1]


def timed(fn, repeat: int) -> float:
    fn()
    start = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - start) / repeat


def control_step_seconds(n: int, threads: int) -> tuple[float, str]:
    from retarget.plugins.characters.human import Human
    from retarget.sim import BatchedSim, SimSettings
    from retarget.sim.world import build_world

    world = build_world(Human())
    settings = SimSettings(threads=threads)
    sim = BatchedSim(world.model, world.layout, n, settings)
    rng = np.random.default_rng(0)
    actions = torch.from_numpy(rng.uniform(-0.2, 0.2, (n, sim.layout.nu)).astype(np.float32))
    seconds = timed(lambda: sim.step(actions), 5 if n > 1000 else 20)
    return seconds, f"human, {settings.substeps} substeps of {settings.timestep * 1e3:.2f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=Path, default=shared_data("mocap"))
    parser.add_argument("--threads", type=int, default=0, help="physics threads (0: all)")
    args = parser.parse_args()
    require_clips(args.clips)  # before any work: the data is there
    torch.set_num_threads(max(1, torch.get_num_threads()))

    files = sorted(args.clips.glob("*.bvh"))
    if not files:
        raise SystemExit(f"no .bvh files in {args.clips}")
    start = time.perf_counter()
    clips = [load_bvh(f) for f in files]
    read_s = time.perf_counter() - start
    frames = sum(c.num_frames for c in clips)
    seconds = sum(c.duration for c in clips)
    print(f"read {len(files)} clips ({frames} frames, {seconds:.0f} s of motion, "
          f"{sum(f.stat().st_size for f in files) / 2**20:.1f} MiB) in {read_s:.2f} s "
          f"= {read_s / len(files) * 1e3:.0f} ms/clip, {frames / read_s:,.0f} frames/s")
    start = time.perf_counter()
    lib = MotionLibrary(clips, fps=36.0, mirrored=True)
    print(f"library at 36 Hz incl. mirrored copies: {lib.num_clips} clips, {lib.num_frames} "
          f"frames, built in {time.perf_counter() - start:.2f} s")

    offsets = window_offsets(1.0, 36.0)
    g = torch.Generator().manual_seed(0)
    print(f"\nreference batch, 1 s window = {len(offsets)} frames; torch threads "
          f"{torch.get_num_threads()}")
    print(f"{'N':>6} {'physics step':>13} {'sample':>9} {'devices win':>12} {'all fields':>11}"
          f" {'dev/phys':>9} {'all/phys':>9}")
    for n in (256, 4096):
        phys, what = control_step_seconds(n, args.threads)
        clip, frame = lib.sample(n, g)
        sample = timed(lambda n=n: lib.sample(n, g), 50)
        dev = timed(lambda c=clip, f=frame: lib.window(c, f, offsets, fields=("devices",)), 50)
        full = timed(lambda c=clip, f=frame: lib.window(c, f, offsets), 10)
        print(f"{n:>6} {phys * 1e3:>10.2f} ms {sample * 1e3:>6.3f} ms {dev * 1e3:>9.3f} ms "
              f"{full * 1e3:>8.2f} ms {(sample + dev) / phys:>9.4f} {(sample + full) / phys:>9.3f}")
    print(f"\nphysics: {what}; sampling includes drawing (clip, frame) for all N envs")


if __name__ == "__main__":
    main()
