"""Does the avatar follow a person? A run driven, as a VR user drives it, by the headset and
controllers of held-out performers, calibrated on their standing start.

    python benchmarks/follow_recordings.py pretrained:human-three_point-student --max-clips 8
    python benchmarks/follow_recordings.py RUN --kinds walk --offsets 0,0.02,-0.02,0.05,-0.05
    python benchmarks/follow_recordings.py RUN --kinds walk,turn --offsets 0 --lose 0.25

For each held-out clip of the corpus (``heldout_eval.corpus_files``), set off from standing
still as a user does (the corpus's takes start mid-stride), the performer's own device
poses (:func:`retarget.motion.devices.device_poses` on the performer's skeleton, not on the
character's retargeted body) become a recording, which drives the run from a standing start
exactly as ``retarget play --input`` and ``retarget serve`` do
(:mod:`retarget.eval.recorded`): the character's size is calibrated once, from the first
headset height. ``--offsets`` then moves every device up or down by a few centimetres more (a
headset worn higher, a calibration taken slouching); ``--lose S`` makes each controller lose
tracking for S seconds every 3 s (the left from 2 s, the right from 3.5 s), held at its last
pose as a live session holds it, as a hand leaving the headset cameras' view does.
``retarget eval`` feeds devices taken from the retargeted reference instead, exact to the
millimetre; this measures what a user sees.

Figures per kind and offset: the share of clips followed to the end (the head never over
0.5 m from the headset, SimXR's rule), the mean head-to-headset distance (cm) and the mean time
until the headset was first lost (s; a clip's length when never). Prints a table, writes JSON.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from heldout_eval import KINDS, corpus_files


def performer_recording(path: Path, formats):
    """The device recording a performer's clip would have given (every device tracked),
    starting as a VR user starts, from standing: a take cut mid-stride is replaced by its own
    start from rest (:mod:`retarget.motion.rest_ends`, the whole take after the set-off), a
    take that never moves is used as it is; None when the take cannot start from standing
    (a run with no double support near its start). ``formats``: the motion readers
    (``retarget.load_plugins().motion_formats()``)."""
    from retarget.motion.clip_cache import read_cached
    from retarget.motion.device_recording import DeviceRecording
    from retarget.motion.devices import device_poses
    from retarget.motion.rest_ends import RestEnds, rest_ends, root_speed
    from retarget.motion.sources import reader_for

    clip = read_cached(reader_for(path, formats), path, None)
    ends = RestEnds()
    if root_speed(clip)[: round(ends.window * clip.fps)].mean() >= ends.min_speed:
        seconds = clip.num_frames / clip.fps
        start = None
        for keep in (seconds - 1.5, seconds - 2.5, ends.keep):  # the longest that fits
            made = rest_ends(clip, RestEnds(keep=max(keep, 0.0)))
            start = next((v for v in made if v.meta["rest_end"] == "from_rest"), None)
            if start is not None:
                break
        if start is None:
            return None
        clip = start
    poses = device_poses(clip.global_pos, clip.global_rot, clip.height)
    times = np.arange(len(poses)) / clip.fps
    return DeviceRecording(times, poses, np.ones(poses.shape[:2], dtype=bool))


def lose_controllers(recording, seconds: float, every: float = 3.0):
    """The recording with each controller untracked for ``seconds`` every ``every`` seconds
    (the left from 2 s, the right from 3.5 s)."""
    from retarget.motion.device_recording import DeviceRecording

    t = recording.time - recording.time[0]
    tracked = recording.tracked.copy()
    for device, first in ((1, 2.0), (2, 3.5)):
        phase = (t - first) % every
        tracked[:, device] &= ~((t >= first) & (phase < seconds))
    return DeviceRecording(recording.time, recording.poses, tracked)


def measure(run: str, recordings: dict, offset: float, sets: list[str], registry) -> dict:
    """Every recording (clip name -> recording) driven at once, one environment each, with
    every device ``offset`` metres higher."""
    from retarget.eval.recorded import drive_recordings, follow, follow_figures

    drive = drive_recordings(run, registry, list(recordings.values()), height_offset=offset,
                             changes={"assignments": list(sets)})  # fmt: skip
    hz = drive.loaded.env.sim.settings.control_hz
    per_clip = [follow_figures(g, hz) for g in follow(drive)]
    pooled = {k: float(np.mean([c[k] for c in per_clip])) for k in per_clip[0]}
    pooled["clips"] = len(recordings)
    pooled["per_clip"] = dict(zip(recordings, per_clip, strict=True))
    return pooled


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", help="run directories or pretrained:NAME")
    parser.add_argument("--style", default="normal", help="held-out style (default normal)")
    parser.add_argument("--kinds", default=",".join(KINDS), help="comma-separated kinds")
    parser.add_argument("--max-clips", type=int, default=8, help="at most this many per kind")
    parser.add_argument("--offsets", default="0,0.03,-0.03",
                        help="comma-separated extra device heights, m (default 0,0.03,-0.03)")
    parser.add_argument("--set", dest="sets", action="append", default=[],
                        help="recipe changes for the run (as retarget play --set)")
    parser.add_argument("--lose", type=float, default=0.0, metavar="S",
                        help="each controller loses tracking for S seconds every 3 s")
    parser.add_argument("--out", type=Path, help="JSON of every figure")
    args = parser.parse_args()
    offsets = [float(x) for x in args.offsets.split(",")]
    import retarget

    registry = retarget.load_plugins()
    formats = registry.motion_formats()
    recordings: dict[str, dict] = {}  # per kind: clip name -> recording (read once)
    for kind in args.kinds.split(","):
        files = corpus_files(args.style, kind, args.max_clips)
        if not files:
            print(f"no {kind} clips of style {args.style}", file=sys.stderr)
        made = {f.stem: performer_recording(f, formats) for f in files}
        recordings[kind] = {name: (lose_controllers(r, args.lose) if args.lose > 0 else r)
                            for name, r in made.items() if r is not None}  # fmt: skip
    results: dict[str, dict] = {}
    for run in args.runs:
        results[run] = {}
        lost = f", controllers lost {args.lose:g} s every 3 s" if args.lose > 0 else ""
        print(f"\n{run}: held-out style '{args.style}', devices of the performers{lost}")
        print(f"{'kind':8} {'offset cm':>9} {'clips':>5} {'followed':>8} {'gap cm':>7} "
              f"{'lost at s':>9} {'of s':>6} {'wall s':>6}")  # fmt: skip
        for kind, named in recordings.items():
            if not named:
                print(f"{kind:8} no clip of this kind starts from standing")
                continue
            for offset in offsets:
                t0 = time.perf_counter()
                r = measure(run, named, offset, args.sets, registry)
                results[run][f"{kind} {offset:+.3f}"] = r
                print(f"{kind:8} {100 * offset:9.1f} {r['clips']:5d} {r['followed']:8.2f} "
                      f"{r['gap_cm']:7.1f} {r['lost_at_s']:9.1f} {r['seconds']:6.1f} "
                      f"{time.perf_counter() - t0:6.0f}", flush=True)  # fmt: skip
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
