"""The budget each of the paper's rows needs: from runs of the `long` scale (the `cpu` runs
8x as long, evaluated as often, a constant learning rate: one run's curve gives its success
at every budget up to its end), per run and budget (1x, 2x, 4x, 8x the `cpu` scale's train
steps): the final success per task (the mean of the last 3 evaluations up to that budget),
the tasks solved (>= 0.8), the mean over the curve up to it; and how far the decoder has
moved by then (metrics.jsonl: |W - W0| / |W0|, the smallest principal cosine to its start,
the overlap with it). Then the first budget at which the run solves every task, and its
decoder's overlap at the end with a reference space (the default's learned decoder of the
same seed, docs/results/paper/discosyn3-l-reward-set1-seed<seed>); and, for a row with two
seeds or more, how far their learned spaces agree at the end (the overlap of each pair,
beside a random pair's).

  python -m studies.paper_budget RUN ... [--reference-folder docs/results/paper]

Reads logs and records only, no training; the runs: `discosyn experiment discosyn-set1
--scale long --seeds S --methods ROW --out runs/long` (and baselines-set1 for PPO)."""

from __future__ import annotations

import argparse
import dataclasses
import pathlib

RESULTS = pathlib.Path(__file__).resolve().parents[1] / "docs/results"
MULTIPLES = (1, 2, 4, 8, 16)
SOLVED = 0.8


def cpu_steps(task_set: str) -> int:
  from discosyn_jax.experiments import paper

  return paper.SCALES["cpu"].train_for(task_set)["steps"]


def upto(run, step: int):
  """The run as it stood at train step `step`: its evaluations up to it."""
  return dataclasses.replace(run, evaluations=[r for r in run.evaluations if r["step"] <= step])


def final_at(run, step: int) -> dict[str, float] | None:
  """Per task, the run's final success at train step `step` (Run.at_end: the mean of the
  last 3 evaluations up to it)."""
  end = upto(run, step).at_end()
  return {t: end[f"{t}/success"] for t in run.config.tasks} if end else None


def curve_at(run, step: int) -> float:
  return upto(run, step).mean_success


def drift_at(run, step: int) -> dict[str, float]:
  rows = [r for r in run.metrics if r["step"] <= step and "decoder/change" in r]
  return rows[-1] if rows else {}


def first_solved(run) -> int | None:
  """Env steps of the first evaluation at which every task's final (`final_at`) is >= SOLVED."""
  for row in run.evaluations:
    final = final_at(run, row["step"])
    if final and min(final.values()) >= SOLVED:
      return int(row["env_steps"])
  return None


def reference_overlap(run, folder: pathlib.Path) -> float | None:
  from discosyn_jax.synergies import diagnostics, discovery

  reference = folder / f"discosyn3-l-reward-set1-seed{run.config.seed}"
  mine, theirs = discovery.learned_basis(run.path), discovery.learned_basis(reference)
  if mine is None or theirs is None:
    return None
  return float(diagnostics.overlap(mine, theirs))


def table(runs, reference: pathlib.Path) -> str:
  lines = ["| run | budget | env steps | final per task | solved | mean over the curve | "
           "W change | smallest cosine to its start | overlap with its start |",
           "|---|---|---|---|---|---|---|---|---|"]
  ends = []
  for run in runs:
    base = cpu_steps(run.task_set)
    last = run.evaluations[-1]["step"]
    per_step = run.evaluations[-1]["env_steps"] / last
    for k in (k for k in MULTIPLES if k * base <= last):
      final, drift = final_at(run, k * base), drift_at(run, k * base)
      cell = lambda key: f"{drift[key]:.3f}" if key in drift else "-"
      lines.append(
          f"| {run.path.name} | {k}x | {k * base * per_step / 1e6:.2f} M | "
          + " / ".join(f"{v:.2f}" for v in final.values())
          + f" | {sum(v >= SOLVED for v in final.values())}/{len(final)} | "
          f"{curve_at(run, k * base):.2f} | {cell('decoder/change')} | "
          f"{cell('decoder/cos_min')} | {cell('decoder/overlap_start')} |")
    first = first_solved(run)
    overlap = reference_overlap(run, reference)
    ends.append(f"| {run.path.name} | {'never' if first is None else f'{first / 1e6:.2f} M'}"
                f" ({'-' if first is None else f'{first / (base * per_step):.1f}x'}) | "
                f"{'-' if overlap is None else f'{overlap:.3f}'} |")
  return ("\n".join(lines) + "\n\n| run | every task solved first at (x cpu) | "
          "overlap of its end with the default's learned space |\n|---|---|---|\n"
          + "\n".join(ends) + "\n")


def across_seeds(runs) -> str:
  """Per row with two seeds or more: the overlap of each pair of seeds' learned spaces at the
  end, and a random pair's (chance)."""
  from discosyn_jax.synergies import diagnostics, discovery

  lines = ["| row | seeds | overlap of each pair at the end | chance |", "|---|---|---|---|"]
  for method in dict.fromkeys(run.method for run in runs):
    group = sorted((r for r in runs if r.method == method), key=lambda r: r.seed)
    bases = [discovery.learned_basis(r.path) for r in group]
    if len(group) < 2 or any(b is None for b in bases):
      continue
    pairs = discovery.cross_seed(bases)
    lines.append(f"| {method} | {', '.join(str(r.seed) for r in group)} | "
                 f"{' / '.join(f'{v:.3f}' for v in pairs)} | "
                 f"{diagnostics.chance_overlap(bases[0].shape[1], bases[0].shape[1]):.2f} |")
  return "\n".join(lines) + "\n"


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("runs", nargs="+", type=pathlib.Path)
  parser.add_argument("--reference-folder", type=pathlib.Path, default=RESULTS / "paper",
                      help="the folder of the default's runs whose learned space each run's "
                           "end is compared with (the same seed)")
  args = parser.parse_args(argv)
  from discosyn_jax.experiments import report_runs

  runs, _ = report_runs.find(args.runs)
  print(table(runs, args.reference_folder))
  print(across_seeds(runs))


if __name__ == "__main__":
  main()
