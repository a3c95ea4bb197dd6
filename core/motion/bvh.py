"""BVH files: a strict parser and the source skeleton's forward kinematics.

The parser accepts what real exporters write (per-joint channel orders, position channels on
any joint, tabs or spaces, ``Frames:`` with or without a space, CRLF) and rejects everything
else with a :class:`retarget.errors.MotionError` naming the file and line: a half-read clip
silently trained on is far more expensive than a clear error. It never raises anything else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.geometry import rotations as rot

CHANNEL_NAMES = {
    "xposition": "Xposition",
    "yposition": "Yposition",
    "zposition": "Zposition",
    "xrotation": "Xrotation",
    "yrotation": "Yrotation",
    "zrotation": "Zrotation",
}
MIN_FRAME_TIME = 1e-4
"""Shortest frame time read, seconds (10 kHz; motion capture runs at 30-480 Hz)."""
MAX_FRAME_TIME = 1.0
"""Longest frame time read, seconds: slower than 1 Hz is not motion capture, and resampling it
to the control rate would allocate without bound."""
MAX_SECONDS = 3 * 3600.0
"""Longest clip read (frames x frame time), seconds."""
MAX_JOINTS = 1024
MAX_CHANNELS_PER_JOINT = 6


@dataclass
class BvhJoint:
    name: str
    parent: int  # -1 for the root
    offset: np.ndarray  # (3,) in file units
    channels: tuple[str, ...]  # canonical spelling, file order
    line: int
    end_site: np.ndarray | None = None  # offset of the first End Site below this joint

    @property
    def rotation_order(self) -> str:
        """Rotation axes in channel order, e.g. ``"zxy"`` (empty when not rotated)."""
        return "".join(c[0].lower() for c in self.channels if c.endswith("rotation"))


@dataclass
class BvhData:
    """A parsed BVH file: hierarchy, frame time and the raw channel values per frame."""

    joints: list[BvhJoint]
    frame_time: float
    values: np.ndarray  # (F, C) floats in file order
    path: Path | None = None
    channel_start: list[int] = field(default_factory=list)

    @property
    def names(self) -> list[str]:
        return [j.name for j in self.joints]

    @property
    def parents(self) -> list[int]:
        return [j.parent for j in self.joints]

    @property
    def num_frames(self) -> int:
        return int(self.values.shape[0])

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time


class _Tokens:
    """Whitespace tokens of the header with their 1-based line numbers."""

    def __init__(self, lines: list[str], file: str) -> None:
        self.items: list[tuple[str, int]] = []
        for number, line in enumerate(lines, start=1):
            for tok in line.split():
                self.items.append((tok, number))
        self.pos = 0
        self.file = file
        self.last_line = len(lines)

    def error(self, message: str, line: int | None = None) -> MotionError:
        if line is None:
            line = self.items[self.pos][1] if self.pos < len(self.items) else self.last_line
        return MotionError(message, file=self.file, line=line)

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def next(self, what: str) -> tuple[str, int]:
        if self.pos >= len(self.items):
            raise self.error(f"unexpected end of file, expected {what}")
        item = self.items[self.pos]
        self.pos += 1
        return item

    def expect(self, word: str) -> int:
        tok, line = self.next(repr(word))
        if tok.upper() != word.upper():
            raise self.error(f"expected {word!r}, found {tok!r}", line)
        return line

    def number(self, what: str) -> float:
        tok, line = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise self.error(f"expected a number for {what}, found {tok!r}", line) from None
        if not math.isfinite(value):
            raise self.error(f"{what} is not finite ({tok!r})", line)
        return value

    def integer(self, what: str) -> int:
        tok, line = self.next(what)
        try:
            return int(tok)
        except ValueError:
            raise self.error(f"expected an integer for {what}, found {tok!r}", line) from None


def _parse_hierarchy(tokens: _Tokens) -> list[BvhJoint]:
    tokens.expect("HIERARCHY")
    tok, line = tokens.next("'ROOT'")
    if tok.upper() != "ROOT":
        raise tokens.error(f"expected 'ROOT', found {tok!r}", line)
    joints: list[BvhJoint] = []
    seen: dict[str, int] = {}
    # explicit stack of open joints instead of recursion: deep files cannot blow the stack
    stack: list[int] = []
    pending_name: tuple[str, int] | None = tokens.next("joint name")
    pending_parent = -1
    while True:
        if pending_name is not None:
            name, line = pending_name
            if name == "{":
                raise tokens.error("joint has no name", line)
            if name in seen:
                raise tokens.error(
                    f"duplicate joint name {name!r} (first defined on line "
                    f"{joints[seen[name]].line}); joint names must be unique",
                    line,
                )
            if len(joints) >= MAX_JOINTS:
                raise tokens.error(f"more than {MAX_JOINTS} joints", line)
            tokens.expect("{")
            tokens.expect("OFFSET")
            offset = np.array(
                [tokens.number("OFFSET x"), tokens.number("OFFSET y"), tokens.number("OFFSET z")]
            )
            channels: tuple[str, ...] = ()
            if (tokens.peek() or "").upper() == "CHANNELS":
                tokens.next("'CHANNELS'")
                count_line = tokens.items[tokens.pos][1] if tokens.peek() else tokens.last_line
                count = tokens.integer("channel count")
                if not 0 <= count <= MAX_CHANNELS_PER_JOINT:
                    raise tokens.error(f"channel count {count} not in 0..6", count_line)
                names = []
                for i in range(count):
                    tok, cline = tokens.next(f"channel name {i + 1} of {count}")
                    canon = CHANNEL_NAMES.get(tok.lower())
                    if canon is None:
                        raise tokens.error(
                            f"CHANNELS {count} lists {i} channel name(s), then {tok!r} "
                            f"(expected one of {', '.join(CHANNEL_NAMES.values())})",
                            cline,
                        )
                    names.append(canon)
                if len(set(names)) != len(names):
                    raise tokens.error(f"repeated channel in {names}", count_line)
                channels = tuple(names)
            elif pending_parent == -1:
                raise tokens.error("root joint has no CHANNELS")
            joints.append(BvhJoint(name, pending_parent, offset, channels, line))
            seen[name] = len(joints) - 1
            stack.append(len(joints) - 1)
            pending_name = None
        tok, line = tokens.next("'JOINT', 'End Site' or '}'")
        upper = tok.upper()
        if upper == "JOINT":
            pending_parent = stack[-1]
            pending_name = tokens.next("joint name")
        elif upper == "END":
            tok2, line2 = tokens.next("'Site'")
            if tok2.upper() != "SITE":
                raise tokens.error(f"expected 'Site' after 'End', found {tok2!r}", line2)
            tokens.expect("{")
            tokens.expect("OFFSET")
            end = np.array(
                [tokens.number("OFFSET x"), tokens.number("OFFSET y"), tokens.number("OFFSET z")]
            )
            tokens.expect("}")
            owner = joints[stack[-1]]
            if owner.end_site is None:
                owner.end_site = end
        elif tok == "}":
            stack.pop()
            if not stack:
                break
        elif upper == "ROOT":
            raise tokens.error("more than one ROOT is not supported", line)
        else:
            raise tokens.error(f"expected 'JOINT', 'End Site' or '}}', found {tok!r}", line)
    if tokens.peek() is not None:
        tok, line = tokens.next("end of hierarchy")
        if tok.upper() == "ROOT":
            raise tokens.error("more than one ROOT is not supported", line)
        raise tokens.error(f"unexpected {tok!r} after the hierarchy", line)
    return joints


def _motion_header(lines: list[str], start: int, file: str) -> tuple[int, float, int]:
    """Parse ``Frames:`` and ``Frame Time:``; returns (frames, frame_time, first data line)."""
    i = start
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise MotionError("missing 'Frames:' line after MOTION", file=file, line=start)
    parts = lines[i].replace(":", ": ").split()
    if len(parts) != 2 or parts[0].lower() != "frames:":
        raise MotionError(
            f"expected 'Frames: N', found {lines[i].strip()!r}", file=file, line=i + 1
        )
    try:
        frames = int(parts[1])
    except ValueError:
        raise MotionError(
            f"frame count {parts[1]!r} is not an integer", file=file, line=i + 1
        ) from None
    if frames <= 0:
        raise MotionError(f"frame count must be positive, got {frames}", file=file, line=i + 1)
    i += 1
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise MotionError("missing 'Frame Time:' line", file=file, line=i)
    parts = lines[i].replace(":", ": ").split()
    if len(parts) != 3 or parts[0].lower() != "frame" or parts[1].lower() != "time:":
        raise MotionError(
            f"expected 'Frame Time: SECONDS', found {lines[i].strip()!r}", file=file, line=i + 1
        )
    try:
        frame_time = float(parts[2])
    except ValueError:
        raise MotionError(
            f"frame time {parts[2]!r} is not a number", file=file, line=i + 1
        ) from None
    if not (math.isfinite(frame_time) and MIN_FRAME_TIME <= frame_time <= MAX_FRAME_TIME):
        raise MotionError(
            f"frame time {parts[2]} s is out of range: between {MIN_FRAME_TIME} s (10 kHz) and "
            f"{MAX_FRAME_TIME} s (1 Hz)",
            file=file, line=i + 1,
        )  # fmt: skip
    if frames * frame_time > MAX_SECONDS:
        raise MotionError(
            f"{frames} frames of {frame_time} s last {frames * frame_time / 3600:.1f} h; a clip "
            f"is at most {MAX_SECONDS / 3600:.0f} h",
            file=file, line=i + 1,
        )  # fmt: skip
    return frames, frame_time, i + 1


def _motion_values(
    lines: list[str], first: int, frames: int, num_channels: int, file: str
) -> np.ndarray:
    rows: list[list[str]] = []
    numbers: list[int] = []
    for k in range(first, len(lines)):
        parts = lines[k].split()
        if not parts:
            continue
        if len(rows) == frames:
            raise MotionError(
                f"more data rows than the {frames} frames declared", file=file, line=k + 1
            )
        if len(parts) != num_channels:
            raise MotionError(
                f"frame {len(rows)} has {len(parts)} values, the hierarchy declares "
                f"{num_channels} channels",
                file=file,
                line=k + 1,
            )
        rows.append(parts)
        numbers.append(k + 1)
    if len(rows) < frames:
        raise MotionError(
            f"file is truncated: {frames} frames declared, {len(rows)} found",
            file=file,
            line=len(lines),
        )
    if num_channels == 0:
        return np.zeros((frames, 0))
    try:
        values = np.array(rows, dtype=np.float64)
    except ValueError:
        values = None
    if values is None or not np.isfinite(values).all():
        for parts, number in zip(rows, numbers, strict=True):
            for tok in parts:
                try:
                    ok = math.isfinite(float(tok))
                except ValueError:
                    ok = False
                if not ok:
                    raise MotionError(
                        f"bad number {tok!r} in motion data", file=file, line=number
                    ) from None
    return values  # type: ignore[return-value]


def parse_bvh_text(text: str, file: str | Path = "<string>") -> BvhData:
    """Parse BVH text; raises :class:`MotionError` (with line) for any malformed input."""
    file = str(file)
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise MotionError("file is empty", file=file, line=1)
    motion_at = next((i for i, line in enumerate(lines) if line.strip().upper() == "MOTION"), None)
    header = lines if motion_at is None else lines[:motion_at]
    tokens = _Tokens(header, file)
    try:
        joints = _parse_hierarchy(tokens)
    except IndexError:  # pragma: no cover - defensive: the parser checks every pop
        raise MotionError("unbalanced braces in HIERARCHY", file=file, line=len(header)) from None
    if motion_at is None:
        raise MotionError("no MOTION section (file truncated?)", file=file, line=len(lines))
    frames, frame_time, first = _motion_header(lines, motion_at + 1, file)
    starts = []
    total = 0
    for j in joints:
        starts.append(total)
        total += len(j.channels)
    values = _motion_values(lines, first, frames, total, file)
    return BvhData(joints, frame_time, values, Path(file), starts)


def read_bvh(path: str | Path) -> BvhData:
    """Read and parse a BVH file (any I/O or decoding problem is a :class:`MotionError`)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MotionError(f"cannot read file: {exc.strerror or exc}", file=path) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if "\x00" in text:
        raise MotionError("file is binary, not BVH text", file=path, line=1)
    return parse_bvh_text(text, path)


def source_forward_kinematics(data: BvhData) -> tuple[np.ndarray, np.ndarray]:
    """Global joint positions ``(F, S, 3)`` (file units) and rotations ``(F, S, 4)``.

    Position channels replace the matching OFFSET component (root translation; Bandai writes
    position channels equal to the offsets on every joint). Rotation channels compose in file
    order (``Zrotation Xrotation Yrotation`` is ``Rz Rx Ry``).
    """
    f = data.num_frames
    n = len(data.joints)
    pos = np.empty((f, n, 3))
    grot = np.empty((f, n, 4))
    for j, joint in enumerate(data.joints):
        start = data.channel_start[j]
        vals = data.values[:, start : start + len(joint.channels)]
        trans = np.broadcast_to(joint.offset, (f, 3)).copy()
        angles = []
        for k, ch in enumerate(joint.channels):
            if ch.endswith("position"):
                trans[:, "XYZ".index(ch[0])] = vals[:, k]
            else:
                angles.append(vals[:, k])
        order = joint.rotation_order
        local = rot.from_euler(np.stack(angles, -1), order) if order else rot.identity((f,))
        if joint.parent < 0:
            pos[:, j] = trans
            grot[:, j] = local
        else:
            p = joint.parent
            pos[:, j] = pos[:, p] + rot.apply(grot[:, p], trans)
            grot[:, j] = rot.mul(grot[:, p], local)
    return pos, grot
