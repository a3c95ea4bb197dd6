"""``retarget bench env`` runs a short measurement and ends with the machine-readable line."""

from __future__ import annotations

import re

from retarget.cli.main import main


def test_bench_env_prints_rates_and_ratio(capsys) -> None:
    code = main(
        ["bench", "env", "--num-envs", "4", "--threads", "1", "--seconds", "0.3", "--blocks", "1"]
    )
    assert code == 0
    out = capsys.readouterr().out
    line = out.strip().splitlines()[-1]
    match = re.fullmatch(
        r"env_steps_per_s=(\d+) raw_steps_per_s=(\d+) ratio=([\d.]+) physics_share=([\d.]+)",
        line,
    )
    assert match, line
    env_rate, raw_rate, ratio = int(match[1]), int(match[2]), float(match[3])
    assert env_rate > 0 and raw_rate > 0 and 0 < float(match[4]) < 1
    assert abs(ratio - env_rate / raw_rate) < 0.01
    for part in ("physics", "observations", "rewards"):
        assert part in out
