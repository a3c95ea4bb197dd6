"""``retarget bench env``: environment throughput against raw MuJoCo on this machine.

Both are measured in the same run, in alternating blocks (these machines are noisy), on the
same compiled model with the same substeps, threads and number of worlds, so the ratio says
how much the environment (reference lookup, sensors, rewards, observations, resets) costs on
top of the physics floor.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import TYPE_CHECKING

import retarget
from retarget import Command

if TYPE_CHECKING:
    import numpy as np
    from mujoco.batch import Batch


def _raw_block(batch: Batch, ctrl: np.ndarray, substeps: int, steps: int, rng) -> float:
    bound = batch.bind("ctrl")
    t0 = time.perf_counter()
    for _ in range(steps):
        bound[:] = rng.uniform(-0.3, 0.3, size=ctrl.shape)
        batch.step(nstep=substeps)
    return time.perf_counter() - t0


class BenchCommand(Command):
    """Measure environment control steps per second against raw MuJoCo stepping."""

    name = "bench"
    help = "measure throughput on this machine (bench env)"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        from retarget.commands.recipe_args import add_recipe_flags
        sub = parser.add_subparsers(dest="bench_verb", required=True)
        env = sub.add_parser("env", help="environment steps/s vs raw MuJoCo steps/s")
        add_recipe_flags(env)
        env.add_argument("--num-envs", type=int, default=None, help="worlds stepped together")
        env.add_argument("--threads", type=int, default=None, help="physics threads")
        env.add_argument("--seconds", type=float, default=10.0, help="measuring time per side")
        env.add_argument("--blocks", type=int, default=4, help="alternating measuring blocks")

    def run(self, args: argparse.Namespace) -> int:
        import numpy as np
        import torch
        from mujoco.batch import Batch
        from rich.console import Console
        from rich.progress import Progress
        from rich.table import Table

        from retarget.commands.recipe_args import load_from_args
        from retarget.env import random_actions
        from retarget.env.build import env_from_recipe
        console = Console()
        # torch's intra-op threads spin between the env's many small tensor ops and steal
        # cores from MuJoCo's pool (measured: physics 40% slower with 2 torch threads)
        torch.set_num_threads(1)
        resolved = load_from_args(args, self.plugins())
        env = env_from_recipe(resolved, num_envs=args.num_envs, threads=args.threads)
        settings = env.sim.settings
        gen = torch.Generator().manual_seed(0)
        env.reset()
        for _ in range(10):  # warm-up
            env.step(random_actions(env, gen, 0.3))
        t0 = time.perf_counter()
        probe = 0
        while time.perf_counter() - t0 < 1.0:
            env.step(random_actions(env, gen, 0.3))
            probe += 1
        steps = max(5, int(probe * args.seconds / args.blocks))
        raw = Batch(env.world.model, env.num_envs, nthread=settings.threads, persistent=True)
        rng = np.random.default_rng(0)
        ctrl = np.zeros((env.num_envs, env.action_dim))
        _raw_block(raw, ctrl, settings.substeps, 10, rng)
        env_rates, raw_rates = [], []
        for key in env.seconds:
            env.seconds[key] = 0.0
        env.sim.seconds = dict.fromkeys(env.sim.seconds, 0.0)
        with Progress(console=console, transient=True) as progress:
            task = progress.add_task("measuring", total=args.blocks * 2)
            for _ in range(args.blocks):
                t = time.perf_counter()
                for _ in range(steps):
                    env.step(random_actions(env, gen, 0.3))
                env_rates.append(steps * env.num_envs / (time.perf_counter() - t))
                progress.advance(task)
                # start raw physics from the env's current states so both see the same regime
                raw.bind("qpos")[:] = env.sim.raw("qpos")
                raw.bind("qvel")[:] = env.sim.raw("qvel")
                raw.forward()
                seconds = _raw_block(raw, ctrl, settings.substeps, steps, rng)
                raw_rates.append(steps * env.num_envs / seconds)
                progress.advance(task)
        total_steps = steps * args.blocks
        split = {**env.sim.seconds, **env.seconds}
        env_rate, raw_rate = statistics.median(env_rates), statistics.median(raw_rates)
        table = Table(
            title=f"{env.character.name}: {env.num_envs} envs, "
            f"{settings.substeps} substeps, threads={settings.threads or 'all'}"
        )
        table.add_column("part")
        table.add_column("ms / control step", justify="right")
        table.add_column("share", justify="right")
        whole = sum(split.values())
        for part, sec in split.items():
            table.add_row(part, f"{1e3 * sec / total_steps:.3f}", f"{100 * sec / whole:.1f}%")
        console.print(table)
        console.print(
            f"terminations: {env.termination_counts}, non-finite resets: {env.nan_resets}"
        )
        # the raw blocks continue from the env's states but, free of resets, drift into
        # other regimes (fallen bodies, other contacts); the physics share is the env against
        # MuJoCo stepping exactly the env's own states
        print(
            f"env_steps_per_s={env_rate:.0f} raw_steps_per_s={raw_rate:.0f} "
            f"ratio={env_rate / raw_rate:.3f} physics_share={split['physics'] / whole:.3f}"
        )
        return 0


@retarget.hookimpl
def register_commands(register) -> None:
    register(BenchCommand)
