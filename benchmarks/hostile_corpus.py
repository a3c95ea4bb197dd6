"""Hostile inputs through the real CLI: does each end in a clear error?

Run: ``.venv/bin/python benchmarks/hostile_corpus.py [--only NAME] [--timeout 60]``

Every case writes its bad input into a temporary directory and runs one ``retarget`` command in
a fresh process (a tiny run is trained first for the cases that need one). Each outcome is one
of: **clear** (exit 2, an ``error:`` line, no traceback), **traceback** (a Python traceback or
an "unexpected failure"), **hang** (killed at ``--timeout``), **silent** (exit 0: accepted
although broken), or for the valid inputs in the corpus **accepted** / **refused**. It prints
a table and the line ``N cases, C clear, T traceback, H hang, S silent``.
"""

from __future__ import annotations

import argparse
import functools
import os
import re
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

TINY = """\
extends: null
name: tiny
character: human
sensors: [three_point]
rewards: {joint_pos: {weight: 1.0}, fail_penalty: {}}
terminations: {fall: {}, episode_cap: {max_steps: 20}}
algorithm: {type: ppo, rollout_steps: 4, actor_hidden: [16], critic_hidden: [16],
            minibatch_size: 8, epochs: 1}
env: {num_envs: 2}
sim: {threads: 1}
"""

@functools.cache
def sample_bvh() -> str:
    """The BVH format plugin's own valid sample, which the BVH cases break one way each."""
    from retarget.plugins.formats.bvh import Bvh

    with tempfile.TemporaryDirectory() as tmp:
        return Bvh.write_sample(Path(tmp)).read_text()


def _first_value_nan(text: str) -> str:
    head, motion = text.split("Frame Time:", 1)
    time_line, first, rest = motion.split("\n", 2)
    values = first.split()
    values[3] = "nan"
    return f"{head}Frame Time:{time_line}\n{' '.join(values)}\n{rest}"


HEADER = '{"format": "retarget-devices", "version": 1}'
POSE = "[0, 1.6, 0, 1, 0, 0, 0]"


@dataclass
class Case:
    name: str
    group: str
    argv: Callable[[Path, Path], list[str]]  # (work dir, trained run) -> arguments
    valid: bool = False  # a valid input the corpus checks is accepted


def _write(work: Path, name: str, text: str | bytes) -> str:
    path = work / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return str(path)


def _recipe(name: str, text: str) -> Case:
    return Case(
        name, "recipe", lambda w, r: ["recipe", "validate", _write(w, f"{name}.yaml", text)]
    )


def _flag(name: str, argv: list[str]) -> Case:
    return Case(name, "flag", lambda w, r: [a.replace("RUN", str(r)) for a in argv])


def _bvh(name: str, text: str | bytes | Callable[[str], str]) -> Case:
    """A BVH case: fixed content, or a change made to the valid sample."""

    def argv(w: Path, r: Path) -> list[str]:
        body = text(sample_bvh()) if callable(text) else text
        return ["motion", "inspect", _write(w, f"{name}.bvh", body)]

    return Case(name, "bvh", argv)


def _recording(name: str, lines: list[str] | bytes) -> Case:
    def argv(w: Path, r: Path) -> list[str]:
        body = lines if isinstance(lines, bytes) else "\n".join(lines) + "\n"
        path = _write(w, f"{name}.jsonl", body)
        return ["play", str(r), "--input", path, "--out", str(w / f"{name}.png"), "--seconds", "1"]

    return Case(name, "recording", argv)


def _mesh(name: str, text: str, scale: float = 1.0, valid: bool = False) -> Case:
    def argv(w: Path, r: Path) -> list[str]:
        path = _write(w, f"{name}.obj", text)
        recipe = f"character: human\nscene: {{type: mesh, path: {path}, scale: {scale}}}\n"
        return ["recipe", "validate", _write(w, f"{name}.yaml", recipe)]

    return Case(name, "mesh", argv, valid=valid)


def _run_file(name: str, make: Callable[[Path], None]) -> Case:
    def argv(w: Path, r: Path) -> list[str]:
        run = w / name / "20260101-000000"
        (run / "checkpoints").mkdir(parents=True)
        (run / "recipe.lock.yaml").write_text((r / "recipe.lock.yaml").read_text())
        for ckpt in sorted((r / "checkpoints").glob("*.pt"))[-1:]:
            (run / "checkpoints" / ckpt.name).write_bytes(ckpt.read_bytes())
        make(run)
        return ["eval", str(run), "--num-envs", "2", "--max-seconds", "0.5"]

    return Case(name, "run dir", argv)


def _crafted_pickle(run: Path) -> None:
    import torch

    class Payload:
        def __reduce__(self):
            return (os.system, (f"touch {run / 'pwned'}",))

    torch.save({"algorithm": Payload()}, run / "checkpoints" / "ckpt-0000009.pt")


def _nan_weights(run: Path) -> None:
    import torch

    from retarget.train.checkpoint import load_checkpoint

    path = sorted((run / "checkpoints").glob("*.pt"))[-1]
    state = load_checkpoint(path)  # a checkpoint this runner trained: loaded the safe way
    for value in state["algorithm"]["actor"].values():
        if value.is_floating_point():
            value.fill_(float("nan"))
            break
    torch.save(state, run / "checkpoints" / "ckpt-0000009.pt")


FLAT = "v 0 0 0.3\nv 2 0 0.3\nv 2 1 0.3\nv 0 1 0.3\nf 1 2 3\nf 1 3 4\n"

CASES = [
    # recipes
    _recipe("alias_bomb", "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)) + "character: human\n"),
    _recipe("deep_nesting", "character: human\nenv: " + "{a: " * 200 + "1" + "}" * 200 + "\n"),
    _recipe("duplicate_key", "character: human\nseed: 1\nseed: 2\n"),
    _recipe("name_escapes", "character: human\nname: ../../etc\n"),
    _recipe("name_absolute", "character: human\nname: /tmp/x\n"),
    _recipe("python_tag", "character: !!python/object/apply:os.system ['true']\n"),
    _recipe("num_envs_nan", "character: human\nenv: {num_envs: .nan}\n"),
    _recipe("num_envs_zero", "character: human\nenv: {num_envs: 0}\n"),
    _recipe("num_envs_huge", "character: human\nenv: {num_envs: 100000000}\n"),
    _recipe("lr_inf", "character: human\nalgorithm: {type: ppo, learning_rate: .inf}\n"),
    _recipe("lr_negative", "character: human\nalgorithm: {type: ppo, learning_rate: -1}\n"),
    _recipe("hidden_huge", "character: human\nalgorithm: {type: ppo, actor_hidden: [1e9]}\n"),
    _recipe("control_hz_zero", "character: human\nsim: {control_hz: 0}\n"),
    _recipe("substeps_negative", "character: human\nsim: {substeps: -3}\n"),
    _recipe("weight_nan", "character: human\nrewards: {joint_pos: {weight: .nan}}\n"),
    _recipe("seed_negative", "character: human\nseed: -5\n"),
    _recipe("unknown_plugin", "character: humann\n"),
    _recipe("unknown_field", "character: human\nenv: {num_env: 4}\n"),
    _recipe("wrong_type", "character: human\nsim: {substeps: many}\n"),
    _recipe("extends_loop", "extends: extends_loop.yaml\ncharacter: human\n"),
    _recipe("extends_missing", "extends: nowhere\ncharacter: human\n"),
    _recipe("not_a_mapping", "- character\n- human\n"),
    _recipe("empty", ""),
    Case("not_utf8", "recipe", lambda w, r: ["recipe", "validate",
                                             _write(w, "bad.yaml", b"character: \xff\xfe\n")]),
    Case("toml_broken", "recipe", lambda w, r: ["recipe", "validate",
                                                _write(w, "bad.toml", "character = \n")]),
    # flags
    _flag("steps_negative", ["train", "--steps", "-1"]),
    _flag("steps_nan", ["train", "--steps", "nan"]),
    _flag("minutes_inf", ["train", "--minutes", "inf"]),
    _flag("checkpoint_every_zero", ["train", "--checkpoint-every", "0"]),
    _flag("num_envs_zero_flag", ["train", "--num-envs", "0"]),
    _flag("threads_negative", ["train", "--threads", "-1"]),
    _flag("eval_every_zero", ["eval", "RUN", "--every", "0"]),
    _flag("eval_max_seconds_nan", ["eval", "RUN", "--max-seconds", "nan"]),
    _flag("eval_num_envs_huge", ["eval", "RUN", "--num-envs", "10000000"]),
    _flag("play_seconds_negative", ["play", "RUN", "--out", "x.gif", "--seconds", "-3"]),
    _flag("play_size_zero", ["play", "RUN", "--out", "x.gif", "--size", "0x0"]),
    _flag("play_size_words", ["play", "RUN", "--out", "x.gif", "--size", "big"]),
    _flag("resume_not_a_run", ["train", "--resume", "/tmp"]),
    _flag("set_no_equals", ["train", "--set", "seed"]),
    # BVH
    _bvh("frame_time_zero", lambda s: s.replace("Frame Time: 0.03333333", "Frame Time: 0")),
    _bvh("frame_time_huge", lambda s: s.replace("Frame Time: 0.03333333", "Frame Time: 1e6")),
    _bvh("frame_time_nan", lambda s: s.replace("Frame Time: 0.03333333", "Frame Time: nan")),
    _bvh("frames_huge", lambda s: re.sub(r"Frames: \d+", "Frames: 999999999", s)),
    _bvh("value_nan", _first_value_nan),
    _bvh("truncated", lambda s: s[: len(s) // 2]),
    _bvh("binary", b"\x00\x01\x02HIERARCHY\xff"),
    _bvh("joints_huge", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation "
         "Yrotation\n" + "".join(f"JOINT B{k}\n{{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation "
                                  "Xrotation Yrotation\n" for k in range(3000))),
    # device recordings
    _recording("gap_huge", [HEADER, f'{{"t": 0, "hmd": {POSE}}}', f'{{"t": 1e9, "hmd": {POSE}}}']),
    _recording("position_nan", [HEADER, '{"t": 0, "hmd": [NaN, 1.6, 0, 1, 0, 0, 0]}']),
    _recording("position_far", [HEADER, '{"t": 0, "hmd": [1e6, 1.6, 0, 1, 0, 0, 0]}']),
    _recording("all_untracked", [HEADER] + [f'{{"t": {k / 72}, "hmd": null}}' for k in range(9)]),
    _recording("time_string", [HEADER, f'{{"t": "0", "hmd": {POSE}}}']),
    _recording("time_bool", [HEADER, f'{{"t": true, "hmd": {POSE}}}']),
    _recording("not_json", [HEADER, "{t: 0"]),
    _recording("no_header", [f'{{"t": 0, "hmd": {POSE}}}']),
    _recording("quaternion_zero", [HEADER, '{"t": 0, "hmd": [0, 1.6, 0, 0, 0, 0, 0]}']),
    _recording("binary_recording", b"\xff\xfe\x00\x01"),
    # meshes
    _mesh("mesh_garbage", "this is not an obj\n"),
    _mesh("mesh_km_wide", FLAT, scale=2000.0),
    _mesh("mesh_overflow", FLAT, scale=1e308),
    _mesh("mesh_grid_huge", FLAT, scale=400.0),
    _mesh("mesh_flat_platform", FLAT, valid=True),
    # run directories
    _run_file("lock_not_utf8", lambda run: (run / "recipe.lock.yaml").write_bytes(b"\xff\xfe")),
    _run_file("lock_python_tag", lambda run: (run / "recipe.lock.yaml").write_text(
        "character: !!python/object/apply:os.system ['true']\n")),
    _run_file("checkpoint_crafted_pickle", _crafted_pickle),
    _run_file("checkpoint_not_retarget", lambda run: __import__("torch").save(
        {"w": 1}, run / "checkpoints" / "ckpt-0000009.pt")),
    _run_file("checkpoint_nan_weights", _nan_weights),
    _run_file("checkpoint_garbage", lambda run: (run / "checkpoints" / "ckpt-0000009.pt")
              .write_bytes(b"not a checkpoint")),
]


def classify(rc: int | None, output: str, valid: bool) -> str:
    if rc is None:
        return "hang"
    if valid:
        return "accepted" if rc == 0 else "refused"
    if "Traceback" in output or "unexpected failure" in output:
        return "traceback"
    if rc == 0:
        return "silent"
    return "clear" if rc == 2 and "error:" in output else "traceback"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", help="run the cases whose name contains this")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds before a hang")
    args = parser.parse_args()
    cases = [c for c in CASES if not args.only or args.only in c.name]
    exe = [sys.executable, "-c", "import sys; from retarget.cli.main import main; "
           "sys.exit(main(sys.argv[1:]))"]  # fmt: skip
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "osmesa")}
    with tempfile.TemporaryDirectory(prefix="retarget-corpus-") as tmp:
        work = Path(tmp)
        (work / "tiny.yaml").write_text(TINY)
        trained = subprocess.run(
            [*exe, "train", str(work / "tiny.yaml"), "--steps", "8", "--runs-dir",
             str(work / "runs"), "--no-tensorboard"],
            capture_output=True, text=True, env=env, cwd=work, timeout=300,
        )  # fmt: skip
        if trained.returncode != 0:
            raise SystemExit(f"could not train the run the cases need:\n{trained.stderr}")
        run = (work / "runs" / "tiny" / "latest").resolve()
        rows = []
        for case in cases:
            home = work / case.name
            home.mkdir()
            argv = case.argv(home, run)
            try:
                done = subprocess.run([*exe, *argv], capture_output=True, text=True, env=env,
                                      cwd=home, timeout=args.timeout)  # fmt: skip
                rc, output = done.returncode, done.stdout + done.stderr
            except subprocess.TimeoutExpired:
                rc, output = None, ""
            outcome = classify(rc, output, case.valid)
            if list(home.rglob("pwned")):
                outcome = "RAN CODE"
            first = next((ln for ln in output.splitlines() if "error" in ln), "")
            rows.append((case.group, case.name, outcome, first.strip()[:90]))
            print(f"{case.group:<10} {case.name:<26} {outcome:<10} {rows[-1][3]}", flush=True)
    bad = [r for r in rows if not (r[0], r[2]) or r[2] not in ("clear", "accepted")]
    counts = {k: sum(r[2] == k for r in rows) for k in ("clear", "traceback", "hang", "silent")}
    valid = [r for r in rows if r[2] in ("accepted", "refused")]
    print(textwrap.dedent(f"""
        {len(rows)} cases, {counts['clear']} clear, {counts['traceback']} traceback, \
{counts['hang']} hang, {counts['silent']} silent; valid inputs: \
{sum(r[2] == 'accepted' for r in valid)}/{len(valid)} accepted"""))
    for row in bad:
        print("  not clear:", *row[:3])


if __name__ == "__main__":
    main()
