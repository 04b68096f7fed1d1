"""The tables of docs/RESULTS.md and README.md, written from the committed records of
docs/results/, so that a figure on a page is the one its records give.

`python -m discosyn_jax.experiments.results_page [--check] [PAGE ...]` (PAGE: docs/RESULTS.md
of this repository by default): each table of a page sits between two marker lines,

    <!-- table:NAME -->
    | ... |
    <!-- /table:NAME -->

and the command replaces what lies between them with `tables()[NAME]`; with --check it
writes nothing and names each table that differs (exit 1), so that a test notices a page
and its records parting. Everything else on a page is left as written.

The tables (every cell a number, an interval, a count or one verdict word):
  budget        what a run of each table trains and how its end is measured (configs)
  table1/2      the paper's Tables I and II, a row per method (docs/results/paper/; set #1's
                paper start from docs/results/hand26/): tasks solved, the paper's mark, the
                final success and the mean over the curve, seeds
  set2_pooled   set #2 over every committed run of one config (the default, two variants,
                full-action PPO): the mean difference to PPO over the curve with its interval
  claims        the headline comparisons: x - y with its interval and its verdict
  confirmations each hypothesis of the two confirmation plans, as `discosyn report` judges it
  transfer      the unseen tasks, a row per method and task
  sparse        the sparse goal valve, with the env steps to the first reward
  quickstart    the quickstart preset's seeds (README)
  headline      README's one table of results

Definitions are the report's (report.py): a run's final success is the mean of its last
FINAL_K evaluations (report_runs.LabelledRun.final); a task is solved where the mean over seeds of
its final success is >= THRESHOLD; "over the curve": the success averaged over every
evaluation of the run. A mean over seeds is of each seed's mean over the tasks. Intervals:
intervals.mean_difference, the 95 % stratified bootstrap of the difference of the means
(runs resampled within each task, each row's on its own), from a fixed seed: the text is the
same byte for byte on every run. Verdict: *above* / *below* where the interval clears 0,
else *not separated*; read at five bootstrap seeds, and where they disagree the cell says at
how many the first seed's verdict holds.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import pathlib
import re
import sys

import numpy as np

from discosyn_jax import config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.experiments import confirm, intervals, report, report_runs
from discosyn_jax.experiments.method import Method
from discosyn_jax.experiments.report_runs import LabelledRun

ROOT = pathlib.Path(__file__).resolve().parents[2]  # the repository, where it is one
RECORDS = pathlib.Path("docs", "results")
PAGE = pathlib.Path("docs", "RESULTS.md")
THRESHOLD = 0.8
# the bootstrap seeds every verdict here is read at (the first is the reports'): one that
# another seed changes says so
BOOTSTRAP_SEEDS = tuple(range(intervals.SEED, intervals.SEED + 5))
MARKER = re.compile(r"^<!-- (/?)table:([A-Za-z0-9_-]+) -->[ \t]*$", re.M)


def _seeds(pattern: str, seeds) -> tuple[str, ...]:
  return tuple(pattern.format(seed) for seed in seeds)


# set #2 pooled over every committed run of one config: (label, records it must have,
# records of the same config that join it where their config is the same run)
POOLED_SET2 = (
    ("DiscoSyn6-L-reward (the default)",
     _seeds("paper/discosyn6-l-reward-set2-seed{}", range(3))
     + _seeds("confirm-late-residual/set2-default-seed{}", range(3, 8))
     + _seeds("confirm-task-noise-bonus-cap/set2-default-seed{}", range(11, 16)), ()),
    ("late residual (-res0.3r200s400)",
     _seeds("confirm-late-residual/set2-late-seed{}", range(3, 8)),
     _seeds("residual-set2/discosyn6-l-reward-res0.3r200s400-set2-seed{}", range(3))),
    ("each task's noise + capped bonus",
     _seeds("unfound-task/discosyn6-l-reward-tasknoise-bonuscap-set2-seed{}", (8, 9))
     + _seeds("confirm-task-noise-bonus-cap/set2-tncap-seed{}", range(11, 16)), ()),
    ("full-action PPO",
     _seeds("paper/ppo-set2-seed{}", range(3))
     + _seeds("confirm-late-residual/set2-ppo-seed{}", range(3, 8))
     + _seeds("confirm-task-noise-bonus-cap/set2-ppo-seed{}", range(11, 16)), ()),
)
DEFAULT2, LATE2, TNCAP2, PPO2 = (label for label, _, _ in POOLED_SET2)
CONFIRMATIONS = (("late residual", "confirm-late-residual"),
                 ("task noise + cap", "confirm-task-noise-bonus-cap"),
                 ("own synergies, transfer", "confirm-own-synergies-transfer"))
# set #1's row from the paper's own start (a random decoder), beside Table I's
PAPER_START = "hand26"


# -- reading the records -----------------------------------------------------------
class Records:
  """The committed records under ROOT/docs/results, each folder read once."""

  def __init__(self, root: pathlib.Path = ROOT):
    self.base = pathlib.Path(root) / RECORDS
    if not self.base.is_dir():
      raise FileNotFoundError(f"no records at {self.base}: the tables are written from a "
                              "clone of the repository, not an installed package")

  @functools.cache
  def folder(self, name: str) -> tuple[LabelledRun, ...]:
    """Every finished run of a folder of records (a run folder, or a folder of them)."""
    runs, _ = report_runs.find([self.base / name])
    return tuple(r for r in runs if r.finished and r.evaluations)

  def runs(self, names) -> list[LabelledRun]:
    return [run for name in names for run in self.folder(name)]

  @functools.cache
  def pooled(self, label: str) -> tuple[LabelledRun, ...]:
    """A pooled set #2 row: its records, checked to train one config on distinct seeds, and
    those that may join it where their config is the same run."""
    _, required, optional = next(row for row in POOLED_SET2 if row[0] == label)
    runs = self.runs(required)
    if len(runs) != len(required):
      raise BadInput(f"{label}: {len(required)} records named, {len(runs)} finished runs read")
    same = lambda run: config_lib.same_run(run.config.replace(seed=runs[0].config.seed),
                                           runs[0].config)
    odd = [str(r.path.relative_to(self.base)) for r in runs if not same(r)]
    if odd:
      raise BadInput(f"{label}: {', '.join(odd)} train another config than the row's")
    runs += [r for r in self.runs(optional) if same(r)]
    seeds = [r.seed for r in runs]
    if len(set(seeds)) != len(seeds):
      raise BadInput(f"{label}: a seed twice among {seeds}")
    return tuple(sorted(runs, key=lambda r: r.seed))

  def paper(self, task_set: str) -> dict[Method, list[LabelledRun]]:
    """The paper's records of a task set (Tables I and II, transfer, the sparse valve), by
    method in the report's order of rows."""
    runs = [r for r in self.folder("paper") if r.task_set == task_set]
    return {m: sorted((r for r in runs if r.method == m), key=lambda r: r.seed)
            for m in report_runs.order({r.method for r in runs})}


# -- figures of runs ------------------------------------------------------------------
def tasks_of(runs) -> list[str]:
  return list(dict.fromkeys(t for r in runs for t in r.config.tasks))


def final(run: LabelledRun, task_names) -> float:
  """A run's final success (the mean of its last k evaluations) averaged over tasks."""
  return float(np.mean([run.final[f"{t}/success"] for t in task_names]))


def curve(run: LabelledRun, task_names) -> float:
  """A run's success averaged over its evaluations and tasks."""
  return float(np.mean([run.curve[t] for t in task_names]))


def solved(runs, task_names) -> int:
  """The tasks whose mean over seeds of the final success is at least THRESHOLD."""
  return sum(np.mean([r.final[f"{t}/success"] for r in runs]) >= THRESHOLD for t in task_names)


def matrix(runs, task_names, score: str) -> np.ndarray:
  """A runs x tasks matrix of one score ("final" or "curve")."""
  if score == "final":
    return np.array([[r.final[f"{t}/success"] for t in task_names] for r in runs])
  return np.array([[r.curve[t] for t in task_names] for r in runs])


def difference(x, y, task_names, score: str) -> intervals.Estimate:
  """mean(x) - mean(y) of one score over `task_names`, with its 95 % bootstrap interval."""
  return intervals.mean_difference({score: matrix(x, task_names, score)},
                                   {score: matrix(y, task_names, score)})[score]


def at_seeds(compute) -> list:
  """`compute()` bootstrapped from each seed of BOOTSTRAP_SEEDS, in their order."""
  found = []
  for seed in BOOTSTRAP_SEEDS:
    with intervals.bootstrap_seed(seed):
      found.append(compute())
  return found


def judged(x, y, task_names, score: str) -> tuple[intervals.Estimate, str]:
  """x - y (`difference`) at the bootstrap's seed, and its verdict at every seed of
  BOOTSTRAP_SEEDS (`stable`)."""
  at = at_seeds(lambda: difference(x, y, task_names, score))
  return at[0], stable([intervals.verdict(e, centre=0.0) for e in at])


def stable(verdicts: list[str]) -> str:
  """The verdict where every bootstrap seed gives it; else the first seed's, and at how many
  seeds it holds (a verdict of the bootstrap, not of the records)."""
  agree = verdicts.count(verdicts[0])
  return (verdicts[0] if agree == len(verdicts)
          else f"{verdicts[0]} at {agree} of {len(verdicts)} bootstrap seeds")


def number(value: float) -> str:
  return f"{value:.2f}"


def signed(value: float) -> str:
  """A difference to 3 places with its sign; one that rounds to 0 is +0.000, never -0.000."""
  return f"{round(value, 3) + 0.0:+.3f}"


def interval(e: intervals.Estimate) -> str:
  return f"{signed(e.value)} [{signed(e.low)}, {signed(e.high)}]"


def seed_list(runs) -> str:
  """Seeds as ranges: '0-7, 11-15'."""
  seeds, parts = sorted({r.seed for r in runs}), []
  for seed in seeds:
    if parts and seed == parts[-1][1] + 1:
      parts[-1][1] = seed
    else:
      parts.append([seed, seed])
  return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in parts)


def seeds_cell(runs) -> str:
  """The count of seeds and their ranges: '13 (0-7, 11-15)'."""
  return f"{len({r.seed for r in runs})} ({seed_list(runs)})"


def spread(values, fmt=number) -> str:
  """The only value, or min-max."""
  values = sorted(set(values))
  return fmt(values[0]) if len(values) == 1 else f"{fmt(values[0])}-{fmt(values[-1])}"


def markdown(head, rows) -> str:
  lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
  lines += ["| " + " | ".join(row) + " |" for row in rows]
  return "\n".join(lines)


def thousands(steps: float) -> str:
  """Env steps: '3.8 k', '384 k', '6.14 M'."""
  if steps >= 1e6:
    return f"{steps / 1e6:.2f} M"
  return f"{steps / 1e3:.1f} k" if steps < 1e5 else f"{steps / 1e3:.0f} k"


# -- the tables -----------------------------------------------------------------------
def budget_table(records: Records) -> str:
  """What a run of each table trains, from the records' configs: a cell is the one value
  its runs share, or their range."""
  by = lambda task_set: [r for rs in records.paper(task_set).values() for r in rs]
  groups = [("Table I (set #1)", "paper/", by("set1")),
            ("Table I: the paper's start", f"{PAPER_START}/",
             [r for r in records.folder(PAPER_START) if r.method == Method.parse("DiscoSyn3-L")]),
            ("Table II (set #2)", "paper/", by("set2")),
            ("set #2 pooled", "paper/, confirm-*/, residual-set2/, unfound-task/",
             [r for label, _, _ in POOLED_SET2 for r in records.pooled(label)]),
            ("transfer: set #1's unseen valves", "paper/transfer-*-set1-*", by("unseen-set1")),
            ("transfer: set #2's unseen screw", "paper/transfer-*-set2-*", by("unseen-set2")),
            ("the sparse valve", "paper/sparse-*", by("sparse")),
            ("the quickstart", "quickstart-reward/", list(records.folder("quickstart-reward")))]
  rows = []
  for name, where, runs in groups:
    c = lambda field: [getattr(r.config, field) for r in runs]
    per_task = [r.config.steps * r.config.num_envs * r.config.unroll_length for r in runs]
    rows.append([name, where, spread([len(r.config.tasks) for r in runs], str),
                 spread(c("steps"), str), spread(c("num_envs"), str),
                 spread(per_task, thousands),
                 spread([p * len(r.config.tasks) for p, r in zip(per_task, runs)], thousands),
                 spread(c("eval_every"), str), spread(c("eval_envs"), str),
                 spread([r.final_k for r in runs], str), str(len(runs))])
  return markdown(["table", "records", "tasks", "train steps", "envs a task",
                   "env steps a task", "env steps a run", "evaluated every (train steps)",
                   "episodes a task an evaluation", "final: mean of the last (evaluations)",
                   "runs"], rows)


def paper_table(records: Records, task_set: str) -> str:
  """Table I or II: a row per method."""
  rows_by = records.paper(task_set)
  if task_set == "set1":  # the paper's own start, from a folder of its own
    own = [r for r in records.folder(PAPER_START) if r.method == Method.parse("DiscoSyn3-L")]
    rows_by = {**rows_by, Method.parse("DiscoSyn3-L"): sorted(own, key=lambda r: r.seed)}
  marks = report.PAPER_SOLVED[task_set]
  rows = []
  for method in report_runs.order(rows_by):
    runs = rows_by[method]
    task_names = tasks_of(runs)
    mark = marks.get(report.paper_row(method))
    where = f"{PAPER_START}/" if method == Method.parse("DiscoSyn3-L") else "paper/"
    rows.append([str(method), where, f"{solved(runs, task_names)}/{len(task_names)}",
                 f"{mark.count('1')}/{len(mark)}" if mark else "–",
                 number(np.mean([final(r, task_names) for r in runs])),
                 number(np.mean([curve(r, task_names) for r in runs])), seeds_cell(runs)])
  return markdown(["row", "records", "solved", "the paper's", "final", "over the curve",
                   "seeds"], rows)


def never_at(runs, task: str) -> int:
  """Runs whose success on `task` never reached THRESHOLD at an evaluation."""
  return sum(report.steps_to(r, task, THRESHOLD) is None for r in runs)


def pooled_table(records: Records) -> str:
  ppo = records.pooled(PPO2)
  task_names = tasks_of(ppo)
  rows = []
  for label, _, _ in POOLED_SET2:
    runs = records.pooled(label)
    if label == PPO2:
      gap = ["–", "–"]
    else:
      d, said = judged(runs, ppo, task_names, "curve")
      gap = [interval(d), said]
    rows.append([label, seeds_cell(runs), f"{solved(runs, task_names)}/{len(task_names)}",
                 number(np.mean([final(r, task_names) for r in runs])),
                 number(np.mean([curve(r, task_names) for r in runs])),
                 number(np.mean([r.final["dice/success"] for r in runs])),
                 f"{never_at(runs, 'weight_pull')} of {len(runs)}"] + gap)
  return markdown(["row", "seeds", "solved", "final", "over the curve", "dice, final",
                   "weight-pull runs never at 0.8", "over the curve minus PPO's [95 %]",
                   "verdict"], rows)


def confirmation_table(records: Records) -> str:
  rows = []
  for name, folder in CONFIRMATIONS:
    plan = confirm.load(records.base / folder / confirm.PLAN_FILE)
    runs = list(records.folder(folder))
    if confirm.record_paths(plan):  # rows of committed records the plan names
      runs += report_runs.find(confirm.record_paths(plan), inside=True)[0]
    at = at_seeds(lambda: confirm.verdicts(plan, runs))
    found = at[0]
    for n, v in enumerate(found):
      h = v.hypothesis
      what = ", ".join(filter(None, (h.task, h.score, "" if h.statistic == "P" else "difference")))
      p = v.p
      value = "–" if p is None else (interval(p) if h.statistic == "difference" else
                                      f"P {p.value:.2f} [{p.low:.2f}, {p.high:.2f}]")
      holds = "pending" if v.holds is None else "yes" if v.holds else "no"
      rows.append([name, f"{h.x} vs {h.y} ({what})", f"{v.runs[0]}, {v.runs[1]}", value,
                   stable([seeds[n].verdict for seeds in at]), h.expect, holds])
    every = all(v.holds for v in found)
    pending = any(v.holds is None for v in found)
    rows.append([name, "the plan: every hypothesis", "–", "–", "–", "hold",
                 "pending" if pending else "yes" if every else "no"])
  return markdown(["plan", "hypothesis (x vs y)", "runs (x, y)", "P(x > y) or x - y [95 %]",
                   "verdict", "expected", "holds"], rows)


def transfer_table(records: Records) -> str:
  """A row per method, the final success and the mean over the curve per unseen task ('–'
  where the row did not run it)."""
  by = {}
  for task_set in ("unseen-set1", "unseen-set2"):
    for method, runs in records.paper(task_set).items():
      by.setdefault(method, []).extend(runs)
  task_names = tasks_of([r for runs in by.values() for r in runs])
  rows = []
  for method in report_runs.order(by):
    cells = []
    for task in task_names:
      runs = [r for r in by[method] if task in r.config.tasks]
      cells += ([number(np.mean([final(r, [task]) for r in runs])),
                 number(np.mean([curve(r, [task]) for r in runs]))] if runs else ["–", "–"])
    rows.append([str(method)] + cells + [seeds_cell(by[method])])
  head = [f"{t}, {what}" for t in task_names for what in ("final", "curve")]
  return markdown(["row"] + head + ["seeds"], rows)


def sparse_table(records: Records) -> str:
  rows = []
  for method, runs in records.paper("sparse").items():
    task = runs[0].config.tasks[0]
    first = [report.first_reward(r, task) for r in runs]
    each = " / ".join("none" if f is None else thousands(f) for f in first)
    budget = [r.per_task_env_steps(r.evaluations[-1]) for r in runs]
    # a seed never paid counts at the budget: the mean is then a lower bound
    mean = np.mean([b if f is None else f for f, b in zip(first, budget)])
    rows.append([str(method), number(np.mean([final(r, [task]) for r in runs])),
                 number(np.mean([curve(r, [task]) for r in runs])), each,
                 ("≥ " if None in first else "") + thousands(mean), seeds_cell(runs)])
  return markdown(["row", "final", "over the curve", "first reward, env steps, seed by seed",
                   "mean (unpaid at the budget)", "seeds"], rows)


def quickstart_table(records: Records) -> str:
  rows = []
  runs = sorted(records.folder("quickstart-reward"), key=lambda r: r.seed)
  task_names = tasks_of(runs)
  for run in runs:
    at = next((row["env_steps"] for row in run.evaluations
               if any(row.get(f"{t}/success", 0) >= THRESHOLD for t in task_names)), None)
    rows.append([str(run.seed)] + [number(run.final[f"{t}/success"]) for t in task_names]
                + [number(curve(run, task_names)), "never" if at is None else thousands(at),
                   thousands(run.evaluations[-1]["env_steps"])])
  return markdown(["seed"] + [f"{t}, final" for t in task_names]
                  + ["over the curve", "env steps at the first evaluation with a valve at 0.8",
                     "env steps in all"], rows)


@dataclasses.dataclass(frozen=True)
class Group:
  """Some runs under a name, on some tasks, and the records they come from."""
  name: str
  runs: tuple
  tasks: tuple
  where: str


def _groups(records: Records) -> dict[str, Group]:
  """The rows the claims and the headline compare, by a short key."""
  s1, s2 = records.paper("set1"), records.paper("set2")
  t1, t2, sp = records.paper("unseen-set1"), records.paper("unseen-set2"), records.paper("sparse")
  m = Method.parse
  g = {}

  def add(key, name, runs, task_names, where):
    g[key] = Group(name, tuple(runs), tuple(task_names), where)

  set1 = tasks_of(s1[m("PPO")])
  add("s1-default", "DiscoSyn3-L-reward", s1[m("DiscoSyn3-L-reward")], set1, "paper/")
  add("s1-control", "Random3-L-zfree", s1[m("Random3-L-zfree")], set1, "paper/")
  add("s1-ppo", "PPO", s1[m("PPO")], set1, "paper/")
  add("s1-prior", "Prior3-L-reward", s1[m("Prior3-L-reward")], set1, "paper/")
  add("s1-paper-start", "DiscoSyn3-L", [r for r in records.folder(PAPER_START)
                                        if r.method == m("DiscoSyn3-L")], set1, f"{PAPER_START}/")
  set2 = tasks_of(s2[m("PPO")])
  add("s2-default", DEFAULT2, records.pooled(DEFAULT2), set2, "pooled")
  add("s2-late", LATE2, records.pooled(LATE2), set2, "pooled")
  add("s2-tncap", TNCAP2, records.pooled(TNCAP2), set2, "pooled")
  add("s2-ppo", PPO2, records.pooled(PPO2), set2, "pooled")
  add("s2-control", "Random6-L-zfree", s2[m("Random6-L-zfree")], set2, "paper/")
  for task, by in (("valve_cylinder", t1), ("valve_cw", t1), ("screw_topdown", t2)):
    default = next(k for k in by if k.family == "DiscoSyn")
    add(f"{task}-default", str(default), by[default], [task], "paper/transfer-*")
    add(f"{task}-ppo", "PPO", by[m("PPO")], [task], "paper/transfer-*")
  default = next(k for k in sp if k.family == "DiscoSyn")
  valve = tasks_of(sp[default])
  add("sparse-default", str(default), sp[default], valve, "paper/sparse-*")
  add("sparse-ppo", "PPO", sp[m("PPO")], valve, "paper/sparse-*")
  return g


# (claim, x, y, score): x - y of that score over x's tasks
CLAIMS = (
    ("Set #1: the default against the strongest control, at the end", "s1-default", "s1-control", "final"),
    ("Set #1: the default against the strongest control, over the curve", "s1-default", "s1-control", "curve"),
    ("Set #1: the default against full-action PPO, over the curve", "s1-default", "s1-ppo", "curve"),
    ("Set #1: the reward prior's start against the paper's random start, at the end", "s1-default",
     "s1-paper-start", "final"),
    ("Set #1: learning the prior's space against keeping it frozen, over the curve", "s1-default", "s1-prior", "curve"),
    ("Set #2: the default against full-action PPO, over the curve", "s2-default", "s2-ppo", "curve"),
    ("Set #2: the default against full-action PPO, at the end", "s2-default", "s2-ppo", "final"),
    ("Set #2: the default against the strongest control, over the curve", "s2-default",
     "s2-control", "curve"),
    ("Set #2: the late residual against full-action PPO, over the curve", "s2-late", "s2-ppo", "curve"),
    ("Set #2: each task's noise + capped bonus against PPO, over the curve", "s2-tncap", "s2-ppo",
     "curve"),
    ("Transfer: set #1's space frozen against PPO on the clockwise valve, at the end", "valve_cw-default",
     "valve_cw-ppo", "final"),
    ("Transfer: the same, over the curve", "valve_cw-default", "valve_cw-ppo", "curve"),
    ("Sparse valve: set #1's space frozen against PPO, at the end", "sparse-default",
     "sparse-ppo", "final"),
)
def claims_table(records: Records) -> str:
  g = _groups(records)
  rows = []
  for claim, x, y, score in CLAIMS:
    a, b = g[x], g[y]
    d, said = judged(a.runs, b.runs, list(a.tasks), score)
    where = a.where if a.where == b.where else f"{a.where}, {b.where}"
    rows.append([claim, a.name, b.name, interval(d), said,
                 f"{len(a.runs)}, {len(b.runs)}", where])
  return markdown(["claim", "x", "y", "x - y [95 %]", "verdict", "seeds (x, y)", "records"],
                  rows)


# README's rows: (what, the default's key, the other rows' keys)
HEADLINE = (
    ("set #1", "s1-default", ("s1-control", "s1-ppo")),
    ("set #2", "s2-default", ("s2-ppo", "s2-control")),
    ("unseen valve_cylinder", "valve_cylinder-default", ("valve_cylinder-ppo",)),
    ("unseen valve_cw", "valve_cw-default", ("valve_cw-ppo",)),
    ("unseen screw_topdown", "screw_topdown-default", ("screw_topdown-ppo",)),
    ("sparse valve_goal", "sparse-default", ("sparse-ppo",)),
)


def headline_table(records: Records) -> str:
  g = _groups(records)
  rows = []
  for what, default, others in HEADLINE:
    for key in (default,) + others:
      group = g[key]
      task_names = list(group.tasks)
      if key == default:
        against = "–"
      else:  # the row against the default over the curve
        against = judged(group.runs, g[default].runs, task_names, "curve")[1]
      rows.append([what, group.name, str(len(group.runs)),
                   f"{solved(group.runs, task_names)}/{len(task_names)}",
                   number(np.mean([final(r, task_names) for r in group.runs])),
                   number(np.mean([curve(r, task_names) for r in group.runs])), against])
  return markdown(["tasks", "row", "seeds", "solved", "final", "over the curve",
                   "against the first row, over the curve"], rows)


# each task's own synergies, exploratory: (place, its tasks' label, the folders of each row,
# in order: the own row first, then what it is read beside on the same seeds)
OWN = (
    ("set #2", ("dice", "valve3", "weight_pull", "screw"),
     (("DiscoSyn6+3-L-reward-tasknoise-bonuscap",
       _seeds("own-synergies/set2/discosyn6+3-l-reward-tasknoise-bonuscap-set2-seed{}", (3, 4))),
      ("DiscoSyn6+6-L-reward-tasknoise-bonuscap",
       _seeds("own-synergies/set2/discosyn6+6-l-reward-tasknoise-bonuscap-set2-seed{}", (3,))),
      ("full-action PPO", _seeds("confirm-late-residual/set2-ppo-seed{}", (3, 4))))),
    ("unseen valve_cw", ("valve_cw",),
     (("set #1's default frozen + 3 own", _seeds("transfer-learned/own-seed{}", range(3))),
      ("set #1's default frozen", _seeds("paper/transfer-synergies-set1-seed{}", range(3))),
      ("full-action PPO", _seeds("paper/transfer-ppo-set1-seed{}", range(3))))),
    ("sparse valve_goal", ("valve_goal",),
     (("set #1's default frozen + 3 own", _seeds("transfer-learned/sparse-own-seed{}", range(3))),
      ("set #1's default frozen", _seeds("paper/sparse-synergies-seed{}", range(3))),
      ("full-action PPO", _seeds("paper/sparse-ppo-seed{}", range(3))))),
)


def own_table(records: Records) -> str:
  """Each task's own synergies beside the rows of the same seeds: final, over the curve, the
  task that lacked room over the curve, and the first reward where the task is sparse."""
  rows = []
  for place, task_names, groups in OWN:
    for label, folders in groups:
      runs = sorted(records.runs(folders), key=lambda r: r.seed)
      config = runs[0].config
      acts = config.n_synergies + config.own_synergies  # PPO's n_synergies: the action size
      each = lambda values: " / ".join(number(v) for v in values)  # seed by seed
      first = ([report.first_reward(r, task_names[0]) for r in runs]
               if place.startswith("sparse") else [])
      rows.append([place, label, seeds_cell(runs), str(acts),
                   each([final(r, list(task_names)) for r in runs]),
                   each([curve(r, list(task_names)) for r in runs]),
                   each([curve(r, [task_names[0]]) for r in runs]) if len(task_names) > 1 else "–",
                   " / ".join("none" if f is None else thousands(f) for f in first) or "–"])
  return markdown(["tasks", "row", "seeds", "a task acts in", "final, seed by seed",
                   "over the curve", "the dice, over the curve",
                   "first reward, env steps"], rows)


BUILDERS = {
    "budget": budget_table,
    "table1": lambda records: paper_table(records, "set1"),
    "table2": lambda records: paper_table(records, "set2"),
    "set2_pooled": pooled_table,
    "claims": claims_table,
    "confirmations": confirmation_table,
    "transfer": transfer_table,
    "sparse": sparse_table,
    "quickstart": quickstart_table,
    "headline": headline_table,
    "own": own_table,
}


@functools.cache
def _tables(root: pathlib.Path) -> tuple[tuple[str, str], ...]:
  records = Records(root)
  return tuple((name, build(records)) for name, build in BUILDERS.items())


def tables(root: pathlib.Path | None = None) -> dict[str, str]:
  """Table name -> its Markdown text, from the records under ROOT (or `root`)/docs/results;
  read once a process."""
  return dict(_tables(pathlib.Path(root or ROOT).resolve()))


# -- the pages -----------------------------------------------------------------------------
def blocks(text: str) -> list[tuple[str, int, int]]:
  """(name, start, end) of each table's text between its markers in a page; BadInput for a
  marker without its pair."""
  found, opened = [], None
  for match in MARKER.finditer(text):
    closing, name = match.group(1) == "/", match.group(2)
    if not closing:
      if opened:
        raise BadInput(f"table {opened[0]!r} opened and not closed before table {name!r}")
      opened = (name, match.end())
    else:
      if not opened or opened[0] != name:
        raise BadInput(f"a closing marker of table {name!r} without its opening one")
      found.append((name, opened[1], match.start()))
      opened = None
  if opened:
    raise BadInput(f"table {opened[0]!r} opened and never closed")
  return found


def render(text: str, found: dict[str, str]) -> str:
  """The page with each table's text between its markers replaced by `found`'s."""
  out, at = [], 0
  for name, start, end in blocks(text):
    if name not in found:
      raise BadInput(f"no table {name!r} (tables: {', '.join(found)})")
    out += [text[at:start], "\n" + found[name].strip("\n") + "\n"]
    at = end
  return "".join(out + [text[at:]])


def check(page_path, found: dict[str, str] | None = None) -> list[str]:
  """The tables of the page at `page_path` that differ from what `write` would put there (a
  name the tables lack, as 'NAME (no such table)')."""
  text = pathlib.Path(page_path).read_text(encoding="utf-8")
  found = tables() if found is None else found
  wrong = []
  for name, start, end in blocks(text):
    if name not in found:
      wrong.append(f"{name} (no such table)")
    elif text[start:end] != "\n" + found[name].strip("\n") + "\n":
      wrong.append(name)
  return wrong


def write(page_path, found: dict[str, str] | None = None) -> list[str]:
  """Write each table of the page at `page_path` between its markers; the names of those
  that changed."""
  path = pathlib.Path(page_path)
  found = tables() if found is None else found
  changed = check(path, found)
  text = path.read_text(encoding="utf-8")
  new = render(text, found)
  if new != text:
    path.write_text(new, encoding="utf-8")
  return changed


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(
      prog="python -m discosyn_jax.experiments.results_page",
      description="Write the tables of a Markdown page (between <!-- table:NAME --> and "
                  "<!-- /table:NAME --> lines) from the committed records of docs/results/.")
  parser.add_argument("pages", nargs="*", metavar="PAGE",
                      help=f"the pages (default: {PAGE} of this repository)")
  parser.add_argument("--check", action="store_true",
                      help="write nothing; name each table that differs (exit 1 if one does)")
  args = parser.parse_args(argv)
  if not (ROOT / RECORDS).is_dir():
    print(f"results_page: no {RECORDS.as_posix()}/ beside this module (an installed package): "
          "run it from a clone of the repository", file=sys.stderr)
    return 2
  pages = [pathlib.Path(p) for p in args.pages] or [ROOT / PAGE]
  status = 0
  for page in pages:
    try:
      names = check(page) if args.check else write(page)
    except (OSError, ValueError) as e:
      print(f"results_page: {page}: {e}", file=sys.stderr)
      return 2
    if args.check and names:
      print(f"{page}: differs from its records: {', '.join(names)}")
      status = 1
    elif not args.check:
      print(f"{page}: " + (f"wrote {', '.join(names)}" if names else "up to date"))
  return status


if __name__ == "__main__":
  sys.exit(main())
