"""Does holding each head's z std open until its task first pays a rollout let the synergy
rows find set #2's weight pull as soon as full-action PPO? finding_lag's set #2 table split the runs by
their weight pull head: every head that kept >= 1.0 nat per dimension over the first 0.5 M
env steps found it (0.19-0.77 M), most that narrowed below found it late or never. This
trains the confirmation plan's set #2 default row (DiscoSyn6-L-reward, `cpu` size, fast
physics) with `z_std_floor` (0.7: 1.06 nat per dimension) on seeds no set #2 run has used,
then prints finding_lag's table of the weight pull and the dice beside the plan's default and
PPO runs (seeds 3-7, docs/results/confirm-late-residual/).

  python -m studies.head_floor [--seeds 8 9 10] [--floor 0.7] [--out runs/head-floor]

A set #2 run is 1,200 train steps (6.1 M env steps), 24-79 min on 2 cores beside others."""

from __future__ import annotations

import argparse
import pathlib

BESIDE = pathlib.Path(__file__).resolve().parents[1] / "docs/results/confirm-late-residual"
PLAN = BESIDE / "plan.json"  # its set #2 default row, and beside it that row's and PPO's runs
FLOOR = 0.7


def configs(seeds, floor: float = FLOOR, steps: int | None = None):
  """(folder name, config, experiment.json) of the plan's set #2 default row with the floor."""
  from discosyn_jax.experiments import confirm
  from discosyn_jax.experiments.method import Method

  row = confirm.load(PLAN).row("set2-default")
  for seed in seeds:
    config = row.run_config(seed).replace(z_std_floor=floor)
    if steps is not None:
      config = config.replace(steps=steps)
    method = Method.of(config).name
    yield (f"{method.lower()}-set2-seed{seed}", config.validate(),
           {"experiment": "head-floor", "method": method, "set": "set2", "seed": seed,
            "scale": "cpu"})


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("--seeds", type=int, nargs="+", default=[8, 9, 10])
  parser.add_argument("--floor", type=float, default=FLOOR)
  parser.add_argument("--steps", type=int, help="train steps (default: the plan's 1,200)")
  parser.add_argument("--window", type=int, default=500_000,
                      help="env steps of a task over which finding_lag reads paid, H and bonus")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/head-floor"))
  args = parser.parse_args(argv)

  from studies.finding_lag import print_tables, runs
  from studies.residual_transfer import train_row

  for name, config, meta in configs(args.seeds, args.floor, args.steps):
    print(f"[{name}] train", flush=True)
    train_row(args.out, name, config, meta)
  print_tables(runs([args.out, BESIDE], "set2"), ["weight_pull", "dice"], args.window)


if __name__ == "__main__":
  main()
