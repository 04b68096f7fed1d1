"""`discosyn report RUN_DIRS...`: the paper's tables and figures from run folders.

Writes OUT/REPORT.md and PNG figures beside it:
  - tables of solved tasks per task set, in the paper's layout (a row per method, a column
    per task), each cell with the final deterministic success, mean (min–max) [seeds], and
    the paper's mark beside the paper's rows (DiscoSyn<b>-L: both the paper's start and
    today's default, -reward); per row the success over the set's tasks at the end and
    over the whole curve (methods are judged over the budget and at its end);
  - explained variance of the sequential baselines' PCA / autoencoder fits;
  - training curves (evaluation success against env steps of that task, per method);
  - t-SNE of the z the DiscoSyn policy picks, coloured by task (the paper's Fig. 6);
  - for rows with a residual beside the synergies, how much of the action each part carries;
  - transfer to unseen tasks and the sparse goal valve: per method and task the final
    success, the mean over the curve, the env steps to the threshold, and for the sparse
    valve the env steps to the first reward; curves;
  - per task set (each of the above), intervals a reviewer can trust from a few seeds
    (intervals.py, rliable): per method the IQM and the mean of the final success and of
    the mean over the curve over runs x tasks, the probability that the set's default row
    improves on it, each with its 95 % stratified bootstrap interval, and the performance
    profiles; a fixed bootstrap seed makes them the same on every run.

"Solved" is: the mean over seeds of the final evaluation's success >= `threshold`, a
threshold on a mean: the intervals say which differences the seeds support.
A run's method and set come from its experiment.json (written by `discosyn experiment`), or
else from its config. It reads a run's record where its checkpoints are not kept
(discosyn_jax/experiments/record.py). The text is the same wherever and whenever it is made from the
same folders: no date, and the folders named relative to the report's own.
"""

from __future__ import annotations

import os
import pathlib
import re
import shutil
from typing import Any

import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.experiments import confirm, intervals, record, report_figures
from discosyn_jax.experiments.method import Method
from discosyn_jax.experiments.presets import REWARDED
from discosyn_jax.experiments.report_runs import FINAL_K, LabelledRun, find, order
from discosyn_jax import tasks
from discosyn_jax.tasks import TASK_SETS

# The paper's Tables I and II (1 = solved, columns in these tasks' order) and its PCA
# explained variance on set #1.
PAPER_SOLVED = {
    "set1": {"PCA4": "0000", "AE4": "1011", "PCA6": "1001", "AE6": "1011", "DiscoSyn3-L": "1111",
             "DiscoSyn3-NL": "1111", "DiscoSyn4-L": "1111", "DiscoSyn4-NL": "1111"},
    "set2": {"PCA4": "0001", "AE4": "1001", "PCA6": "1001", "AE6": "1001", "DiscoSyn4-L": "1100",
             "DiscoSyn4-NL": "1111", "DiscoSyn6-L": "1111", "DiscoSyn6-NL": "1111"},
}
PAPER_PCA_VARIANCE = {"set1": {3: 0.415, 4: 0.508, 6: 0.628}}


def paper_row(method: Method) -> str:
  """The paper's row a method stands for: its own name, and for today's default start of a
  DiscoSyn decoder (DiscoSyn3-L-reward) the paper's DiscoSyn3-L."""
  if method == Method("DiscoSyn", method.synergies, method.decoder, start="reward"):
    return method.replace(start="").name
  return method.name


# -- tables ---------------------------------------------------------------------
def _success(runs: list[LabelledRun], task: str) -> np.ndarray:
  return np.array([r.final[f"{task}/success"] for r in runs if f"{task}/success" in r.final])


def _percent(values: np.ndarray) -> str:
  """mean (min–max) of success rates; – for none."""
  if values.size == 0:
    return "–"
  spread = f" ({values.min():.0%}–{values.max():.0%})" if values.size > 1 else ""
  return f"{values.mean():.0%}{spread}"


def _cell(values: np.ndarray, threshold: float, paper: str | None) -> str:
  if values.size == 0:
    return "–"
  mark = "✓" if values.mean() >= threshold else "✗"
  paper_mark = "" if paper is None else f" (paper {'✓' if paper == '1' else '✗'})"
  return f"{mark} {_percent(values)} [{values.size}]{paper_mark}"


def _mean_success(run: LabelledRun, task_names, over_curve: bool) -> float | None:
  """A run's success averaged over `task_names`, at its end (the mean of its last k
  evaluations, LabelledRun.final) or averaged over all its evaluations (the mean over the curve);
  None where one is missing."""
  rows = run.evaluations if over_curve else [run.final] if run.evaluations else []
  values = [row.get(f"{t}/success") for row in rows for t in task_names]
  return float(np.mean(values)) if values and None not in values else None


def _mean_over_tasks(group: list[LabelledRun], task_names, over_curve: bool = False) -> str:
  """Each seed's success averaged over the set's tasks (`_mean_success`), then the mean
  (min-max) over seeds: the figure the targets for a learned decoder compare."""
  per_seed = [_mean_success(r, task_names, over_curve) for r in group]
  return _percent(np.array([v for v in per_seed if v is not None]))


def _closing_over_tasks(group: list[LabelledRun], task_names) -> str:
  """Each seed's closing evaluation averaged over the set's tasks, then the mean (min-max)
  [seeds] over the seeds that have one."""
  values = np.array([np.mean([r.closing[f"{t}/success"] for t in task_names]) for r in group
                     if r.closing and all(f"{t}/success" in r.closing for t in task_names)])
  return f"{_percent(values)} [{values.size}]" if values.size else "–"


def solved_tables(runs: list[LabelledRun], threshold: float) -> str:
  lines = []
  main = [r for r in runs if r.main]
  for task_set in sorted({r.task_set for r in main}):
    in_set = [r for r in main if r.task_set == task_set]
    task_names = list(in_set[0].config.tasks)
    paper = PAPER_SOLVED.get(task_set, {})
    closing = any(r.closing for r in in_set)  # a column where a run of the set has one
    lines += [f"### {task_set}: tasks solved (success >= {threshold:.0%})", "",
              "| method | " + " | ".join(map(tasks.label, task_names))
              + " | mean | over the curve |" + (" closing |" if closing else "") + " solved |",
              "|---" * (len(task_names) + 4 + closing) + "|"]
    for method in order({r.method for r in in_set}):
      group = [r for r in in_set if r.method == method]
      cells, solved = [], 0
      paper_tasks = TASK_SETS[task_set] if task_set in PAPER_SOLVED else ()
      marks = paper.get(paper_row(method))
      for task in task_names:
        values = _success(group, task)
        mark = marks[paper_tasks.index(task)] if marks and task in paper_tasks else None
        cells.append(_cell(values, threshold, mark))
        solved += bool(values.size and values.mean() >= threshold)
      paper_count = (f" (paper {marks.count('1')}/4)"
                     if marks and set(paper_tasks) == set(task_names) else "")
      unfinished = sum(not r.finished for r in group)
      note = f", {unfinished} unfinished" if unfinished else ""
      closing_cell = f" | {_closing_over_tasks(group, task_names)}" if closing else ""
      lines.append(f"| {method} | " + " | ".join(cells) + f" | {_mean_over_tasks(group, task_names)}"
                   f" | {_mean_over_tasks(group, task_names, over_curve=True)}{closing_cell}"
                   f" | {solved}/{len(task_names)}{paper_count}{note} |")
    lines.append("")
  return "\n".join(lines)


def variance_table(fits: list[dict[str, Any]]) -> str:
  sizes = sorted({int(k) for f in fits for m in ("PCA", "AE") for k in f.get(m, {})})
  lines = ["| set | method | " + " | ".join(f"k = {k}" for k in sizes) + " | samples |",
           "|---" * (len(sizes) + 3) + "|"]
  for task_set in sorted({f["set"] for f in fits}):
    group = [f for f in fits if f["set"] == task_set]
    for method in ("PCA", "AE"):
      cells = []
      for k in sizes:
        values = np.array([f[method][str(k)] for f in group if str(k) in f.get(method, {})])
        cell = "–" if values.size == 0 else f"{values.mean():.1%}" + (
            f" ± {values.std():.1%}" if values.size > 1 else "")
        paper = PAPER_PCA_VARIANCE.get(task_set, {}).get(k) if method == "PCA" else None
        cells.append(cell + (f" (paper {paper:.1%})" if paper is not None else ""))
      samples = ", ".join(str(f["samples"]) for f in group)
      lines.append(f"| {task_set} | {method} | " + " | ".join(cells) + f" | {samples} |")
  lines.append("| any | DiscoSyn | " + " | ".join("100% (by construction)" for _ in sizes) + " | |")
  return "\n".join(lines) + "\n"


def decoder_table(runs: list[LabelledRun], last: int = 10) -> str:
  """Is the synergy space learned? Per run with a decoder: its movement from the initial
  decoder at the end (diagnostics.py), the gradient norms of decoder and heads, and the
  discriminator's bonus beside the env's reward per step (means over the last `last` logged
  train steps). A frozen decoder's gradient is computed but never applied: marked so."""
  lines = ["| run | env steps | W change | principal cosines | decoder / heads grad norm "
           "| bonus / reward per step |", "|---|---|---|---|---|---|"]
  for run in sorted(runs, key=lambda r: (r.task_set, r.method, r.seed)):
    rows = [r for r in run.metrics if "decoder/change" in r][-last:]
    if not rows:
      continue
    end = rows[-1]
    cosines = " / ".join(f"{end[f'decoder/cos_{k}']:.3f}"
                         for k in range(1, run.config.n_synergies + 1) if f"decoder/cos_{k}" in end)
    mean = lambda key: float(np.mean([r.get(key, np.nan) for r in rows]))
    tasks = run.config.tasks
    bonus = np.mean([mean(f"{t}/bonus") for t in tasks])
    reward = np.mean([mean(f"{t}/reward") for t in tasks])
    frozen = " (frozen)" if run.config.freeze_decoder else ""
    lines.append(f"| {run.method} {run.task_set} seed {run.seed} | {end['env_steps']:,.0f} | "
                 f"{end['decoder/change']:.1%} | {cosines} | {mean('grad_norm/decoder'):.3g}"
                 f"{frozen} / {mean('grad_norm/heads'):.3g} | {bonus:.3f} / {reward:.3f} |")
  return "\n".join(lines) + "\n" if len(lines) > 2 else ""


def residual_table(runs: list[LabelledRun], last: int = 10) -> str:
  """Do the synergies still do the work? Per method, set and task with a residual beside
  the decoder: the mean |D(z)| and rho |r| per actuator, and their ratio, over the last `last`
  logged train steps (agent/residual.py), over seeds."""
  lines = ["| method | set | task | rho at the end | synergies' share abs(D(z)) | residual's "
           "share rho abs(r) | residual / synergies |", "|---|---|---|---|---|---|---|"]
  with_residual = [r for r in runs if r.config.residual > 0]
  for task_set in sorted({r.task_set for r in with_residual}):
    for method in order({r.method for r in with_residual if r.task_set == task_set}):
      group = [r for r in with_residual if r.task_set == task_set and r.method == method]
      ends = [[row for row in r.metrics
               if "residual/rho" in row][-last:] for r in group]
      ends = [rows for rows in ends if rows]
      if not ends:
        continue
      rho = np.array([rows[-1]["residual/rho"] for rows in ends])
      for task in group[0].config.tasks:
        mean = lambda key: np.array([np.mean([row[key] for row in rows]) for rows in ends])
        synergy, res = mean(f"{task}/action_synergy"), mean(f"{task}/action_residual")
        lines.append(f"| {method} | {task_set} | {tasks.label(task)} | {_spread(rho)} | "
                     f"{_spread(synergy)} | "
                     f"{_spread(res)} | {_spread(res / synergy)} |")
  return "\n".join(lines) + "\n" if len(lines) > 2 else ""


def _spread(values) -> str:
  """mean (min–max) [count] of some overlaps; – for none."""
  values = np.asarray(values, float)
  if values.size == 0:
    return "–"
  spread = f" ({values.min():.2f}–{values.max():.2f})" if values.size > 1 else ""
  return f"{values.mean():.2f}{spread} [{values.size}]"


def discovery_table(runs: list[LabelledRun]) -> str:
  """Is the synergy space discovered? Per method and set with a decoder: the overlaps
  (diagnostics.py) of the seeds' learned subspaces, pair by pair, beside those of the same
  seeds' initial decoders; each seed's overlap with its own start, and with the planted
  span on planted tasks (both as logged at the run's last step); and the chance level."""
  from discosyn_jax.synergies import diagnostics, discovery

  lines = ["| method | set | learned, seed pairs | initial, seed pairs | each seed with its start "
           "| each seed with the planted span | chance |", "|---|---|---|---|---|---|---|"]
  decoders = [r for r in runs if not r.config.kind.full_action]
  for task_set in sorted({r.task_set for r in decoders}):
    for method in order({r.method for r in decoders if r.task_set == task_set}):
      group = sorted((r for r in decoders if r.task_set == task_set and r.method == method),
                     key=lambda r: r.seed)
      learned = [b for b in map(discovery.learned_basis, (r.path for r in group)) if b is not None]
      n = group[0].action_size
      initial = [b for b in (discovery.initial_basis(r.config, n) for r in group) if b is not None]
      ends = [_last_logged(r) for r in group]
      start = [e["decoder/overlap_start"] for e in ends if "decoder/overlap_start" in e]
      planted = [e["decoder/overlap_planted"] for e in ends if "decoder/overlap_planted" in e]
      b = group[0].config.n_synergies
      lines.append(f"| {method} | {task_set} | {_spread(discovery.cross_seed(learned))} | "
                   f"{_spread(discovery.cross_seed(initial))} | {_spread(start)} | "
                   f"{_spread(planted)} | {diagnostics.chance_overlap(b, b, n):.2f} |")
  return "\n".join(lines) + "\n" if len(lines) > 2 else ""


def _last_logged(run: LabelledRun) -> dict[str, Any]:
  """The decoder's figures at the last logged train step of a run ({} if none): the
  overlap with its start derived from the cosines for logs older than that metric."""
  rows = [r for r in run.metrics if "decoder/change" in r]
  if not rows:
    return {}
  end = dict(rows[-1])
  cos = [end[f"decoder/cos_{k}"] for k in range(1, run.config.n_synergies + 1)
         if f"decoder/cos_{k}" in end]
  if "decoder/overlap_start" not in end and cos:
    end["decoder/overlap_start"] = float(np.mean(np.square(cos)))
  return end


def first_reward(run: LabelledRun, task: str) -> int | None:
  """Env steps of the task until the first non-zero reward of `task` in training, or None
  when none was seen (or the run did not log it)."""
  cfg = run.config
  for row in run.metrics:
    t = row.get(f"{task}/first_reward_t")
    if t is not None and t < cfg.unroll_length:
      before = row["step"] - 1  # train steps before the one that saw it
      return before * cfg.num_envs * cfg.unroll_length + (int(t) + 1) * cfg.num_envs
  return None


def steps_to(run: LabelledRun, task: str, threshold: float) -> int | None:
  """Env steps of the task until the first evaluation at which its success reached
  `threshold`; None when none did."""
  for row in run.evaluations:
    if row.get(f"{task}/success", 0.0) >= threshold:
      return run.per_task_env_steps(row)
  return None


def _steps(values: list[int | None], none: str) -> str:
  """Env steps over seeds: mean (min–max) [seeds that got there], and the seeds that did
  not, `none` [count]."""
  got = np.array([v for v in values if v is not None], float)
  missed = len(values) - got.size
  text = ""
  if got.size:
    spread = f" ({got.min():,.0f}–{got.max():,.0f})" if got.size > 1 else ""
    text = f"{got.mean():,.0f}{spread} [{got.size}]"
  if missed:
    text += ("; " if text else "") + f"{none} [{missed}]"
  return text


def frozen_table(group: list[LabelledRun], threshold: float, first_rewards: bool) -> str:
  """Transfer or the sparse valve: per method and task over seeds, the final success, the
  mean success over the evaluation curve (how soon, not only how far), the env steps to
  `threshold` success and, for a sparse reward, to the first reward."""
  head = (f"| method | task | final success | mean over the curve | env steps to "
          f"{threshold:.0%} |" + (" env steps to the first reward |" if first_rewards else ""))
  lines = [head, "|---" * (head.count("|") - 1) + "|"]
  for method in order({r.method for r in group}):
    runs = [r for r in group if r.method == method]
    for task in dict.fromkeys(t for r in runs for t in r.config.tasks):
      with_task = sorted((r for r in runs if task in r.config.tasks), key=lambda r: r.seed)
      final = _success(with_task, task)
      curve = np.array([_mean_success(r, [task], over_curve=True) for r in with_task if r.evaluations])
      cells = [f"{_percent(final)} [{final.size}]", f"{_percent(curve)} [{curve.size}]",
               _steps([steps_to(r, task, threshold) for r in with_task], "not reached")]
      if first_rewards:
        cells.append(_steps([first_reward(r, task) for r in with_task], "none seen"))
      lines.append(f"| {method} | {task} | " + " | ".join(cells) + " |")
  return "\n".join(lines) + "\n"


# -- intervals ----------------------------------------------------------------------
# the two scores of a run on a task: its final success, and its success averaged over every
# evaluation of the run (how soon, not only how far)
SCORES = {"final": "final success", "curve": "mean over the curve"}


def score_matrices(runs: list[LabelledRun], task_names) -> dict[str, dict[str, np.ndarray]]:
  """Per score and method, a runs x tasks matrix of success: every finished run that has
  each task (an unfinished run's last evaluation is not its end)."""
  matrices = {kind: {} for kind in SCORES}
  for method in order({r.method for r in runs}):
    group = sorted((r for r in runs if r.method == method and r.finished and r.evaluations
                    and all(f"{t}/success" in r.final for t in task_names)), key=lambda r: r.seed)
    if group:
      matrices["final"][method] = np.array([[r.final[f"{t}/success"] for t in task_names]
                                            for r in group])
      matrices["curve"][method] = np.array([[_mean_success(r, [t], over_curve=True)
                                             for t in task_names] for r in group])
  return matrices


def default_method(task_set: str, methods) -> Method | None:
  """The row the others are measured against: the set's default DiscoSyn row (for unseen
  tasks and the sparse valve, that row's decoder frozen), else its first DiscoSyn row."""
  from discosyn_jax.experiments import paper

  source = paper.TRANSFER_FROM.get(task_set)
  rows = paper.PAPER_ROWS.get(source[0] if source else task_set, ())
  wanted = [rows[0].replace(reuse="frozen" if source else "")] if rows else []
  found = [m for m in wanted + order(methods) if m in methods and m.family == "DiscoSyn"]
  return found[0] if found else None


INTERVALS_TEXT = (
    "*Intervals*, per set: a row per method over its finished runs (seeds), the interquartile "
    "mean (IQM: the mean of the middle half of all runs x tasks scores) and the mean, of the "
    "final success and of the mean success over the curve; and P(default > row), the "
    "probability that a run of the set's default row (its DiscoSyn<b>-L-reward, frozen for "
    "unseen tasks and the sparse valve) scores above a run of that row on a task, ties half, "
    "averaged over tasks (Agarwal et al., NeurIPS 2021). Brackets: 95 % stratified bootstrap "
    f"intervals (runs resampled within each task; rliable, {intervals.REPS:,} replications, "
    f"seed {intervals.SEED}). *above* / *below*: the interval of P lies above / below 0.5; "
    "else *not separated at n* seeds, with the seeds per row that would separate them if the "
    "gap held: the interval's half-width towards 0.5 scaled by sqrt(n / n'). Where a set has "
    "DiscoSyn rows with a residual beside their synergies, a table for each gives P(that row > "
    "row) for each other row, with the same intervals. The profiles: "
    "the fraction of runs x tasks above each success level, with its band, for the default, "
    "PPO and the three rows of the highest final IQM.")


def _interval(e: intervals.Estimate) -> str:
  return f"{e.value:.2f} [{e.low:.2f}, {e.high:.2f}]"


def _improvement_cell(p: intervals.Estimate, seeds: int) -> str:
  """P(default > row) with its interval and where it stands; for a row not separated, the
  seeds (per row) that would separate it if the gap held (intervals.seeds_to_separate)."""
  where = intervals.verdict(p)
  if where == "not separated":
    needed = intervals.seeds_to_separate(p, seeds)
    more = "no gap" if needed is None else "> 100 would" if needed > 100 else f"~{needed} would"
    where += f" at {seeds} ({more})"
  return f"{_interval(p)} {where}"


def _improvement_cells(matrices, x: str, y: str) -> list[str]:
  """P(x > y) per score, each with where it stands."""
  of = lambda method: {kind: matrices[kind][method] for kind in SCORES}
  seeds = min(len(matrices["final"][x]), len(matrices["final"][y]))
  return [_improvement_cell(p, seeds)
          for p in intervals.probability_of_improvement(of(x), of(y)).values()]


def interval_table(matrices: dict[str, dict[str, np.ndarray]], default: str | None) -> str:
  """A row per method: the runs, the IQM and the mean of each score with their intervals,
  and the probability that the default improves on the row."""
  head = ["method", "runs"] + [f"{name}: {stat}" for name in SCORES.values()
                               for stat in ("IQM", "mean")]
  head += [f"P({default} > row), {name}" for name in SCORES.values()] if default else []
  lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
  of = lambda method: {kind: matrices[kind][method] for kind in SCORES}
  for method in matrices["final"]:
    cells = [str(method), str(len(matrices["final"][method]))]
    for middle, mean in intervals.aggregates(of(method)).values():
      cells += [_interval(middle), _interval(mean)]
    if default and method == default:
      cells += ["(the default)"] * len(SCORES)
    elif default:
      cells += _improvement_cells(matrices, default, method)
    lines.append("| " + " | ".join(cells) + " |")
  return "\n".join(lines) + "\n"


def residual_methods(runs: list[LabelledRun], methods) -> list[Method]:
  """The set's learned-synergy rows with a residual (their decoder frozen on unseen tasks and
  the sparse valve), each measured against the others in a table of its own."""
  with_residual = {r.method for r in runs if r.config.residual > 0}
  return [m for m in order(methods) if m in with_residual and m.family == "DiscoSyn"]


def improvement_table(matrices: dict[str, dict[str, np.ndarray]], x: str) -> str:
  """P(x > row) per score for every other row of the set, with where it stands."""
  head = ["method", "runs"] + [f"P({x} > row), {name}" for name in SCORES.values()]
  lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
  for method in matrices["final"]:
    if method != x:
      lines.append("| " + " | ".join([str(method), str(len(matrices["final"][method]))]
                                      + _improvement_cells(matrices, x, method)) + " |")
  return "\n".join(lines) + "\n"


def profile_rows(matrices: dict[str, dict[Method, np.ndarray]], default: Method | None,
                 others: int = 3) -> list[Method]:
  """The rows a profile draws: the default, full-action PPO, and the `others` other rows of
  the highest final IQM (every row of a set would hide the lines)."""
  final = matrices["final"]
  fixed = [m for m in (default, Method("PPO")) if m in final]
  rest = sorted((m for m in final if m not in fixed), key=lambda m: -intervals.iqm(final[m]))
  chosen = set(fixed + rest[:others])
  return [m for m in final if m in chosen]


def interval_section(runs: list[LabelledRun], task_set: str, out: pathlib.Path) -> list[str]:
  """A set's interval table and its performance-profile figure, as lines of the report."""
  task_names = list(dict.fromkeys(t for r in runs for t in r.config.tasks))
  matrices = score_matrices(runs, task_names)
  if not matrices["final"]:
    return []
  default = default_method(task_set, matrices["final"])
  name = figure_name("profile", task_set)
  shown = profile_rows(matrices, default)
  report_figures.profiles({m: {SCORES[k]: matrices[k][m] for k in SCORES} for m in shown},
                          out / name, f"{task_set}: performance profiles")
  labels = ", ".join(map(tasks.label, task_names))
  lines = [f"### {task_set}: intervals over runs x tasks ({labels})", "",
           interval_table(matrices, default), f"![profile {task_set}]({name})", ""]
  for residual in residual_methods(runs, matrices["final"]):
    lines += [f"### {task_set}: {residual} against the others", "",
              improvement_table(matrices, residual), ""]
  return lines


def improvement_of(runs: list[LabelledRun], task_set: str, x: str | Method, y: str | Method,
                   task_names=None) -> dict[str, intervals.Estimate]:
  """P(x > y) per score for any two rows of a set (a row by its name or its Method), over
  its tasks or `task_names` alone: the comparisons the tables do not hold (two controls, one
  task, ...). BadInput naming the rows the set has where one is not there."""
  in_set = [r for r in runs if r.task_set == task_set]
  if not in_set:
    sets = ", ".join(sorted({r.task_set for r in runs})) or "none"
    raise BadInput(f"no runs of set {task_set!r} (sets: {sets})")
  task_names = task_names or list(dict.fromkeys(t for r in in_set for t in r.config.tasks))
  matrices = score_matrices(in_set, task_names)
  rows = {str(m): m for m in matrices["final"]}

  def of(row):
    method = row if isinstance(row, Method) else rows.get(str(row))
    if method not in matrices["final"]:
      raise BadInput(f"no row {str(row)!r} on {task_set} with runs on {', '.join(task_names)}; "
                     f"rows: {', '.join(rows)}")
    return {kind: matrices[kind][method] for kind in SCORES}

  return intervals.probability_of_improvement(of(x), of(y))


# -- figures ----------------------------------------------------------------------
def write(paths, out: pathlib.Path, threshold: float = 0.8, with_tsne: bool = True,
          force: bool = False, final_k: int = FINAL_K) -> pathlib.Path:
  """Write OUT/REPORT.md and its figures; return the REPORT.md path. A run's final success
  is the mean of its last `final_k` evaluations."""
  if not 0 < threshold <= 1:
    raise BadInput(f"the success threshold must be in (0, 1], not {threshold}")
  plans = confirm.plans_in(paths)  # read first: a damaged plan is refused before any work
  runs, fits = find(paths, final_k=final_k)
  # the committed records a plan names: read for its verdicts, not pooled into the tables
  plans = [(plan, folder, find(confirm.record_paths(plan), inside=True, final_k=final_k)[0])
           for plan, folder in plans]
  if not runs and not fits:
    raise BadInput("no runs among the folders given")
  out = pathlib.Path(out)
  report = out / "REPORT.md"
  if report.exists() and not force:
    raise BadInput(f"{out} already holds a report; pass --force to replace it")
  made = not out.exists()
  try:
    return _write(runs, fits, paths, out, threshold, with_tsne, final_k, plans)
  except BaseException:
    if made:  # a report that fails leaves no folder of half its figures
      shutil.rmtree(out, ignore_errors=True)
    raise


def _write(runs, fits, paths, out: pathlib.Path, threshold: float, with_tsne: bool,
           final_k: int, plans) -> pathlib.Path:
  report = out / "REPORT.md"
  old_figures = set(_figures(report.read_text())) if report.exists() else set()
  out.mkdir(parents=True, exist_ok=True)

  # the folders relative to the report's own: the text names no path of this machine
  sources = [os.path.relpath(pathlib.Path(p).resolve(), out.resolve()) for p in paths]
  lines = ["# DiscoSyn-JAX report", "",
           f"{len(runs)} runs and {len(fits)} synergy fits from: "
           + ", ".join(f"`{p}`" for p in sources) + " (relative to this report's folder).",
           f"A run's *final* success on a task is the mean of its last {final_k} deterministic "
           f"evaluation{'s' if final_k > 1 else ''}; a task is *solved* when the mean over "
           f"seeds of the final success is at least {threshold:.0%}. *closing*, where runs "
           "have one: the closing evaluation that ends a run (more episodes a task, "
           "closing.json), averaged over the set's tasks, mean (min–max) [seeds]. Cells: mark, "
           "mean success, (min–max "
           "over seeds), [seeds], and the paper's mark (Tables I and II; the paper's "
           f"DiscoSyn<b>-L marks also beside today's default start, DiscoSyn<b>-L{REWARDED}). "
           "*mean*: each seed's success averaged over the set's tasks at the end, *over the "
           "curve*: the same averaged over every evaluation of the run; mean (min–max) over "
           "seeds.", "", INTERVALS_TEXT, ""]
  scales = sorted({r.scale for r in runs if r.scale})
  if scales:
    lines += [f"Scales: {', '.join(scales)}.", ""]

  for plan, folder, records in plans:
    lines += confirm.report_lines(plan, [r for r in runs if r.path.resolve().parent == folder]
                                  + records)
  main = [r for r in runs if r.main]
  if main:
    lines += ["## Tasks solved", "", solved_tables(runs, threshold)]
    lines += ["## Intervals over runs and tasks", ""]
    for task_set in sorted({r.task_set for r in main}):
      lines += interval_section([r for r in main if r.task_set == task_set], task_set, out)
  if fits:
    lines += ["## Explained variance of the action data", "",
              "PCA and autoencoder fitted to the deterministic actions of the independent "
              "full-action policies of each set (all tasks pooled).", "", variance_table(fits)]

  if main:
    lines += ["## Training curves", ""]
  for task_set in sorted({r.task_set for r in main}):
    group = [r for r in main if r.task_set == task_set]
    name = figure_name("curves", task_set)
    report_figures.curves(group, out / name, f"{task_set}: deterministic evaluation success")
    lines += [f"![{task_set}]({name})", ""]

  movement = decoder_table(runs)
  if movement:
    lines += ["## Is the synergy space learned?", "",
              "The decoder's synergy basis (linear: W; MLP: its Jacobian at z = 0) against the "
              "one it started from: relative change, and the cosines of the principal angles "
              "between the two subspaces (1: the same subspace). A frozen decoder shows 0 and 1.",
              "", movement]

  shares = residual_table(runs)
  if shares:
    lines += ["## Do the synergies still do the work?", "",
              "Rows with a residual beside the synergies (a = D(z) + rho r): the mean absolute "
              "action per actuator each part carries, over the last 10 logged train steps. "
              "Cells: mean (min–max) [seeds].", "", shares]

  discovered = discovery_table(main)
  if discovered:
    lines += ["## Is the synergy space discovered?", "",
              "Overlap of two synergy subspaces: the mean squared cosine of their principal "
              "angles, |Q_i^T Q_j|_F^2 / b (1: the same subspace, 0: orthogonal; two random "
              "b-dim subspaces of the 20 actions: b / 20, the *chance* column). A space the task "
              "set determines has a high overlap between seeds (learned, seed pairs) however "
              "low it was between their random starts (initial); a seed that only turned its "
              "own start keeps a high overlap with it. The planted span: the subspace the "
              "planted tasks' targets lie in (discosyn_jax/tasks/planted.py). Cells: mean (min–max) [pairs "
              "or seeds]; the learned subspaces are read from the runs' checkpoints, or their "
              "records' decoder.npz.", "", discovered]
    for task_set in sorted({r.task_set for r in main}):
      name = figure_name("overlap", task_set)
      if report_figures.overlap_curves([r for r in main if r.task_set == task_set], out / name,
                        f"{task_set}: the decoder's subspace during training"):
        lines += [f"![overlap {task_set}]({name})", ""]

  # the runs whose z can be read (z.npz, or a checkpoint to draw it from), per set
  drawable = [r for r in main if with_tsne and r.method.family == "DiscoSyn" and r.evaluations
              and record.has_z(r.path)]
  if drawable:
    lines += ["## t-SNE of the low-dimensional actions", ""]
  for task_set in sorted({r.task_set for r in drawable}):
    best = max((r for r in drawable if r.task_set == task_set),
               key=lambda r: (np.mean([r.final.get(f"{t}/success", 0) for t in r.config.tasks]),
                              -r.seed))
    name = figure_name("tsne", task_set)
    report_figures.tsne(best, out / name)
    lines += [f"{best.method} (its best-scoring run on {task_set}, `{best.path.name}`):", "",
              f"![t-SNE {task_set}]({name})", ""]

  for experiment, heading in (("transfer", "Transfer to unseen tasks"),
                              ("sparse", "The sparse goal valve")):
    group = [r for r in runs if r.experiment == experiment]
    if not group:
      continue
    lines += [f"## {heading}", "", "Per method and task over seeds: the final success, the "
              "mean success over the evaluation curve, the env steps of the task to the first "
              f"evaluation at {threshold:.0%} success"
              + (" and to the first reward seen in training" if experiment == "sparse" else "")
              + ": mean (min–max) [seeds that got there], and [seeds] that did not.", "",
              frozen_table(group, threshold, first_rewards=experiment == "sparse")]
    for task_set in sorted({r.task_set for r in group}):
      lines += interval_section([r for r in group if r.task_set == task_set], task_set, out)
    name = f"{experiment}.png"
    report_figures.curves(group, out / name, f"{heading}: deterministic evaluation success")
    lines += [f"![{experiment}]({name})", ""]
    if experiment == "sparse":
      report_figures.curves(group, out / "sparse-return.png", "sparse goal valve: evaluation return", "return")
      lines += ["![sparse return](sparse-return.png)", ""]

  text = "\n".join(lines)
  report.write_text(text)
  # once the new report stands: the old one's figures it did not draw again (--no-tsne, say)
  for name in old_figures - set(_figures(text)):
    (out / name).unlink(missing_ok=True)
  return report


def _figures(report_text: str) -> list[str]:
  """The figure files a REPORT.md links, each beside it."""
  return re.findall(r"\]\(([^)/]+\.png)\)", report_text)


def figure_name(kind: str, task_set: str) -> str:
  """A figure's file name for a set ("set1 on leap16", "Press+Rake"): one a Markdown link
  takes as it is (no spaces, no slashes)."""
  return f"{kind}-{re.sub(r'[^A-Za-z0-9_.-]+', '_', task_set)}.png"
