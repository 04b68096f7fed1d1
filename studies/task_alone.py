"""Does a task of set #2 learn later inside its set than alone? Trains one task alone at the
budget it gets inside the set (1,200 train steps x 64 envs x 20 steps: 1.54 M env steps,
`cpu` size, fast physics) with the confirmation plan's set #2 default row (DiscoSyn6-L-reward:
six synergies learned from the reward prior of that task alone) and with full-action PPO,
then prints, per row, the task alone beside the same row's set #2 runs of the committed
confirmations (seeds 3-7 and 11-15): over the curve, at the end, and the env steps of the
task to the first evaluation at 0.8.

Read together: a synergy row that is as fast as PPO alone and slower inside the set is slowed
by sharing its decoder with the other tasks; one as slow alone is slowed by the
low-dimensional space itself. With --sources, the default row on the task alone starts
instead from each set #2 run's learned decoder and learns on (the seed the source's): as fast
as from the task's own prior, the set's space holds the task and what slows it inside the
set is the joint training; as slow as inside the set, the space itself.

  python -m studies.task_alone [--task dice] [--seeds 0 1 2] [--synergies B]
                               [--sources RECORD ...] [--out runs/task-alone]

A run is a quarter of a set #2 run: 10-15 min two side by side on 2 cores."""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs/results"
PLAN = RESULTS / "confirm-task-noise-bonus-cap/plan.json"  # its set #2 default and PPO rows
ROWS = ("set2-default", "set2-ppo")
BESIDE = (RESULTS / "confirm-late-residual", RESULTS / "confirm-task-noise-bonus-cap")


def configs(task: str, seeds, steps: int | None = None, synergies: int | None = None):
  """(folder name, config, experiment.json) of each plan row on `task` alone (the synergy
  row with `synergies` synergies where given)."""
  from discosyn_jax.experiments import confirm

  plan = confirm.load(PLAN)
  for row_name in ROWS:
    row = plan.row(row_name)
    for seed in seeds:
      config = row.run_config(seed).replace(tasks=(task,))
      if synergies and not config.kind.full_action:
        config = config.replace(n_synergies=synergies)
      yield _step(config, steps)


def from_set(task: str, sources, out: pathlib.Path, steps: int | None = None):
  """(folder name, config, experiment.json) of the default row on `task` alone, its decoder
  learned on from each set #2 source's (its seed the source's). Each source's record is
  copied beside the runs, so that a kept run names its decoder by that sibling folder."""
  from discosyn_jax.experiments import confirm, record
  from studies.transfer_learned import beside

  row = confirm.load(PLAN).row(ROWS[0])
  for given in sources:
    source = beside(out, given)
    seed = record.saved_config(source).seed
    yield _step(row.run_config(seed).replace(
        tasks=(task,), decoder_init="random",
        decoder_from=str((source / "decoder.npz").resolve())), steps)


def _step(config, steps: int | None):
  """(folder name, config, experiment.json) of a run of `config` on its one task."""
  from discosyn_jax.experiments import report_runs

  if steps is not None:
    config = config.replace(steps=steps)
  method = report_runs.method_of(config).name  # ' tuned' where it learns on a set's decoder
  task, seed = config.tasks[0], config.seed
  return (f"{method.lower().replace(' ', '-')}-{task}-seed{seed}", config.validate(),
          {"experiment": "task-alone", "method": method, "set": task, "seed": seed,
           "scale": "cpu"})


def summary(run, task: str) -> dict:
  from studies.finding_lag import found_at

  return dict(curve=run.curve[task], end=run.at_end()[f"{task}/success"],
              found=found_at(run, task))


def table(alone: list, in_set: list, task: str) -> list[str]:
  """Markdown rows: each method alone and inside set #2, its seeds' figures and their mean."""
  lines = [f"| row | where | seeds | {task} over the curve | at the end | env steps of the "
           "task to 0.8 (M) |", "|---|---|---|---|---|---|"]
  for method in sorted({r.method.name for r in alone} | {r.method.name for r in in_set}):
    for where, runs in (("alone", alone), ("in set #2", in_set)):
      mine = sorted((r for r in runs if r.method.name == method), key=lambda r: r.seed)
      if not mine:
        continue
      s = [summary(r, task) for r in mine]
      found = ", ".join("-" if x["found"] is None else f"{x['found'] / 1e6:.2f}" for x in s)
      lines.append(
          f"| {method} | {where} | {', '.join(str(r.seed) for r in mine)} | "
          f"{_listed([x['curve'] for x in s])} | {_listed([x['end'] for x in s])} | "
          f"{found} ({sum(x['found'] is not None for x in s)} of {len(s)}) |")
  return lines


def _listed(values) -> str:
  return f"{', '.join(f'{v:.2f}' for v in values)} (**{np.mean(values):.2f}**)"


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("--task", default="dice", choices=["dice", "valve3", "weight_pull", "screw"])
  parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2],
                      help="seeds of the rows from the task's own prior (none: --seeds alone)")
  parser.add_argument("--sources", type=pathlib.Path, nargs="*", default=[], metavar="RECORD",
                      help="set #2 runs (or records) whose decoders the default row learns on from")
  parser.add_argument("--synergies", type=int,
                      help="the synergy row's b (default: the plan's 6; set #2's reward prior "
                           "gives each task one or two of its six directions)")
  parser.add_argument("--steps", type=int, help="train steps (default: the plan's 1,200)")
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/task-alone"))
  args = parser.parse_args(argv)

  from studies.finding_lag import runs
  from studies.residual_transfer import train_row

  for source in args.sources:
    if not (source / "decoder.npz").is_file():
      parser.error(f"{source} holds no decoder.npz: give a set #2 run or record folder")
  made = [*configs(args.task, args.seeds, args.steps, args.synergies),
          *from_set(args.task, args.sources, args.out, args.steps)]
  for name, config, meta in made:
    print(f"[{name}] train", flush=True)
    train_row(args.out, name, config, meta)
  in_set = [r for r in runs(BESIDE, "set2") if r.method.name in _methods()]
  print("\n".join(table(runs([args.out], args.task), in_set, args.task)))


def _methods() -> set[str]:
  """The plan rows' method names (the in-set runs read beside the task alone)."""
  from discosyn_jax.experiments import confirm
  from discosyn_jax.experiments.method import Method

  plan = confirm.load(PLAN)
  return {Method.of(plan.row(name).run_config(0)).name for name in ROWS}


if __name__ == "__main__":
  main()
