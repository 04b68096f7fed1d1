"""The functions of the public API that join the parts: train a config into a run folder,
evaluate a run, read a finished run. `discosyn_jax/__init__.py` exports them with the rest;
the command line is built on the same parts."""

from __future__ import annotations

import dataclasses
import pathlib
from typing import Any, Callable

from discosyn_jax.config import TrainConfig


def train(config: TrainConfig | str = "quickstart", run_dir: str | pathlib.Path | None = None, *,
          progress_fn: Callable[[int, dict], None] | None = None, resume: bool = False,
          force: bool = False, progress: bool = True, stop_at: float | None = None,
          log: Callable[[str], None] = print) -> dict[str, Any]:
  """Train `config` (a TrainConfig, or a preset's name) into `run_dir` (default:
  runs/<preset or "run">-seed<seed>) on the registered tasks, or continue it (`resume`).

  `progress_fn(env_steps, row)` is called after every evaluation with its row of
  eval.jsonl ("<task>/success", "<task>/return", "step", "wall_s"). Returns
  {"results": {task: {"success", "return"}}, "run_dir", "state", "trainer", "compile_s"}.
  Ctrl-C stops the run cleanly and names the checkpoint it resumes from.
  """
  from discosyn_jax.experiments import presets
  from discosyn_jax.tasks import assemble

  name = config if isinstance(config, str) else "run"
  if isinstance(config, str):
    config = presets.preset(config)
  config = config.validate()
  run_dir = pathlib.Path(run_dir if run_dir is not None else f"runs/{name}-seed{config.seed}")
  on_eval = None if progress_fn is None else (lambda _, row: progress_fn(row["env_steps"], row))
  done = assemble.train(config, run_dir, resume=resume, force=force, progress=progress, log=log,
                        stop_at=stop_at, on_eval=on_eval)
  return {**done, "run_dir": run_dir}


def evaluate(run: str | pathlib.Path, *, episodes: int | None = None,
             backend: str | None = None) -> dict[str, dict[str, float]]:
  """The deterministic policy of a run (its newest good checkpoint) or of one checkpoint:
  {task: {"success", "return"}} over `episodes` per task (default: the run's eval_envs)."""
  from discosyn_jax.tasks import assemble
  from discosyn_jax.training import evaluation

  changes = {"backend": backend} if backend else {}
  if episodes is not None:
    changes["eval_envs"] = episodes
  trainer, state = assemble.load(pathlib.Path(run), **changes)
  return evaluation.evaluate(trainer, state)


@dataclasses.dataclass(frozen=True)
class Run:
  """A run folder as read: its config, its evaluations (eval.jsonl rows, env_steps and
  "<task>/success" ...) and its training metrics (metrics.jsonl, or the record's .xz)."""
  path: pathlib.Path
  config: TrainConfig
  evaluations: list[dict[str, Any]]
  metrics: list[dict[str, Any]]

  @property
  def success(self) -> dict[str, float]:
    """Each task's deterministic success at the last evaluation."""
    last = self.evaluations[-1] if self.evaluations else {}
    return {task: last[f"{task}/success"] for task in self.config.tasks if f"{task}/success" in last}

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
    steps, as the report's residual table reads them: how much of the action the synergies
    and the residual carry ({} for a run without a residual)."""
    rows = [row for row in self.metrics if "residual/rho" in row][-last:]
    mean = lambda key: sum(row[key] for row in rows) / len(rows)
    return {task: (mean(f"{task}/action_synergy"), mean(f"{task}/action_residual"))
            for task in self.config.tasks if rows and f"{task}/action_residual" in rows[-1]}


def read_run(path: str | pathlib.Path) -> Run:
  """A run folder, or a run's record kept without checkpoints (docs/results/...), as a Run."""
  from discosyn_jax import config as config_lib
  from discosyn_jax.run import layout, logs, reading

  run_dir = reading.find_run_dir(pathlib.Path(path))
  return Run(path=run_dir, config=config_lib.load(run_dir / layout.CONFIG_FILE),
             evaluations=logs.read_log(run_dir / layout.EVAL_FILE),
             metrics=logs.read_log(run_dir / layout.METRICS_FILE))
