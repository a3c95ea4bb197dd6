"""A fine-tuned policy blended with the policy it started from (``retarget blend``).

A fine-tune learns what its new data asks and forgets some of what its start knew: a
three-point student fine-tuned to read the controllers' tracked flags holds raised hands
closer to the controllers and falls more often on runs. Interpolating the weights of the
start and of the fine-tune (WiSE-FT, Wortsman et al. 2022; model soups) keeps much of both,
because a fine-tune stays in its start's basin, where the straight line between the two is
low-loss; ``weight`` 0 is the start, 1 the fine-tune.

The start may observe fewer inputs than the fine-tune (``--init-from`` adds new sources at zero
weight): it is widened exactly as the warm start did, so its new columns are zero and blending
scales the fine-tune's. The two must read their shared inputs with the same statistics, which
a warm start guarantees (it freezes them); runs trained apart do not, and are refused, since
their weights mean different things. Observation statistics come from the fine-tune.
"""

from __future__ import annotations

import copy
import json
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import torch

from retarget.errors import RetargetError
from retarget.registry import Registry
from retarget.train.average import KEEP, combine
from retarget.train.checkpoint import save_checkpoint
from retarget.train.load import load_run
from retarget.train.package_model import policy_only
from retarget.train.run_dir import CHECKPOINTS, LOCK
from retarget.train.warm_start import warm_start

BLENDED_FROM = "blended_from.json"
"""In the new run's directory: the start, the fine-tune and the weight of the blend."""
STATISTICS = "obs_norm"  # the algorithm state's observation statistics (taken, not blended)


def _check_statistics(start: Mapping[str, Any], tuned: Mapping[str, Any],
                      inputs: Mapping[str, torch.Tensor], tuned_run: Path) -> None:  # fmt: skip
    """Refuse runs whose shared inputs are normalised differently (not a fine-tune and its
    start): the blend of their weights would read each input at another scale."""
    for group, index in inputs.items():
        known = index >= 0
        for stat in ("mean", "var"):
            key = f"groups.{group}.{stat}"
            if key not in tuned or key not in start:
                continue
            a, b = start[key][known].double(), tuned[key][known].double()
            if not torch.allclose(a, b, rtol=1e-4, atol=1e-6):
                worst = int((a - b).abs().argmax())
                raise RetargetError(
                    f"the runs normalise their shared '{group}' inputs differently (input "
                    f"{worst}: {stat} {float(a[worst]):.4g} against {float(b[worst]):.4g})",
                    file=str(tuned_run),
                    hint="blend a fine-tune with the run it started from (--init-from)",
                )


def blend_runs(tuned: str | Path, start: str | Path, weight: float, out: str | Path,
               registry: Registry) -> Path:  # fmt: skip
    """Write a run directory at ``out`` whose policy is ``(1 - weight) * start + weight *
    tuned`` (see module doc); lock, settings and checkpoint name from ``tuned``."""
    if not 0.0 <= weight <= 1.0:
        raise RetargetError(f"--weight must be within 0 and 1, got {weight}")
    target = Path(out)
    if target.exists() and any(target.iterdir()):
        raise RetargetError("the output directory exists and is not empty", file=str(target),
                            hint="give a new --out")  # fmt: skip
    loaded = load_run(tuned, registry, num_envs=1)
    # a copy: state dicts share storage with the network, which the warm start overwrites
    tuned_state = copy.deepcopy(policy_only({"algorithm": loaded.algorithm.state_dict()}))
    tuned_state = tuned_state["algorithm"]
    info = warm_start(loaded.algorithm, loaded.env.obs_layout, start, registry)
    start_state = policy_only({"algorithm": loaded.algorithm.state_dict()})["algorithm"]
    _check_statistics(start_state.get(STATISTICS, {}), tuned_state.get(STATISTICS, {}),
                      info.inputs, loaded.run)  # fmt: skip
    mixed = combine(
        start_state, tuned_state,
        lambda a, b: ((1.0 - weight) * a.double() + weight * b.double()).to(b.dtype),
        file=loaded.checkpoint, where="algorithm", against="than in the start run",
        hint="blend a fine-tune with the run it started from", keep=(STATISTICS,),
    )  # fmt: skip
    (target / CHECKPOINTS).mkdir(parents=True, exist_ok=True)
    shutil.copy2(loaded.run / LOCK, target / LOCK)
    for name in KEEP:
        if (loaded.run / name).is_file():
            shutil.copy2(loaded.run / name, target / name)
    save_checkpoint(target / CHECKPOINTS / loaded.checkpoint.name,
                    {"algorithm": mixed, "progress": loaded.progress})  # fmt: skip
    record = {"start": str(info.checkpoint), "tuned": str(loaded.checkpoint), "weight": weight}
    (target / BLENDED_FROM).write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    return target
