"""When each run first finds a task, and what its head did before: why the synergy rows find
set #2's weight pull and dice later than full-action PPO, read from the records' training
logs, run by run, with no new training (and the same table for the planted test bed's
planted sets, studies/planted_lag.py).

Per run and task (the weight pull and the dice by default), from metrics.jsonl (the
stochastic policy that collects the samples) and eval.jsonl (the deterministic one):
  found      the task's env steps when its evaluated success first reaches 0.8 ('-': never)
  end        its success at the end (the mean of the last 3 evaluations)
  paid       the training rollouts' mean reward from the task's own term (the weight pull's
             lift, the dice's orientation, a planted task's reach) over the first WINDOW env
             steps of the task: how
             far the exploring policy reaches what the task pays before it is found
  H/dim      the head's entropy per dimension of what it samples (z for a synergy row, the
             20 actions for PPO) at the start and at the end of the window: how much the head
             still explores
  share      the task's share of the decoder's gradient over the window (decoder_share;
             '-' for PPO and for records from before it was logged): how much the task
             shapes the shared synergies while it is not yet found
  bonus      the discriminator bonus alpha2 log q(z|a) per step over the window (0 for PPO),
             beside `paid`: whether the bonus outweighs what the task pays

  python -m studies.finding_lag [RECORD_FOLDER ...] [--set set2] [--tasks weight_pull dice]
                               [--window 500000]

Defaults: set #2's committed records at the `cpu` scale (fast physics): every row of the
paper's tables, the residual rows, z free, and the confirmation's runs."""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

RECORDS = ("docs/results/paper", "docs/results/residual-set2", "docs/results/set2-zfree",
           "docs/results/confirm-late-residual")
# each task's own reward term: what it pays for the motion it asks for
TERM = {"weight_pull": "reward/lift", "dice": "reward/orientation", "valve3": "reward/turn",
        "screw": "reward/screw"}
PLANTED_TERM = "reward/reach"  # every planted task's (discosyn_jax/tasks/planted.py)


def term(task: str) -> str:
  if task in TERM:
    return TERM[task]
  if task.startswith("planted"):
    return PLANTED_TERM
  raise ValueError(f"finding_lag knows no reward term of {task!r}; known: {', '.join(TERM)}, planted*")


FOUND = 0.8  # success at which a task counts as found


def runs(folders, task_set: str = "set2") -> list:
  from discosyn_jax.experiments import report_runs

  found, _ = report_runs.find(folders)
  return [r for r in found if r.task_set == task_set and r.finished]


def found_at(run, task: str) -> int | None:
  from discosyn_jax.experiments import report

  return report.steps_to(run, task, FOUND)


def window_rows(run, window: int) -> list[dict]:
  return [row for row in run.metrics if run.per_task_env_steps(row) <= window]


def entropy_per_dim(run, task: str, row: dict) -> float:
  size = run.action_size if run.config.kind.full_action else run.config.n_synergies
  return row[f"{task}/entropy_z"] / size


def summary(run, task: str, window: int) -> dict:
  rows = window_rows(run, window)
  term_key = f"{task}/{term(task)}"
  return dict(found=found_at(run, task), end=run.at_end()[f"{task}/success"],
              paid=float(np.mean([r[term_key] for r in rows if term_key in r])),
              h_start=entropy_per_dim(run, task, rows[0]),
              h_end=entropy_per_dim(run, task, rows[-1]),
              share=_mean_of(rows, f"{task}/decoder_share"),
              bonus=float(np.mean([r.get(f"{task}/bonus", 0.0) for r in rows])))


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("folders", nargs="*", type=pathlib.Path,
                      default=[pathlib.Path(p) for p in RECORDS])
  parser.add_argument("--set", default="set2", help="the task set whose runs are read")
  parser.add_argument("--tasks", nargs="+", default=["weight_pull", "dice"])
  parser.add_argument("--window", type=int, default=500_000,
                      help="env steps of a task over which `paid`, H/dim and bonus are read")
  args = parser.parse_args(argv)
  for task in args.tasks:
    try:
      term(task)
    except ValueError as err:
      parser.error(str(err))
  print_tables(runs(args.folders, args.set), args.tasks, args.window)


def _mean_of(rows, key: str) -> float | None:
  values = [r[key] for r in rows if key in r]
  return float(np.mean(values)) if values else None


def in_order(found: list):
  """(method, run) of each run, in the report's order of rows, each row's runs by seed."""
  from discosyn_jax.experiments.report_runs import order

  for method in order({r.method for r in found}):
    for run in sorted((r for r in found if r.method == method), key=lambda r: r.seed):
      yield method, run


def print_tables(found: list, task_names, window: int) -> None:
  for task in task_names:
    print(f"\n{task}: found = env steps to evaluated success {FOUND}; end = success at the "
          f"end; over the first {window:,} env steps: paid = mean {term(task)} per step, H/dim = the head's "
          "entropy per dimension at its start and end, share = its share of the decoder's "
          "gradient, bonus = alpha2 log q per step\n")
    print("| method | seed | found | end | paid | H/dim start -> end | share | bonus |")
    print("|---|---|---|---|---|---|---|---|")
    for method, run in in_order(found):
      s = summary(run, task, window)
      at = "-" if s["found"] is None else f"{s['found'] / 1e6:.2f} M"
      share = "-" if s["share"] is None else f"{s['share']:.2f}"
      print(f"| {method} | {run.seed} | {at} | {s['end']:.2f} | {s['paid']:.4f} | "
            f"{s['h_start']:.2f} -> {s['h_end']:.2f} | {share} | {s['bonus']:.4f} |")


if __name__ == "__main__":
  main()
