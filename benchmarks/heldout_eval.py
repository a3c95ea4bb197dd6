"""A run (or shipped model) measured on a held-out style of the Bandai Namco corpus, by kind
of motion, with PHC's protocol (one run per clip, first frame to last) beside the project's
figures.

    python benchmarks/heldout_eval.py RUN [RUN ...] --style normal --out results.json
    python benchmarks/heldout_eval.py pretrained:human-teacher --kinds walk,run --max-clips 20
    python benchmarks/heldout_eval.py RUN --kinds walk,turn --rest-ends   # set off and stop
    python benchmarks/heldout_eval.py RUN --kinds run --by-speed 3        # slow .. fast clips

The corpus is ``../shared/data/mocap_corpus`` (or ``$RETARGET_SHARED_DATA/mocap_corpus``); a
run must not have trained on ``--style`` (the packaged corpus recipes hold ``normal`` out).
Each kind is one ``retarget eval --protocol phc`` on the clips of that kind and style, so its
figures pool the kind's seconds exactly. ``--max-clips`` takes every k-th clip of a kind to
keep a quick look short. ``--rest-ends`` measures, instead of each clip, its start from
standing still and its stop (``retarget.motion.rest_ends``: the held-out take's own poses,
time-warped), which the corpus's takes, cut mid-stride, never show. ``--by-speed K`` also
splits each kind's clips into K groups by the performer's mean ground speed (the same number
of clips each, slowest first) and prints the PHC figures per group: where a policy loses a
kind, whether it is the fast takes. Prints one table per run and writes every figure as JSON.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from retarget.motion.shared_data import shared_data

KINDS = {
    "walk": ["walk"],
    "turn": ["walk-turn-left", "walk-turn-right"],
    "run": ["run"],
    "gesture": ["wave-both-hands", "wave-left-hand", "wave-right-hand", "raise-up-both-hands",
                "raise-up-left-hand", "raise-up-right-hand"],
}  # fmt: skip
FIGURES = ("phc_success", "phc_mpjpe_mm", "phc_g_mpjpe_mm", "phc_pa_mpjpe_mm",
           "phc_accel_mm_f2", "phc_vel_mm_f", "phc_g_mpjpe_mm_succ", "success_frame",
           "falls_per_min", "headset_cm", "controller_cm", "hands_to_controllers_cm",
           "mpjpe_mm", "runs")  # fmt: skip


def corpus_files(style: str, kind: str, max_clips: int | None) -> list[Path]:
    """The corpus's clips of one kind and style (unpacked from the archives once)."""
    from retarget.motion.sources import resolve_motion_source, select

    files = resolve_motion_source(shared_data("mocap_corpus"), (".bvh",)) or []
    chosen = select(files, [f"*_{c}_{style}_*" for c in KINDS[kind]])
    if max_clips and len(chosen) > max_clips:
        step = len(chosen) / max_clips
        chosen = [chosen[int(i * step)] for i in range(max_clips)]
    return chosen


def write_rest_ends(files: list[Path], folder: Path, which: str = "both") -> int:
    """The start-from-rest and stop variants of ``files`` (``which``: ``from_rest``,
    ``to_rest`` or ``both``) written to ``folder`` as BVH."""
    import retarget
    from retarget.motion.bvh_write import write_bvh
    from retarget.motion.clip_cache import read_cached
    from retarget.motion.rest_ends import rest_ends
    from retarget.motion.sources import reader_for

    formats = retarget.load_plugins().motion_formats()
    count = 0
    for f in files:
        for variant in rest_ends(read_cached(reader_for(f, formats), f, None)):
            if which != "both" and variant.meta["rest_end"] != which:
                continue
            write_bvh(variant, folder / f"{variant.name}.bvh")
            count += 1
    return count


def evaluate(
    run: str,
    files: list[Path],
    num_envs: int,
    sets: list[str] = (),
    checkpoint: str | None = None,
    rest: str | None = None,
    whole: bool = False,
) -> dict:
    """``retarget eval --protocol phc`` over ``files`` (linked into one folder), or over
    their rest-end variants (``rest``: which, see :func:`write_rest_ends`): its overall
    figures, or (``whole``) its whole report, per clip included."""
    folder = Path(tempfile.mkdtemp(prefix="heldout-"))
    try:
        if rest:
            if not write_rest_ends(files, folder, rest):
                return {"runs": 0}
        else:
            for f in files:
                (folder / f.name).symlink_to(f.resolve())
        report = folder / "eval.json"
        cmd = [sys.executable, "-m", "retarget", "eval", run, "--motions", str(folder),
               "--protocol", "phc", "--num-envs", str(num_envs), "--json", str(report),
               *(f"--set={a}" for a in sets),
               *(["--checkpoint", checkpoint] if checkpoint else [])]  # fmt: skip
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        result = json.loads(report.read_text())
        return result if whole else result["overall"]
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def ground_speed(path: Path, formats) -> float:
    """The performer's mean horizontal root speed over a clip, m/s (its own size);
    ``formats``: the motion readers (``retarget.load_plugins().motion_formats()``)."""
    from retarget.motion.clip_cache import read_cached
    from retarget.motion.rest_ends import root_speed
    from retarget.motion.sources import reader_for

    return float(root_speed(read_cached(reader_for(path, formats), path, None)).mean())


def by_speed(files: list[Path], clips: dict[str, dict], groups: int) -> list[dict[str, float]]:
    """Per-clip figures ``clips`` (``retarget eval``'s, keyed by file stem) pooled over
    ``groups`` groups of ``files`` by ground speed, slowest first (clips weigh equally)."""
    import numpy as np

    import retarget

    formats = retarget.load_plugins().motion_formats()
    speeds = sorted((ground_speed(f, formats), f.stem) for f in files if f.stem in clips)
    out = []
    for part in np.array_split(np.arange(len(speeds)), groups):
        if not len(part):
            continue
        chosen = [speeds[i] for i in part]
        row = {"speed_from": chosen[0][0], "speed_to": chosen[-1][0], "clips": len(chosen)}
        for k in ("phc_success", "phc_mpjpe_mm", "phc_g_mpjpe_mm", "falls_per_min", "headset_cm"):
            values = [clips[name][k] for _, name in chosen if clips[name].get(k) is not None]
            row[k] = float(np.mean(values)) if values else float("nan")
        out.append(row)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", help="run directories or pretrained:NAME")
    parser.add_argument("--style", default="normal", help="held-out style (default normal)")
    parser.add_argument("--kinds", default=",".join(KINDS), help="comma-separated kinds")
    parser.add_argument("--max-clips", type=int, default=None, help="at most this many per kind")
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--out", type=Path, help="JSON of every figure")
    parser.add_argument("--checkpoint", help="a checkpoint file of the (one) run")
    parser.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        help="passed to retarget eval (e.g. algorithm.reach_controllers=false)",
    )
    parser.add_argument(
        "--rest-ends",
        nargs="?",
        const="both",
        choices=("both", "from_rest", "to_rest"),
        help="measure each clip's start from (from_rest) and/or stop to "
        "(to_rest) standing still instead of the clip",
    )
    parser.add_argument(
        "--by-speed",
        type=int,
        default=0,
        metavar="K",
        help="also pool each kind's clips in K groups by ground speed",
    )
    args = parser.parse_args()
    if args.by_speed < 0 or (args.by_speed and args.rest_ends):
        parser.error("--by-speed takes a positive count and measures the clips themselves")
    speed_tables: dict[str, dict[str, list[dict[str, float]]]] = {}
    results: dict[str, dict[str, dict[str, float]]] = {}
    for run in args.runs:
        results[run] = {}
        for kind in args.kinds.split(","):
            files = corpus_files(args.style, kind, args.max_clips)
            if not files:
                print(f"no {kind} clips of style {args.style}", file=sys.stderr)
                continue
            report = evaluate(
                run, files, args.num_envs, args.sets, args.checkpoint, args.rest_ends, whole=True
            )
            overall = report["overall"]
            results[run][kind] = {k: overall[k] for k in FIGURES if k in overall}
            results[run][kind]["clips"] = len(files)
            if args.by_speed:
                table = by_speed(files, report.get("clips", {}), args.by_speed)
                results[run][kind]["by_speed"] = table
                speed_tables.setdefault(run, {})[kind] = table
        made = f" (rest ends: {args.rest_ends})" if args.rest_ends else ""
        print(f"\n{run} on held-out style '{args.style}'{made}")
        print(f"{'kind':8} {'clips':>5} " + " ".join(f"{k[:14]:>14}" for k in FIGURES[:-1]))
        for kind, figures in results[run].items():
            cells = " ".join(f"{figures.get(k, float('nan')):14.3f}" for k in FIGURES[:-1])
            print(f"{kind:8} {figures['clips']:5d} {cells}")
        for kind, table in speed_tables.get(run, {}).items():
            print(
                f"\n{kind} by the performer's ground speed (m/s): clips, success, MPJPE mm, "
                "G-MPJPE mm, falls/min, headset cm"
            )
            for r in table:
                print(
                    f"  {r['speed_from']:4.2f}-{r['speed_to']:4.2f} {r['clips']:4d} "
                    f"{r['phc_success']:6.3f} {r['phc_mpjpe_mm']:7.1f} "
                    f"{r['phc_g_mpjpe_mm']:7.1f} {r['falls_per_min']:6.2f} "
                    f"{r['headset_cm']:6.1f}"
                )
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
