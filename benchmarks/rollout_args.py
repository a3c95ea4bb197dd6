"""The arguments of the benchmarks that roll one trained policy through one clip, as ``play``."""

from __future__ import annotations

import argparse


def add_rollout_args(parser: argparse.ArgumentParser) -> None:
    """``RUN``, ``--motions``, ``--clip``, ``--seconds``."""
    parser.add_argument("run")
    parser.add_argument("--motions", help="clip file or directory (default: the run's own)")
    parser.add_argument("--clip", type=int, default=0)
    parser.add_argument("--seconds", type=float, default=8.0)
