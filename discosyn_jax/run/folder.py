"""A run folder as read: one type for a run and for its record kept without checkpoints
(docs/results/...), the one reader, and the one place that decides whether a run finished.

`ds.read_run(PATH)` is `read`; the report reads every run through it too and adds its own
labels (experiments/report_runs.py), so a figure of a run is computed once, here.
"""

from __future__ import annotations

import dataclasses
import pathlib
from typing import Any

import numpy as np

from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.run import layout, logs, reading, record_files

FINAL_K = 3  # evaluations whose mean is a run's final success (the report's, a synergy file's)


@dataclasses.dataclass(frozen=True)
class Run:
  """A run folder: its config, its evaluations (eval.jsonl rows: env_steps, "<task>/success",
  ...), its training metrics (metrics.jsonl, or the record's .xz, at the record's precision:
  a run and its record read the same), its closing evaluation (closing.json, None without
  one), its labels (experiment.json, {} without one) and whether it finished."""
  path: pathlib.Path
  config: TrainConfig
  evaluations: list[dict[str, Any]]
  metrics: list[dict[str, Any]]
  closing: dict[str, Any] | None = None
  labels: dict[str, Any] = dataclasses.field(default_factory=dict)
  finished: bool = False

  @property
  def success(self) -> dict[str, float]:
    """Each task's deterministic success at the last evaluation."""
    last = self.evaluations[-1] if self.evaluations else {}
    return {task: last[f"{task}/success"] for task in self.config.tasks if f"{task}/success" in last}

  def at_end(self, k: int = FINAL_K) -> dict[str, Any]:
    """The newest evaluation with each task's figures averaged over the last `k` (its step,
    env steps and wall clock its own): the report's final success."""
    rows = self.evaluations[-k:]
    if not rows:
      return {}
    out = dict(rows[-1])
    for key in (key for key in rows[-1] if "/" in key):
      out[key] = float(np.mean([row[key] for row in rows if key in row]))
    return out

  @property
  def mean_success(self) -> float:
    """The mean over the tasks and the evaluations: the area under the success curve."""
    rows = [row[f"{task}/success"] for row in self.evaluations for task in self.config.tasks
            if f"{task}/success" in row]
    return sum(rows) / len(rows) if rows else float("nan")

  @property
  def curve(self) -> dict[str, float]:
    """Each task's success averaged over the evaluations: its area under the curve."""
    return {task: sum(values) / len(values) for task in self.config.tasks
            if (values := [row[f"{task}/success"] for row in self.evaluations
                           if f"{task}/success" in row])}

  def action_shares(self, last: int = 10) -> dict[str, tuple[float, float]]:
    """Each task's mean |D(z)| and mean rho |r| per actuator over the `last` logged train
    steps: how much of the action the synergies and the residual carry ({} for a run
    without a residual)."""
    rows = [row for row in self.metrics if "residual/rho" in row][-last:]
    mean = lambda key: float(np.mean([row[key] for row in rows]))
    return {task: (mean(f"{task}/action_synergy"), mean(f"{task}/action_residual"))
            for task in self.config.tasks if rows and f"{task}/action_residual" in rows[-1]}


def finished(run_dir: pathlib.Path, config: TrainConfig, evaluations: list[dict[str, Any]]) -> bool:
  """Whether the run in `run_dir` finished: its final checkpoint, or (a record kept without
  checkpoints) an evaluation at its last step."""
  return (pathlib.Path(run_dir) / layout.FINAL).is_dir() or bool(
      evaluations and evaluations[-1]["step"] >= config.steps)


def read(path, config: TrainConfig | None = None) -> Run:
  """The run of a run folder (or of a checkpoint folder in one); `config`: its config as
  already read (a record's decoder_from found where the folder is now, say). A file of it
  that does not hold what a run writes is refused (record_files.RecordError)."""
  run_dir = reading.find_run_dir(pathlib.Path(path))
  config = config or config_lib.load(run_dir / layout.CONFIG_FILE)
  evaluations = logs.read_log(run_dir / layout.EVAL_FILE)
  closing_file, labels_file = run_dir / layout.CLOSING_FILE, run_dir / layout.EXPERIMENT_FILE
  closing = record_files.read_closing(closing_file) if closing_file.is_file() else None
  labels = record_files.read_labels(labels_file) if labels_file.is_file() else {}
  _check_ended(run_dir, evaluations, [f.name for f in (labels_file, closing_file) if f.is_file()])
  return Run(path=run_dir, config=config, evaluations=evaluations,
             metrics=logs.read_log(run_dir / layout.METRICS_FILE, as_archived=True),
             closing=closing, labels=labels, finished=finished(run_dir, config, evaluations))


def _check_ended(run_dir: pathlib.Path, evaluations, ended: list[str]) -> None:
  """A run that ended (`ended`: its files written at its end, after its last evaluation)
  has every evaluation whole: none gone, no last line cut short as a kill leaves it."""
  if not ended:
    return
  path = run_dir / layout.EVAL_FILE
  if not evaluations:
    raise record_files.RecordError(
        f"{path}: no evaluation, but the run ended ({ended[0]} is written at its end); "
        "expected its evaluations, the last at its final step")
  if not path.is_file():  # read from its archive alone
    return
  with open(path, "rb") as f:
    f.seek(-1, 2)
    if f.read(1) != b"\n":
      raise record_files.RecordError(
          f"{path}: its last line is cut short, but the run ended ({ended[0]} is written at "
          "its end); expected every evaluation whole")
