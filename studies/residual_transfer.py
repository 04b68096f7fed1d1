"""Which residual cap for a frozen decoder on tasks it was not learned for: the frozen runs
that `discosyn experiment transfer` / `sparse` made from the residual row's decoder
(`<experiment>-synergies-residual-...`, cap 0.3 ramped in over the first half), trained
again with other caps, the same config otherwise, one run at a time; then a table per cap
and seed: per task the final success and its mean over the evaluation curve, and the
action shares at the end.

  python -m studies.residual_transfer --runs runs/residual-frozen --caps 0.6 1.0 \
      --frozen transfer-synergies-residual-set1 --seeds 0 1 2 --out runs/residual-transfer-caps
"""

from __future__ import annotations

import argparse
import json
import pathlib


def summary(run_dir: pathlib.Path) -> dict[str, tuple[float, float, float | None, float | None]]:
  """Per task: final success, its mean over the curve, |D(z)| and rho |r| at the end."""
  import discosyn_jax as ds

  run = ds.read_run(run_dir)
  shares = run.action_shares()
  return {t: (run.success[t], run.curve[t], *shares.get(t, (None, None))) for t in run.success}


def print_table(rows) -> None:
  """A markdown row per run and task of [(run name, summary(run_dir))]."""
  print("| run | task | final success | mean over the curve | abs D(z) | rho abs(r) |")
  print("|---|---|---|---|---|---|")
  share = lambda value: "–" if value is None else f"{value:.3f}"
  for name, per_task in rows:
    for task, (final, curve, synergy, residual) in per_task.items():
      print(f"| {name} | {task} | {final:.2f} | {curve:.2f} | {share(synergy)} | {share(residual)} |")


def frozen_meta(source: pathlib.Path, config) -> dict:
  """The frozen run's experiment.json with its method named by this run's residual
  ('DiscoSyn3-L-reward-res0.3r150 frozen-res1r150'), so `discosyn report` shows it as a
  transfer row of its own."""
  from discosyn_jax.experiments.method import Method, Residual
  from discosyn_jax.run import layout

  meta = json.loads((source / layout.EXPERIMENT_FILE).read_text())
  method = Method.parse(meta["method"]).replace(acting_residual=Residual.of(config))
  meta["method"] = method.name
  return meta


def train_row(out: pathlib.Path, name: str, config, meta: dict) -> pathlib.Path:
  """Train `config` into OUT/NAME as a step of `discosyn experiment` does (resumed where
  unfinished, kept where finished), ending with its record and experiment.json `meta`."""
  from discosyn_jax.experiments import paper

  step, quiet = paper.Train(name, config, meta), lambda *a: None
  if step.done(out):
    step.settle(out, quiet)
  else:
    step.run(out, False, quiet)
  return out / name


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--runs", type=pathlib.Path, default=pathlib.Path("runs/residual-frozen"),
                      help="the experiment's folder, which holds the frozen runs")
  parser.add_argument("--frozen", default="transfer-synergies-residual-set1",
                      help="the frozen runs' folder name before -seed<n>")
  parser.add_argument("--caps", type=float, nargs="+", default=[0.6, 1.0])
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
  parser.add_argument("--steps", type=int, help="train steps (default: the frozen run's)")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/residual-transfer-caps"))
  args = parser.parse_args(argv)

  from discosyn_jax.experiments import record

  rows = []
  for seed in args.seeds:
    source = args.runs / f"{args.frozen}-seed{seed}"
    rows.append((source.name, summary(source)))
    for cap in args.caps:
      config = record.saved_config(source).replace(residual=cap)
      config = (config if args.steps is None else config.replace(steps=args.steps)).validate()
      run_dir = train_row(args.out, f"{args.frozen}-cap{cap:g}-seed{seed}", config,
                          frozen_meta(source, config))
      rows.append((run_dir.name, summary(run_dir)))
  print_table(rows)


if __name__ == "__main__":
  main()
