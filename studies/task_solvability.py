"""Can full-action PPO learn each task? One `valve3-ppo`-style run per task and
seed, up to 10 M env steps, ended at the first evaluation at which its deterministic success
reaches 80 % (`train --stop-at`); then the table of the curves.

  python studies/task_solvability.py --tasks dice weight_pull screw valve_cw --seeds 0 1
  python studies/task_solvability.py --summary runs/solvability      # the table only

Each run goes to OUT/<task>-seed<n> (an unfinished one is resumed, a finished one kept), so
two invocations with different tasks or seeds can share the two cores. The random policy's
rates to put beside them: studies/task_calibration.py. Results: docs/TASKS_NOTES.md.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import discosyn_jax  # noqa: E402
from discosyn_jax.run import jax_setup  # noqa: E402

jax_setup.setup_jax()  # the compile cache; MJX imported quietly

from discosyn_jax import config as config_lib  # noqa: E402
from discosyn_jax.run import layout, logs
from discosyn_jax.experiments import presets, record  # noqa: E402

TARGET = 0.8  # deterministic success that counts as learnt
MAX_ENV_STEPS = 10_000_000


def config_for(task: str, seed: int, eval_every: int) -> config_lib.TrainConfig:
  base = presets.preset("valve3-ppo")
  steps = math.ceil(MAX_ENV_STEPS / (base.num_envs * base.unroll_length))
  return base.replace(tasks=(task,), seed=seed, steps=steps, eval_every=eval_every,
                      checkpoint_every=eval_every).validate()


def summary(out: pathlib.Path) -> str:
  lines = [f"| run | first >= {TARGET:.0%} at env steps | best (env steps) | last evaluation | "
           "success every ~1 M env steps |", "|---|---|---|---|---|"]
  runs = sorted(p for p in out.iterdir() if (p / layout.EVAL_FILE).is_file()) if out.is_dir() else []
  for run in runs:
    config = config_lib.load(run / layout.CONFIG_FILE)
    (task,) = config.tasks
    evals = [(row["env_steps"], row[f"{task}/success"]) for row in logs.read_jsonl(run / layout.EVAL_FILE)]
    if not evals:
      continue
    first = next((f"{steps:,}" for steps, success in evals if success >= TARGET), "not reached")
    best = max(evals, key=lambda e: e[1])
    curve, next_mark = [], 0
    for steps, success in evals:
      if steps >= next_mark:
        curve.append(f"{success:.2f}@{steps / 1e6:.1f}M")
        next_mark = steps + 1_000_000
    lines.append(f"| {run.name} | {first} | {best[1]:.2f} ({best[0]:,}) | "
                 f"{evals[-1][1]:.2f} ({evals[-1][0]:,}) | {' '.join(curve)} |")
  return "\n".join(lines)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=["dice", "weight_pull", "screw", "valve_cw"],
                      help="tasks to train (default: set #2's new tasks and valve_cw)")
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1], help="one run per seed")
  parser.add_argument("--eval-every", type=int, default=50,
                      help="train steps between evaluations (128 k env steps at 50)")
  parser.add_argument("--out", default="runs/solvability", help="folder of the runs")
  parser.add_argument("--summary", metavar="OUT", help="print the table of OUT and stop")
  args = parser.parse_args(argv)
  if args.summary:
    print(summary(pathlib.Path(args.summary)))
    return
  out = pathlib.Path(args.out)
  for task in args.tasks:
    for seed in args.seeds:
      config = config_for(task, seed, args.eval_every)
      run = out / f"{task}-seed{seed}"
      if not record.finished(run, config):
        discosyn_jax.train(config, run, resume=(run / layout.CONFIG_FILE).is_file(),
                           progress=False, stop_at=TARGET)
  print(summary(out))


if __name__ == "__main__":
  main()
