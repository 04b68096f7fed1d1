"""The runs and fits `discosyn report` reads (report.py): each run folder with its method,
task set and seed (from its experiment.json, else from its config), its evaluations and its
closing evaluation.

A run's *final* success is the mean of its last `final_k` evaluations (FINAL_K by default):
one evaluation of a few dozen episodes swings a task by tenths, the mean of three less so.
Its *closing* evaluation (closing.json, `closing_episodes` a task on episodes of their own)
is the end measured once more, where the run has one."""

from __future__ import annotations

import dataclasses
import functools
import pathlib
from typing import Any

from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import hands
from discosyn_jax.run import folder, layout, record_files
from discosyn_jax.run.record_files import RecordError
from discosyn_jax.experiments import record
from discosyn_jax.experiments.method import Method, Residual
from discosyn_jax import tasks
from discosyn_jax.tasks import TASK_SETS

MAIN_EXPERIMENTS = ("discosyn", "baselines", "confirm")
FINAL_K = folder.FINAL_K


@dataclasses.dataclass(frozen=True, kw_only=True)
class LabelledRun(folder.Run):
  """A run as the report reads it (folder.Run), with the labels its tables group it by."""
  experiment: str
  method: Method
  task_set: str
  seed: int
  scale: str | None  # None for a run `discosyn experiment` did not make
  final_k: int = FINAL_K

  @property
  def main(self) -> bool:
    """A run of the solved tables (DiscoSyn or a baseline), not transfer or sparse."""
    return self.experiment.split("-")[0] in MAIN_EXPERIMENTS or self.experiment == "train"

  @property
  def final(self) -> dict[str, Any]:
    """Each task's figures averaged over the last `final_k` evaluations (folder.Run.final)."""
    return self.at_end(self.final_k)

  def per_task_env_steps(self, row) -> int:
    return row["step"] * self.config.num_envs * self.config.unroll_length

  @property
  def action_size(self) -> int:
    return action_size(self.config.tasks[0], self.config.hand)


@functools.cache
def action_size(task: str, hand: str) -> int:
  """The action size of `task` on `hand`: the hand's actuators, or a pure-JAX task's own
  (its env built once). A task no longer known (a file gone) counts as a hand's."""
  import discosyn_jax.tasks.registry as registry

  entry = registry.REGISTRY.get(task)
  if entry is not None and entry.env is not registry.HandEnv:
    return registry.make(task, hand=hand).action_size
  return len(hands.actuators(hand))


def method_of(config: TrainConfig) -> Method:
  """The method a config runs, as the report names it where experiment.json is silent."""
  from discosyn_jax.synergies import fitting

  if not config.decoder_from or config.kind.full_action:
    return Method.of(config)
  # a space from elsewhere, named by its source, how it is used here (frozen, or learned on
  # with this run's own switches) and the residual it acts with here
  own = Method.of(config)
  reused = dict(reuse="frozen" if config.freeze_decoder else "tuned",
                acting_residual=Residual.of(config))
  try:  # a synergy file knows its method (PCA, AE); a run folder is DiscoSyn's
    source = Method.of(fitting.read(config.decoder_from)[0])
  except ValueError:
    return own.replace(residual=None, **reused)
  if not config.freeze_decoder:
    reused["tag"] = source.tag + tuple(part for part in own.tag if part not in source.tag)
  return source.replace(**reused)


def set_of(config: TrainConfig) -> str:
  for name, members in TASK_SETS.items():
    if tuple(members) == tuple(config.tasks):
      return name
  return "+".join(tasks.label(task) for task in config.tasks)  # one's own task by its class


def read(path: pathlib.Path) -> LabelledRun:
  """The run or record at `path` with the labels the report groups it by."""
  from discosyn_jax.run import checkpoints, owner

  config = record.saved_config(path)  # its decoder_from found where the folder is now
  writer = owner.writer_of(path)
  if writer:  # its logs are read as far as they go now
    checkpoints.warn(f"{path} is being written by {writer}: read its logs as they are now")
  run = folder.read(path, config)
  meta = run.labels
  # derived from the config only where experiment.json is silent (method_of may read a file)
  task_set = meta["set"] if "set" in meta else set_of(config)
  if config.hand != hands.DEFAULT:  # another hand's runs are never pooled with ours
    task_set = f"{task_set} on {hands.label(config.hand)}"
  fields = {f.name: getattr(run, f.name) for f in dataclasses.fields(folder.Run)}
  return LabelledRun(**{**fields, "path": path}, experiment=meta.get("experiment", "train"),
                     method=_method(path, meta) if "method" in meta else method_of(config),
                     task_set=task_set, seed=meta.get("seed", config.seed), scale=meta.get("scale"))


def _method(path: pathlib.Path, meta: dict[str, Any]) -> Method:
  try:
    return Method.parse(meta["method"])
  except ValueError as err:
    raise RecordError(f"{path / layout.EXPERIMENT_FILE}: method: {err}") from None


def find(paths, inside: bool = False, final_k: int = FINAL_K) -> tuple[list[LabelledRun], list[dict[str, Any]]]:
  """The runs and the synergy fits in `paths` (run folders, fit folders, or folders of them),
  each run's final success the mean of its last `final_k` evaluations. A folder named here
  must hold one; one found inside (a report, say) may hold none."""
  if final_k < 1:
    raise BadInput(f"the final success is the mean of at least 1 evaluation, not {final_k}")
  runs, fits = [], []
  for path in map(pathlib.Path, paths):
    if not path.is_dir():
      raise BadInput(f"{path} is not a folder")
    if (path / layout.CONFIG_FILE).is_file():
      runs.append(dataclasses.replace(read(path), final_k=final_k))
    elif (path / record.FIT_FILE).is_file():
      fits.append(record_files.read_object(path / record.FIT_FILE))
    else:
      inner = sorted(p for p in path.iterdir() if p.is_dir())
      found = find(inner, inside=True, final_k=final_k) if inner else ([], [])
      if not found[0] and not found[1] and not inside:
        raise BadInput(f"{path} holds no run (config.json) and no synergy fit")
      runs += found[0]
      fits += found[1]
  if not inside:
    _one_run_per_seed(runs)
  return runs, fits


def _one_run_per_seed(runs: list[LabelledRun]) -> None:
  """Two runs of one method and seed would count as two seeds: name the pair instead."""
  seen = {}
  for run in runs:
    key = (run.experiment, run.task_set, tuple(run.config.tasks), run.method, run.seed)
    if key in seen:
      raise BadInput(f"{seen[key].path} and {run.path} are both {run.method} seed {run.seed} "
                     f"on {run.task_set}; give the report one of them")
    seen[key] = run


def order(methods) -> list[Method]:
  """Methods in the report's order of rows (Method.rank)."""
  return sorted(set(methods), key=Method.rank)
