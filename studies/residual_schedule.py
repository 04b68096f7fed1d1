"""Which schedule for the residual beside the synergies on a task set: a `-residual` preset
(cap 0.3 ramped in over the first half of its train steps) trained again with another ramp,
start or cap (in train steps here, stored as the config's shares of the run), one run at a time, each ending with its record (`discosyn keep`'s files) and an
experiment.json that names its row by the schedule (DiscoSyn6-L-reward-res0.3r150), so that
`discosyn report` shows it beside the experiment's rows; then a table per run: per task the
final success, its mean over the evaluation curve and the action shares at the end.

  python -m studies.residual_schedule --preset set2-disco6-linear-residual --ramp 150 \
      --seeds 0 1 --out runs/residual-schedule
"""

from __future__ import annotations

import argparse
import pathlib


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--preset", default="set2-disco6-linear-residual",
                      help="a residual row's preset (default: %(default)s)")
  parser.add_argument("--cap", type=float, help="rho's cap (default: the preset's)")
  parser.add_argument("--ramp", type=int, help="train steps of rho's ramp (default: the preset's)")
  parser.add_argument("--start", type=int, default=0,
                      help="train steps rho is held at 0 before its ramp (default: 0)")
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
  parser.add_argument("--steps", type=int, help="train steps (default: the preset's)")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/residual-schedule"))
  args = parser.parse_args(argv)

  from discosyn_jax.experiments import paper, presets, report_runs
  from discosyn_jax.experiments.method import Method
  from studies.residual_transfer import print_table, summary, train_row

  base = presets.preset(args.preset)
  if not base.residual:
    parser.error(f"{args.preset} has no residual: pick a preset ending in -residual")
  task_set = report_runs.set_of(base)
  changes = {"residual": args.cap, "steps": args.steps}
  base = base.replace(**paper.SCALES["cpu"].train_for(task_set),
                      **{k: v for k, v in changes.items() if v is not None})
  ramp = base.residual_ramp_step_count if args.ramp is None else args.ramp
  base = base.replace(residual_ramp=ramp / base.steps, residual_start=args.start / base.steps)
  rows = []
  for seed in args.seeds:
    config = base.replace(seed=seed).validate()
    method = Method.of(config).name
    meta = {"experiment": f"discosyn-{task_set}", "method": method, "set": task_set,
            "seed": seed, "scale": "cpu"}  # a row of its set's table
    run_dir = train_row(args.out, f"{method.lower()}-{task_set}-seed{seed}", config, meta)
    rows.append((run_dir.name, summary(run_dir)))
  print_table(rows)


if __name__ == "__main__":
  main()
