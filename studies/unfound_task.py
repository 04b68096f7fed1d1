"""Does keeping a task that is not yet found exploring let the synergy rows find set #2's
weight pull as soon as full-action PPO? Trains the confirmation plan's set #2 default row
(DiscoSyn6-L-reward, `cpu` size, fast physics) with one change, on seeds no set #2 run of the
plan has used, then prints finding_lag's table of the weight pull and the dice beside the
plan's default and PPO runs (seeds 3-7, docs/results/confirm-late-residual/):

  floor        each head's z std held at >= 0.7 (1.06 nat per dimension) until its task first
               pays a rollout (`z_std_floor`): every set #2 task, the weight pull too, is
               paid +0.01 in its first rollout, so it holds nothing there
  task-noise-bonus-cap
               each task's own decoder noise (`task_noise`) and its bonus capped at the
               spread of what it pays (`bonus_cap`): on the planted bed it found the unpaid
               task on 2 of the 4 seeds the preset never did; on set #2 the weight pull's
               bonus is scaled to 0.01-0.1 in the rollouts that lift nothing

  python -m studies.unfound_task [--variant floor] [--seeds 8 9 10] [--out runs/unfound-task]

A set #2 run is 1,200 train steps (6.1 M env steps), 24-79 min on 2 cores beside others."""

from __future__ import annotations

import argparse
import pathlib

from studies import planted_lag  # its variants' changes (no JAX)

BESIDE = pathlib.Path(__file__).resolve().parents[1] / "docs/results/confirm-late-residual"
PLAN = BESIDE / "plan.json"  # its set #2 default row, and beside it that row's and PPO's runs
# the planted bed's changes of the same names (studies/planted_lag.py)
VARIANTS = {name: planted_lag.VARIANTS[name] for name in ("floor", "task-noise-bonus-cap")}


def configs(seeds, variant: str = "floor", steps: int | None = None):
  """(folder name, config, experiment.json) of the plan's set #2 default row with the
  variant's change."""
  from discosyn_jax.experiments import confirm
  from discosyn_jax.experiments.method import Method

  row = confirm.load(PLAN).row("set2-default")
  for seed in seeds:
    config = row.run_config(seed).replace(**VARIANTS[variant])
    if steps is not None:
      config = config.replace(steps=steps)
    method = Method.of(config).name
    yield (f"{method.lower()}-set2-seed{seed}", config.validate(),
           {"experiment": "unfound-task", "method": method, "set": "set2", "seed": seed,
            "scale": "cpu"})


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("--variant", default="floor", choices=list(VARIANTS))
  parser.add_argument("--seeds", type=int, nargs="+", default=[8, 9, 10])
  parser.add_argument("--steps", type=int, help="train steps (default: the plan's 1,200)")
  parser.add_argument("--window", type=int, default=500_000,
                      help="env steps of a task over which finding_lag reads paid, H and bonus")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/unfound-task"))
  args = parser.parse_args(argv)

  from studies.finding_lag import print_tables, runs
  from studies.residual_transfer import train_row

  for name, config, meta in configs(args.seeds, args.variant, args.steps):
    print(f"[{name}] train", flush=True)
    train_row(args.out, name, config, meta)
  print_tables(runs([args.out, BESIDE], "set2"), ["weight_pull", "dice"], args.window)


if __name__ == "__main__":
  main()
