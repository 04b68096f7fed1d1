"""A confirmatory experiment: a plan written (and committed) before its runs, run exactly as
written, and judged by the rule it states. `discosyn experiment confirm PLAN --out DIR`
runs it; `discosyn report DIR` prints each hypothesis with its interval and its verdict.

A plan is a JSON file:

  {"name": "late-residual",            the experiment's name (experiment.json says
                                       confirm-<name>)
   "claim": "...",                     what is being confirmed, and where it was chosen
   "final_k": 3,                       a run's final success: the mean of its last k evaluations
   "level_margin": 0.1,                "level": P's interval inside 0.5 +- this margin
   "rows": [{"name": "set2-late",      a row: its runs are folders <name>-seed<n> in DIR
             "seeds": [3, 4, 5, 6, 7],
             "config": {...}},         every TrainConfig field but the seed (config.json's)
            {"name": "set2-ppo", "seeds": [0, 1], "config": {...},
             "records": ["../paper/ppo-set2-seed0", ...]},
                                       a row of committed records, one per seed, relative
                                       to the plan file's folder: not run again, each
                                       checked to be the run of the row's config and seed
            ...],
   "hypotheses": [{"x": "set2-late", "y": "set2-ppo", "score": "final", "expect": "above"},
                  {"x": ..., "y": ..., "score": "curve", "expect": "not below",
                   "statistic": "difference", "task": "dice"},
                  ...],
   "decision": "..."}                  what follows if every hypothesis holds, and if not

Scores: "final" (the mean of the last k evaluations), "curve" (the mean over the evaluation
curve) or "closing" (the closing evaluation, closing.json), a run x task matrix each, over the
tasks the two rows share (or the one task a hypothesis names). The statistic: P = P(x > y),
the probability that a run of x scores above a run of y on a task (ties half, averaged over
tasks), with its 95 % stratified bootstrap interval (intervals.py); the verdict is *above*
where the interval lies above 0.5, *below* where it lies below, *level* where it lies inside
0.5 +- level_margin, else *not separated*. Or ("statistic": "difference") the mean score of
x minus y's (each the mean over tasks of the mean over runs), its interval the bootstrap's
with each row's runs resampled on their own: *above* / *below* where the interval clears 0,
*level* inside 0 +- level_margin / 2 (a difference of success, half P's margin: P moves
about twice as far as the mean for a shift among a few seeds), else *not separated*: where
tasks tie at 1.0 (every row solves them) P dilutes a difference and the mean does not.
An expectation holds: "above" / "below" / "level" on that verdict;
"not below" on any verdict but below; "not above" on any but above. The plan holds where
every hypothesis holds, and only once every run of its rows has finished.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
from typing import Any

import numpy as np

from discosyn_jax import atomic, checks, config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.experiments import intervals

PLAN_FILE = "plan.json"  # the plan, copied into the folder of its runs


class PlanError(BadInput):
  """A plan, or the runs it is judged on, that cannot be run or judged: the line names the
  file or the row and field (the CLI prints it alone, exit 2)."""

SCORES = ("final", "curve", "closing")
STATISTICS = ("P", "difference")
EXPECTATIONS = {"above": {"above"}, "below": {"below"}, "level": {"level"},
                "not below": {"above", "level", "not separated"},
                "not above": {"below", "level", "not separated"}}


@dataclasses.dataclass(frozen=True)
class Row:
  name: str
  seeds: tuple[int, ...]
  config: TrainConfig  # its seed that of the first seed; run(seed) gives each
  # committed records of its runs, one per seed, relative to the plan file's folder: a row
  # of records is read, not run
  records: tuple[str, ...] = ()

  def run_config(self, seed: int) -> TrainConfig:
    return self.config.replace(seed=seed).validate()

  def folder(self, seed: int) -> str:
    return f"{self.name}-seed{seed}"


@dataclasses.dataclass(frozen=True)
class Hypothesis:
  x: str
  y: str
  score: str
  expect: str
  statistic: str = "P"  # STATISTICS
  task: str = ""  # one task the rows share; "" for every shared task

  @property
  def text(self) -> str:
    return f"{self.x} {self.expect} {self.y} ({self.what})"

  @property
  def what(self) -> str:
    """Its task (where it names one), score and statistic (where not P), as a label says them."""
    return ", ".join(filter(None, (self.task, self.score,
                                   "" if self.statistic == "P" else self.statistic)))


@dataclasses.dataclass(frozen=True)
class Plan:
  name: str
  claim: str
  final_k: int
  level_margin: float
  rows: tuple[Row, ...]
  hypotheses: tuple[Hypothesis, ...]
  decision: str
  source: dict[str, Any]  # the file's JSON, as written
  base: pathlib.Path | None = None  # the plan file's folder: where its records are found

  def row(self, name: str) -> Row:
    return next(row for row in self.rows if row.name == name)

  def record(self, row: Row, seed: int) -> pathlib.Path:
    """Where the committed record of `row`'s run of `seed` lies."""
    return (self.base or pathlib.Path(".")) / row.records[row.seeds.index(seed)]


def load(path) -> Plan:
  """The checked plan in the file at `path`; PlanError naming the file and what is wrong."""
  path = pathlib.Path(path)
  try:
    values = json.loads(path.read_text())
  except FileNotFoundError:
    raise PlanError(f"no plan file {path}") from None
  except (json.JSONDecodeError, UnicodeDecodeError) as err:
    raise PlanError(f"plan {path}: not JSON ({err})") from None
  try:
    plan = dataclasses.replace(parse(values), base=path.parent)
  except (KeyError, TypeError, ValueError) as err:
    what = f"no {err}" if isinstance(err, KeyError) else str(err)
    raise PlanError(f"plan {path}: {what}") from None
  check_records(plan)
  return plan


def parse(values: dict[str, Any]) -> Plan:
  if not isinstance(values, dict):
    raise PlanError("not a JSON object")
  known = {"name", "claim", "final_k", "level_margin", "rows", "hypotheses", "decision"}
  unknown = sorted(set(values) - known)
  if unknown:
    raise PlanError(f"unknown field(s) {', '.join(unknown)}")
  for field in ("rows", "hypotheses"):
    if not isinstance(values[field], list) or not values[field]:
      raise PlanError(f"{field} must be a non-empty list, not {_shown(values[field])}")
  rows = tuple(_row(r, i) for i, r in enumerate(values["rows"]))
  names = [r.name for r in rows]
  if len(set(names)) != len(names):
    raise PlanError("rows must be given, each name once")
  hypotheses = tuple(_hypothesis(h, i) for i, h in enumerate(values["hypotheses"]))
  for h in hypotheses:
    for name in (h.x, h.y):
      if name not in names:
        raise PlanError(f"hypothesis {h.text}: no row {name!r}")
    if h.score not in SCORES:
      raise PlanError(f"hypothesis {h.text}: score is one of {', '.join(SCORES)}")
    if h.expect not in EXPECTATIONS:
      raise PlanError(f"hypothesis {h.text}: expect is one of {', '.join(EXPECTATIONS)}")
    if h.statistic not in STATISTICS:
      raise PlanError(f"hypothesis {h.text}: statistic is one of {', '.join(STATISTICS)}")
    shared = set(_row_by(rows, h.x).config.tasks) & set(_row_by(rows, h.y).config.tasks)
    if not shared:
      raise PlanError(f"hypothesis {h.text}: the two rows share no task ({h.x}: "
                       f"{', '.join(_row_by(rows, h.x).config.tasks)}; {h.y}: "
                       f"{', '.join(_row_by(rows, h.y).config.tasks)})")
    if h.task and h.task not in shared:
      raise PlanError(f"hypothesis {h.text}: task {h.task!r} is not one both rows train")
    if h.x == h.y:
      raise PlanError(f"hypothesis {h.text}: compares a row with itself")
  final_k, margin = values["final_k"], values["level_margin"]
  if not isinstance(final_k, int) or final_k < 1:
    raise PlanError(f"final_k must be a whole number >= 1, not {final_k!r}")
  if not isinstance(margin, (int, float)) or not 0 <= margin < 0.5:
    raise PlanError(f"level_margin must be in [0, 0.5), not {margin!r}")
  return Plan(str(values["name"]), str(values["claim"]), final_k, float(margin), rows,
              hypotheses, str(values["decision"]), values)


def _row_by(rows, name: str) -> Row:
  return next(r for r in rows if r.name == name)


def _shown(value) -> str:
  """A value as a message names it: short, one line."""
  return checks.shortened(json.dumps(value) if not isinstance(value, str) else repr(value))


MAX_NAME = 100  # a row's name is a folder's name: short, printable


def _hypothesis(values, index: int) -> Hypothesis:
  if not isinstance(values, dict):
    raise PlanError(f"hypotheses[{index}] must be an object (x, y, score, expect), not "
                     f"{_shown(values)}")
  fields = {f.name for f in dataclasses.fields(Hypothesis)}
  unknown, missing = sorted(set(values) - fields), [k for k in ("x", "y", "score", "expect")
                                                     if k not in values]
  if unknown or missing:
    raise PlanError(f"hypotheses[{index}]: " + (f"unknown field(s) {', '.join(unknown)}" if unknown
                                                 else f"no {missing[0]}"))
  bad = [k for k, v in values.items() if not isinstance(v, str)]
  if bad:
    raise PlanError(f"hypotheses[{index}]: {bad[0]} must be a string, not {_shown(values[bad[0]])}")
  return Hypothesis(**values)


def _row(values, index: int = 0) -> Row:
  if not isinstance(values, dict):
    raise PlanError(f"rows[{index}] must be an object (name, seeds, config), not {_shown(values)}")
  name, seeds, fields = values["name"], values["seeds"], values["config"]
  if (not isinstance(name, str) or not name or "/" in name or len(name) > MAX_NAME
      or not name.isprintable() or name in (".", "..")):
    raise PlanError(f"rows[{index}]: a row's name is a folder's name (printable, no '/', at most "
                     f"{MAX_NAME} characters), not {_shown(name)}")
  if (not isinstance(seeds, list) or not seeds or len(set(map(str, seeds))) != len(seeds)
      or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds)):
    raise PlanError(f"row {name}: seeds must be a list of distinct whole numbers, not {_shown(seeds)}")
  for seed in seeds:
    try:
      checks.seed(seed)
    except ValueError as err:
      raise PlanError(f"row {name}: {err}") from None
  if not isinstance(fields, dict):
    raise PlanError(f"row {name}: config must be an object of TrainConfig fields, not {_shown(fields)}")
  if "seed" in fields:
    raise PlanError(f"row {name}: its config gives no seed (the row's seeds do)")
  records = values.get("records", [])
  unknown = sorted(set(values) - {"name", "seeds", "config", "records"})
  if unknown:
    raise PlanError(f"row {name}: unknown field(s) {', '.join(unknown)}")
  if records and (len(records) != len(seeds) or not all(isinstance(r, str) and r for r in records)):
    raise PlanError(f"row {name}: records must be one folder per seed ({len(seeds)})")
  try:
    # a plan written before a field was added ran with that field's value of then
    config = TrainConfig.from_dict(config_lib.with_added({**fields, "seed": seeds[0]})[0]).validate()
  except (TypeError, ValueError) as err:
    raise PlanError(f"row {name}: {err}") from None
  return Row(name, tuple(seeds), config, tuple(records))


def _differs(saved: TrainConfig, wanted: TrainConfig, whose: str) -> str:
  """'' where `saved` trains the run `wanted` describes, else its first field that differs,
  as a refusal says it ("its lr is 0.001, the plan's 0.0003")."""
  if config_lib.same_run(saved, wanted):
    return ""
  field = next(k for k, v in saved.to_dict().items() if getattr(wanted, k) != v)
  return f"its {field} is {getattr(saved, field)!r}, {whose} {getattr(wanted, field)!r}"


def check_records(plan: Plan) -> None:
  """Refuse a plan whose named records are missing, or are not the runs of their row's
  config and seed (a record names the config it ran: config.json)."""
  for row in plan.rows:
    for seed in row.seeds if row.records else ():
      path = plan.record(row, seed)
      config_file = path / "config.json"
      if not config_file.is_file():
        raise PlanError(f"row {row.name}: no record of seed {seed} at {path}")
      differs = _differs(config_lib.load(config_file), row.run_config(seed), "the row's")
      if differs:
        raise PlanError(f"row {row.name}: {path} is not the run of the row's config: {differs}")


def row_fields(config: TrainConfig) -> dict[str, Any]:
  """A row's config as a plan writes it: every field but the seed."""
  return {k: v for k, v in config.to_dict().items() if k != "seed"}


# -- running it ----------------------------------------------------------------------
def steps(plan: Plan, out: pathlib.Path) -> list:
  """The plan's runs as steps of paper.py (trained, resumed or kept as any step), in the
  order of its seeds then rows: the first seeds of every row come first."""
  from discosyn_jax.experiments import paper, report_runs

  out = pathlib.Path(out)
  runs = []
  methods = [report_runs.method_of(row.config) for row in plan.rows]
  for index in range(max(len(row.seeds) for row in plan.rows)):
    for row, method in zip(plan.rows, methods):
      if index < len(row.seeds) and not row.records:
        seed = row.seeds[index]
        config = row.run_config(seed)
        if methods.count(method) > 1:  # rows apart in a field the name does not carry
          method = method.replace(tag=(*method.tag, row.name))
        meta = dict(experiment=f"confirm-{plan.name}", method=str(method),
                    set=report_runs.set_of(config), seed=seed, scale=f"plan {plan.name}",
                    row=row.name)
        runs.append(paper.Train(row.folder(seed), config, meta))
  return runs


def check_folder(plan: Plan, out: pathlib.Path) -> None:
  """Refuse a folder that holds another plan, or a run whose config is not the plan's."""
  out = pathlib.Path(out)
  if out.exists() and not out.is_dir():
    raise PlanError(f"{out} is not a folder: the plan's runs go in a folder")
  held = out / PLAN_FILE
  if held.exists() and not held.is_file():
    raise PlanError(f"{held} is not a file: the folder's plan file is in the way")
  if held.is_file():
    try:
      same = json.loads(held.read_text()) == plan.source
    except (json.JSONDecodeError, UnicodeDecodeError):
      same = False
    if not same:
      raise PlanError(f"{out} holds the runs of another plan ({held} differs from this one)")
  for row in plan.rows:
    for seed in () if row.records else row.seeds:
      config_file = out / row.folder(seed) / "config.json"
      if config_file.is_file():
        differs = _differs(config_lib.load(config_file), row.run_config(seed), "the plan's")
        if differs:
          raise PlanError(f"{config_file.parent} is not the plan's run: {differs}")


def check_runnable(plan: Plan) -> None:
  """Refuse, before anything is written, a plan whose rows name a task, a hand or a decoder
  source that is not there."""
  from discosyn_jax import tasks
  from discosyn_jax.env import hands
  from discosyn_jax.synergies import fitting

  for row in plan.rows:
    if row.records:
      continue
    try:
      tasks.expand(row.config.tasks)
      hands.load(row.config.hand)
      if row.config.decoder_from and not fitting.resolve(row.config.decoder_from).exists():
        raise PlanError(f"decoder_from {row.config.decoder_from} does not exist")
    except ValueError as err:
      raise PlanError(f"row {row.name}: {err}") from None


def run(plan_path, out, *, progress: bool = False, log=print) -> list[pathlib.Path]:
  """LabelledRun (or continue) every run of the plan in `out`; the plan is copied there first. A run
  that another process is writing is passed by, so that the same command started twice
  trains two runs side by side."""
  from discosyn_jax.run import owner

  plan = load(plan_path)
  out = pathlib.Path(out)
  check_folder(plan, out)
  check_runnable(plan)  # everything known good before OUT is made
  out.mkdir(parents=True, exist_ok=True)
  atomic.write_text(out / PLAN_FILE, json.dumps(plan.source, indent=1) + "\n")
  folders = []
  for step in steps(plan, out):
    folders.append(out / step.name)
    if step.done(out):
      log(f"[{step.name}] done already; kept")
      step.settle(out, log)
      continue
    if owner.writer_of(out / step.name):
      log(f"[{step.name}] being trained by another process; passed by")
      continue
    log(f"[{step.name}] train")
    try:
      step.run(out, progress, log)
    except owner.Busy:  # taken by another process since the look above
      log(f"[{step.name}] being trained by another process; passed by")
  return folders


# -- judging it ----------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Verdict:
  hypothesis: Hypothesis
  p: intervals.Estimate | None  # None until both rows have finished runs
  runs: tuple[int, int]  # finished runs of x and of y
  verdict: str
  holds: bool | None  # None until every planned run has finished


def judge(p: intervals.Estimate, margin: float, statistic: str = "P") -> str:
  """The verdict of the rule (module docstring) on P(x > y), or on the difference of the
  means, and its interval."""
  if statistic == "difference":
    found = intervals.verdict(p, centre=0.0)
    margin = margin / 2
    centre = 0.0
  else:
    found, centre = intervals.verdict(p), 0.5
  if found == "not separated" and centre - margin <= p.low and p.high <= centre + margin:
    return "level"
  return found


def check_successes(run, tasks_) -> None:
  """Refuse a run whose evaluations (or closing evaluation) hold a success that is not a
  number in [0, 1], naming the run, the evaluation and the task: a damaged number is never
  turned into a verdict."""
  found = [(f"the evaluation at step {row.get('step')}", row) for row in run.evaluations]
  if run.closing:
    found.append(("its closing evaluation", run.closing))
  for where, row in found:
    for task in tasks_:
      value = row.get(f"{task}/success")
      if value is None:
        continue  # a task this evaluation did not hold: scores() leaves the run out
      if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 1:
        raise PlanError(f"{run.path}: {task}/success is {value!r} in {where}, not a success "
                         "in [0, 1]; the report refuses to judge on it")


def scores(runs, tasks_, score: str, final_k: int) -> np.ndarray | None:
  """A runs x tasks matrix of one score of finished runs (None for none)."""
  rows = []
  for run in runs:
    check_successes(run, tasks_)
    if score == "closing":
      row = run.closing or {}
    elif score == "final":
      row = run.at_end(final_k)
    else:
      row = {f"{t}/success": value for t, value in run.curve.items()}
    if all(f"{t}/success" in row for t in tasks_):
      rows.append([row[f"{t}/success"] for t in tasks_])
  return np.array(rows) if rows else None


def verdicts(plan: Plan, runs) -> list[Verdict]:
  """Each hypothesis of `plan` judged on `runs` (report_runs.LabelledRun, those of its folder)."""
  def of(row: Row):
    if row.records:
      wanted = {plan.record(row, seed).resolve() for seed in row.seeds}
      return [r for r in runs if r.path.resolve() in wanted and r.finished and r.evaluations]
    names = {row.folder(seed) for seed in row.seeds}
    return [r for r in runs if r.path.name in names and r.finished and r.evaluations]

  everything = all(len(of(row)) == len(row.seeds) for row in plan.rows)
  out = []
  for h in plan.hypotheses:
    x_row, y_row = plan.row(h.x), plan.row(h.y)
    shared = [h.task] if h.task else [t for t in x_row.config.tasks if t in y_row.config.tasks]
    x = scores(of(x_row), shared, h.score, plan.final_k)
    y = scores(of(y_row), shared, h.score, plan.final_k)
    counts = (0 if x is None else len(x), 0 if y is None else len(y))
    if x is None or y is None:
      out.append(Verdict(h, None, counts, "no runs yet", None))
      continue
    statistic = (intervals.mean_difference if h.statistic == "difference" else
                 intervals.probability_of_improvement)
    p = statistic({h.score: x}, {h.score: y})[h.score]
    if min(counts) < 2:  # one run a row: a bootstrap of one has no spread to judge by
      out.append(Verdict(h, p, counts, "too few runs", None))
      continue
    found = judge(p, plan.level_margin, h.statistic)
    holds = found in EXPECTATIONS[h.expect] if everything else None
    out.append(Verdict(h, p, counts, found, holds))
  return out


def report_lines(plan: Plan, runs) -> list[str]:
  """The report's section of a plan: each hypothesis with P, its interval, its verdict and
  whether it holds; then the plan's own decision rule and where it stands."""
  found = verdicts(plan, runs)
  planned = sum(len(row.seeds) for row in plan.rows)
  finished = sum(1 for row in plan.rows for seed in row.seeds
                 if any(r.finished and (r.path.resolve() == plan.record(row, seed).resolve()
                                        if row.records else r.path.name == row.folder(seed))
                        for r in runs))
  lines = [f"## Confirmation: {plan.name}", "", plan.claim, "",
           f"{finished} of {planned} planned runs finished. Final success: the mean of the last "
           f"{plan.final_k} evaluations. P = P(x > y) with its 95 % stratified bootstrap "
           f"interval; *above* / *below*: the interval clears 0.5; *level*: it lies inside "
           f"0.5 ± {plan.level_margin:g}; else *not separated*. A *difference*: x's mean "
           f"minus y's, its interval the bootstrap's, judged against 0 with *level* inside "
           f"0 ± {plan.level_margin / 2:g}.", "",
           "| hypothesis | runs (x, y) | P(x > y) or difference | verdict | expected | holds |",
           "|---|---|---|---|---|---|"]
  for v in found:
    p = "–" if v.p is None else f"{v.p.value:+.3f} [{v.p.low:+.3f}, {v.p.high:+.3f}]" if (
        v.hypothesis.statistic == "difference") else f"{v.p.value:.2f} [{v.p.low:.2f}, {v.p.high:.2f}]"
    holds = "pending" if v.holds is None else "yes" if v.holds else "no"
    lines.append(f"| {v.hypothesis.x} vs {v.hypothesis.y} ({v.hypothesis.what}) | "
                 f"{v.runs[0]}, {v.runs[1]} | {p} | {v.verdict} | {v.hypothesis.expect} | {holds} |")
  if finished < planned:
    outcome = "The plan is pending: not every planned run has finished."
  else:
    outcome = "The plan holds." if all(v.holds for v in found) else "The plan does not hold."
  lines += ["", f"{outcome} Decision rule: {plan.decision}", "",
            "| row | seeds | runs | a task acts in | directions in all |", "|---|---|---|---|---|"]
  for row in plan.rows:
    acts, total = dimensions(row.config)
    source = "committed records" if row.records else "run by the plan"
    lines.append(f"| {row.name} | {', '.join(map(str, row.seeds))} | {source} | {acts} | {total} |")
  return lines + [""]


def dimensions(config: TrainConfig) -> tuple[str, str]:
  """(the action dimensions a task acts in, the directions there are in all): b + k and
  b + tasks x k with each task's own synergies; the full action for PPO."""
  if config.kind.full_action:
    return f"{config.n_synergies} (the full action)", str(config.n_synergies)
  if not config.own_synergies:
    return str(config.n_synergies), str(config.n_synergies)
  b, k, n = config.n_synergies, config.own_synergies, len(config.tasks)
  return f"{b + k} ({b} shared + {k} own)", f"{b + n * k} ({b} + {n} x {k})"


def record_paths(plan: Plan) -> list[pathlib.Path]:
  """The committed records a plan's rows name (read beside the runs of its folder)."""
  return [plan.record(row, seed) for row in plan.rows if row.records for seed in row.seeds]


def plans_in(paths) -> list[tuple[Plan, pathlib.Path]]:
  """The plans of the folders given to the report: each folder's own plan.json (a folder
  above a folder given is not read: a run's folder given alone reports that run)."""
  found = []
  for folder in (pathlib.Path(p).resolve() for p in paths):
    if (folder / PLAN_FILE).is_file() and all(f != folder for _, f in found):
      found.append((load(folder / PLAN_FILE), folder))
  return found
