"""Fixtures for the motion tests: the shared real mocap clips, read once per session."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from retarget.motion.shared_data import shared_data

REPO = Path(__file__).resolve().parents[2]


def shared_mocap_dir() -> Path:
    return shared_data("mocap")


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
