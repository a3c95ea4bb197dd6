"""An expert directory: what ``retarget expert`` wrote, read back without trusting it.

    DIR/expert.json          character, the recipe and planner settings, format version
    DIR/motions/FILE         a copy of every planned clip (a student replays the same clips)
    DIR/clips/NAME.npz       the best path (qpos, qvel, actions, body positions) and the
                             beam's other members (``demo_*``)
    DIR/clips/NAME.json      that clip's figures (success, MPJPE, CPU-seconds) and source
    DIR/report.json          every clip's figures and their summary

Arrays are ``.npz`` read with ``allow_pickle=False``; every shape is checked against the
environment that reads them, and sizes are bounded, so a hostile directory is refused with
its file named instead of allocating or executing anything.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from retarget.errors import RecipeError
from retarget.expert.config import ADDED_LATER, BEAM_IN_ILQR_ADDED_LATER, ILQR_ADDED_LATER
from retarget.kinds.track import Track

VERSION = 1
HEADER = "expert.json"
MAX_ROWS = 10_000_000
"""Frames or demonstration rows one clip file may hold (about 90 hours at 36 Hz)."""
_SAFE = re.compile(r"[^A-Za-z0-9._-]")


def clip_name(path: Path, taken: set[str]) -> str:
    """A file-name-safe, unique name for the clip read from ``path``."""
    base = _SAFE.sub("_", path.stem)[:80] or "clip"
    name = base
    if name in taken:
        name = f"{base}-{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"
    taken.add(name)
    return name


LATER_BY_PART: dict[str | None, dict[str, object]] = {
    None: ADDED_LATER, "ilqr": ILQR_ADDED_LATER, "beam": BEAM_IN_ILQR_ADDED_LATER,
}
"""Fields added later, by where a header's planner settings hold them (None: the top level,
``beam``'s own; ``ilqr`` and ``beam``: ``beam_ilqr``'s parts)."""


def settings_key(header: Mapping[str, Any]) -> str:
    """Hash of what decides a clip's plan (recipe, planner and its settings); planner fields
    of :data:`ADDED_LATER` (the refinement's: ``ILQR_ADDED_LATER``) at their old behaviour's
    value are left out, and so is the planner when it is ``beam`` (directories written before
    planners were plugins)."""
    planner = dict(header["planner"])
    for part, later in LATER_BY_PART.items():
        node = planner if part is None else planner.get(part)
        if isinstance(node, dict):
            kept = {k: v for k, v in node.items() if k not in later or v != later[k]}
            planner = kept if part is None else {**planner, part: kept}
    decides: dict[str, Any] = {"recipe": header["recipe"], "planner": planner}
    if header.get("method", "beam") != "beam":
        decides["method"] = header["method"]
    blob = json.dumps(decides, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def _flat(tree: Any, prefix: str = "") -> dict[str, Any]:
    """Nested settings as ``{"a.b.c": value}``, so two headers compare field by field."""
    if not isinstance(tree, Mapping):
        return {prefix: tree}
    out: dict[str, Any] = {}
    for k, v in tree.items():
        out.update(_flat(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


def differences(old: Mapping[str, Any], new: Mapping[str, Any], limit: int = 6) -> list[str]:
    """What a directory's header ``old`` recorded that ``new`` sets otherwise, as
    ``planner.FIELD: OLD in the directory, NEW now`` (at most ``limit``); a planner field the
    directory predates counts at the value it planned with."""
    before = {".".join(filter(None, ("planner", part, k))): v
              for part, later in LATER_BY_PART.items() for k, v in later.items()}
    a = _flat({"method": old.get("method", "beam"), "recipe": old.get("recipe"),
               "planner": old.get("planner")})  # fmt: skip
    b = _flat({"method": new.get("method", "beam"), "recipe": new.get("recipe"),
               "planner": new.get("planner")})  # fmt: skip
    missing = object()
    lines = []
    for key in sorted(set(a) | set(b)):
        was, now = a.get(key, before.get(key, missing)), b.get(key, before.get(key, missing))
        if was != now:
            lines.append(f"{key}: {'(none)' if was is missing else json.dumps(was)} in the "
                         f"directory, {'(none)' if now is missing else json.dumps(now)} now")
    return lines[:limit] + ([f"and {len(lines) - limit} more"] if len(lines) > limit else [])


def write_header(out: Path, header: dict[str, Any]) -> None:
    """Start ``out`` or check that it was started with the same settings (resume)."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "clips").mkdir(exist_ok=True)
    (out / "motions").mkdir(exist_ok=True)
    file = out / HEADER
    header = {**header, "version": VERSION, "key": settings_key(header)}
    if file.exists():
        old = read_header(out)
        if old["key"] != header["key"]:
            changed = differences(old, header)
            raise RecipeError(
                "was planned with other recipe or planner settings"
                + (f": {'; '.join(changed)}" if changed else ""),
                file=str(file), hint="resume with the same settings (--planner KEY=VALUE, "
                "--set PATH=VALUE), or use another --out",
            )
        return
    file.write_text(json.dumps(header, indent=2, sort_keys=True), encoding="utf-8")


def read_header(out: Path) -> dict[str, Any]:
    file = Path(out) / HEADER
    try:
        header = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RecipeError(f"not an expert directory: {exc}", file=str(file)) from None
    if not isinstance(header, dict) or header.get("version") != VERSION or not isinstance(
        header.get("recipe"), dict
    ):
        raise RecipeError(f"not an expert directory of version {VERSION}", file=str(file))
    return header


def write_track(out: Path, name: str, track: Track, meta: Mapping[str, Any]) -> dict[str, Any]:
    """The clip's arrays and figures; the figures file is written last, so a clip counts as
    done (and is skipped on resume) only when both are complete."""
    arrays = {
        "qpos": track.qpos, "qvel": track.qvel, "actions": track.actions,
        "body_pos": track.body_pos, "ref_body_pos": track.ref_body_pos,
        "ref_qpos0": track.ref_qpos0, "fps": np.array(track.fps),
        **{f"demo_{k}": v for k, v in track.demos.items()},
    }
    tmp = out / "clips" / f".{name}.npz.part"
    with open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    tmp.replace(out / "clips" / f"{name}.npz")
    figures = {"clip": track.clip, **track.metrics(), **meta}
    part = out / "clips" / f".{name}.json.part"
    part.write_text(json.dumps(figures, indent=2), encoding="utf-8")
    part.replace(out / "clips" / f"{name}.json")
    return figures


def done_clips(out: Path, key: str) -> dict[str, dict[str, Any]]:
    """Figures of the clips already planned with settings ``key``."""
    done = {}
    for file in sorted((out / "clips").glob("*.json")):
        try:
            figures = json.loads(file.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            continue  # an unreadable record is planned again
        if isinstance(figures, dict) and figures.get("key") == key and (
            out / "clips" / f"{file.stem}.npz"
        ).exists():
            done[file.stem] = figures
    return done


def summarize(figures: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """Means over clips (motion-second weighted CPU cost)."""
    rows = list(figures.values())
    if not rows:
        return {"clips": 0}
    seconds = sum(r["motion_seconds"] for r in rows)
    return {
        "clips": len(rows),
        "motion_seconds": seconds,
        "success_clip": float(np.mean([r["success_clip"] for r in rows])),
        "mpjpe_mm": float(np.mean([r["mpjpe_mm"] for r in rows])),
        "g_mpjpe_mm": float(np.mean([r["g_mpjpe_mm"] for r in rows])),
        "cpu_s_per_motion_s": sum(r["cpu_seconds"] for r in rows) / max(seconds, 1e-9),
    }


def write_report(out: Path, figures: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    report = {"summary": summarize(figures), "clips": dict(figures)}
    part = out / ".report.json.part"
    part.write_text(json.dumps(report, indent=2), encoding="utf-8")
    part.replace(out / "report.json")
    return report


def load_track(file: Path, *, nq: int, nv: int, nu: int, state_shapes: Mapping[str, tuple]
               ) -> dict[str, np.ndarray]:
    """One clip's arrays, checked: ``nq``/``nv`` of the whole model, ``nu`` actions and the
    per-row shapes of the simulator state fields (``BatchedSim.STATE_FIELDS``)."""
    def bad(why: str) -> RecipeError:
        return RecipeError(f"expert data refused: {why}", file=str(file))

    try:
        with np.load(file, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError) as exc:
        raise bad(str(exc)) from None
    need = {"qpos": (nq,), "qvel": (nv,), "actions": (nu,), "demo_frame": (),
            "demo_prev_action": (nu,), "demo_steps": ()}
    need.update({f"demo_state_{k}": s for k, s in state_shapes.items()})
    for key, tail in need.items():
        if key not in data:
            raise bad(f"no '{key}' array")
        arr = data[key]
        wrong = arr.ndim != len(tail) + 1 or tuple(arr.shape[1:]) != tuple(tail)
        if wrong or len(arr) > MAX_ROWS:
            want = ", ".join(map(str, tail))
            raise bad(f"'{key}' has shape {arr.shape}, expected (rows, {want})")
        if arr.dtype.kind not in "fiu":
            raise bad(f"'{key}' is not numeric")
    acts = data.get("demo_actions")
    rows = len(data["demo_frame"])
    if acts is None or acts.ndim != 3 or acts.shape[0] != rows or acts.shape[2] != nu:
        raise bad("'demo_actions' does not match the demonstrations")
    if len(data["actions"]) != len(data["qpos"]) - 1:
        raise bad("'actions' must have one row fewer than 'qpos'")
    frames = len(data["qpos"])
    steps = data["demo_steps"]
    if rows and (data["demo_frame"].min() < 0 or (data["demo_frame"] + steps).max() >= frames
                 or steps.min() < 1 or steps.max() > acts.shape[1]):
        raise bad("demonstration frames fall outside the clip")
    for key, arr in data.items():
        if arr.dtype.kind == "f" and not np.isfinite(arr).all():
            raise bad(f"'{key}' holds non-finite values")
    return data
