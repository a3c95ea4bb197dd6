"""``retarget export RUN --onnx``: the trained actor (with its normaliser) as ONNX + JSON."""

from __future__ import annotations

import argparse
from pathlib import Path

from retarget.errors import RetargetError, require_extra
from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("export", help="export a trained policy (ONNX)")
    parser.add_argument("run", help="run directory (runs/NAME/latest)")
    parser.add_argument("--onnx", action="store_true", help="write ONNX (the only format yet)")
    parser.add_argument("--out", help="output .onnx file (default: RUN/export/policy.onnx)")
    parser.add_argument("--checkpoint", help="a specific checkpoint file (default: latest)")
    parser.set_defaults(handler=run)


def _export_stages(env, folder: Path) -> list[dict]:
    """ONNX files of the networks the run's sensors run (a two-stage tracker's estimator):
    a headset application runs each on its inputs and feeds its output to the policy's
    columns of that source."""
    import warnings

    import torch

    out = []
    for sensor in env.sensors:
        found = sensor.deployable()
        if found is None:
            continue
        module, width, description = found
        folder.mkdir(parents=True, exist_ok=True)
        target = folder / f"{sensor.name}.onnx"
        with torch.no_grad(), warnings.catch_warnings():  # the legacy exporter warns so
            warnings.simplefilter("ignore")
            torch.onnx.export(module, (torch.zeros(1, width),), str(target), input_names=["obs"],
                              output_names=["out"], dynamic_axes={"obs": {0: "batch"},
                                                                  "out": {0: "batch"}},
                              opset_version=17, dynamo=False)  # fmt: skip
        out.append({"source": sensor.name, "onnx": target.name, "obs_dim": width,
                    "out_dim": int(sensor.spec(env.layout).size), **description})  # fmt: skip
    return out


def run(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.cli.console import out
    from retarget.deploy import export_onnx, export_post_stages, policy_of
    from retarget.sim import describe_actuation
    from retarget.train.load import load_run
    if not args.onnx:
        raise RetargetError("choose a format", hint="retarget export RUN --onnx")
    require_extra("export", "onnx", needed_for="retarget export --onnx")
    loaded = load_run(args.run, registry, num_envs=1, checkpoint=args.checkpoint)
    env = loaded.env
    group, _ = policy_of(loaded.algorithm)
    layout = env.layout
    metadata = loaded.algorithm.export_metadata(env) or {
        "character": env.character.name,
        "control_hz": env.sim.settings.control_hz,
        "obs_dim": env.obs_dims[group],
        "observation_sources": [
            {"name": name, "size": env.observation_size(name)} for name in env.groups[group]
        ],
        "actuators": list(layout.actuator_names),
        "torque_limits": [float(t) for t in layout.torque_limits],
        "actuation": describe_actuation(env.sim.model, env.sim.settings.actuation),
    }
    metadata = {"run": str(loaded.run), "checkpoint": str(loaded.checkpoint), **metadata}
    from retarget.pretrained import inside_models

    base = Path("export") / loaded.run.name if inside_models(loaded.run) else loaded.run / "export"
    path = Path(args.out) if args.out else base / "policy.onnx"
    stages = _export_stages(env, path.parent)
    if stages:
        metadata["stages"] = stages  # networks inside sensors, run before the policy
    after = export_post_stages(loaded.algorithm, path.parent)
    if after:
        metadata["after"] = after  # steps on the exported module's output
    exported = export_onnx(loaded.algorithm, path, metadata)
    out.print(
        f"wrote {exported.onnx} (obs {exported.obs_dim} -> action {exported.action_dim}) "
        f"and {exported.metadata}"
    )
    return 0
