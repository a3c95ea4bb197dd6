"""One table for kinematic, two-stage and physics methods from their ``retarget eval`` reports.

Run: ``.venv/bin/python benchmarks/method_table.py "estimator=est.json" "PPO student=ppo.json" ...``
(each argument ``LABEL=REPORT.json``; reports of the same clips and eval settings). Prints a
Markdown table of the overall figures, and each method's MPJPE relative to the first row.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

COLUMNS = (
    ("headset_cm", "HMD cm", "{:.1f}"),
    ("controller_cm", "hands cm", "{:.1f}"),
    ("mpjpe_mm", "MPJPE mm", "{:.0f}"),
    ("g_mpjpe_mm", "G-MPJPE mm", "{:.0f}"),
    ("mpjre_deg", "MPJRE deg", "{:.1f}"),
    ("jerk_km_s3", "jerk km/s3", "{:.2f}"),
    ("foot_skate_mm", "skate mm", "{:.1f}"),
    ("penetration_mean_mm", "pen mean mm", "{:.1f}"),
    ("penetration_max_mm", "pen max mm", "{:.0f}"),
    ("falls_per_min", "falls/min", "{:.2f}"),
    ("success_frame", "success frame", "{:.2f}"),
)


def main(argv: list[str]) -> int:
    if not argv or any("=" not in a for a in argv):
        print(__doc__)
        return 2
    rows = []
    for arg in argv:
        label, path = arg.split("=", 1)
        report = json.loads(Path(path).read_text())
        rows.append((label, report["overall"], report.get("method", "policy (physics)")))
    print("| method | kind | " + " | ".join(c[1] for c in COLUMNS) + " | MPJPE vs first |")
    print("|---" * (len(COLUMNS) + 3) + "|")
    base = rows[0][1].get("mpjpe_mm")
    for label, overall, kind in rows:
        cells = [fmt.format(overall[k]) if k in overall else "-" for k, _, fmt in COLUMNS]
        ratio = f"{overall['mpjpe_mm'] / base:.2f}x" if base and "mpjpe_mm" in overall else "-"
        print(f"| {label} | {kind.split(' (')[0]} | " + " | ".join(cells) + f" | {ratio} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
