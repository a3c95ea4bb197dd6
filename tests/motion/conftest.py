"""Fixtures for the motion tests: the shared real mocap clips, read once per session."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def shared_mocap_dir() -> Path:
    env = os.environ.get("RETARGET_SHARED_DATA")
    if env:
        p = Path(env)
        return p / "mocap" if (p / "mocap").is_dir() else p
    return (REPO / ".." / "shared" / "data" / "mocap").resolve()


@pytest.fixture(scope="session")
def mocap_dir() -> Path:
    d = shared_mocap_dir()
    if not d.is_dir() or not list(d.glob("*.bvh")):
        pytest.skip(f"shared mocap clips not found at {d} (set RETARGET_SHARED_DATA)")
    return d


@pytest.fixture(scope="session")
def mocap_index(mocap_dir: Path) -> dict[str, dict[str, str]]:
    with (mocap_dir / "index.csv").open() as f:
        return {row["file"]: row for row in csv.DictReader(f)}


@pytest.fixture(scope="session")
def real_clips(mocap_dir: Path):
    from retarget.motion.import_bvh import load_bvh

    return {p.name: load_bvh(p, keep_source=True) for p in sorted(mocap_dir.glob("*.bvh"))}
