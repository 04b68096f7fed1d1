"""The one place that assembles a run from a config: the envs of its tasks (tasks/registry.py)
and the Trainer on them, trained in a run folder by the host loop (training/loop.py), or a
run's trained state restored. A layer of its own, above the tasks and below the experiments:
the public API (`ds.train`, `ds.evaluate`), the command line and the experiments all go
through here; the library below takes a Trainer and knows no registry.

A test or a study with environments of its own registers them (`registry.register`) and
then goes through here too.
"""

from __future__ import annotations

import pathlib
from typing import Any, Callable

from discosyn_jax import checks
from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.run import checkpoints, jax_setup, layout, owner, reading
from discosyn_jax.tasks import registry
from discosyn_jax.training import loop
from discosyn_jax.training.trainer import Trainer, TrainState
from discosyn_jax.viz import plots


def trainer(config: TrainConfig, **kwargs) -> Trainer:
  """A Trainer of `config` on its tasks' envs; `kwargs` go to Trainer (devices). JAX is set
  up first, once a process (run/jax_setup.py: the persistent compile cache on)."""
  jax_setup.setup_jax()
  return Trainer(config, registry.make_envs(config), **kwargs)


def train(config: TrainConfig, run_dir, *, resume: bool = False, force: bool = False,
          progress: bool = True, log=print, stop_at: float | None = None,
          on_eval: Callable[[int, dict], None] | None = None, **trainer_kwargs) -> dict[str, Any]:
  """Train (or continue) `config` in `run_dir` (loop.train says what the loop does and what
  it refuses); the training curves are drawn into RUN/plots at the end. `trainer_kwargs` go
  to the Trainer (devices). Returns the loop's {"results", "closing", "state", "trainer",
  "compile_s"}."""
  run_dir = pathlib.Path(run_dir)
  owner.refuse_if_written(run_dir)
  config = reading.run_config(run_dir, config, resume, force)  # the run's own, when resuming
  built = trainer(config, **trainer_kwargs)

  return loop.train(built, run_dir, resume=resume, force=force, progress=progress, log=log,
                    stop_at=stop_at, on_eval=on_eval, on_end=lambda: _curves(run_dir, log))


def _curves(run_dir: pathlib.Path, log) -> None:
  log(f"training curves: {', '.join(map(str, plots.run_curves(run_dir, run_dir / layout.PLOTS_DIR)))}")


def finish(run_dir, log=print) -> None:
  """What a finished run's writer did not get to before it died (killed after its final
  checkpoint): its lock left behind is taken over (one warning) and released, its missing
  training curves drawn. A run a live process writes is left to it."""
  run_dir = pathlib.Path(run_dir)
  missing = (run_dir / layout.FINAL).is_dir() and not all(
      (run_dir / layout.PLOTS_DIR / name).is_file() for name in plots.CURVES)
  if not (missing or (run_dir / layout.LOCK).exists()) or owner.writer_of(run_dir):
    return
  try:
    with owner.Writer(run_dir):
      if missing:
        _curves(run_dir, log)
  except owner.Busy:  # taken by a live writer since the look above: it finishes the run
    pass


def load(path, **changes) -> tuple[Trainer, TrainState]:
  """The trainer and the restored state of a run (its newest checkpoint that restores) or of
  one checkpoint; `changes` replace config fields that do not change the state's layout
  (backend, eval_envs)."""
  run_dir = reading.find_run_dir(pathlib.Path(path))
  config = config_lib.load(run_dir / layout.CONFIG_FILE)
  built = trainer(config.replace(**changes).validate())
  checks.memory(built.config, built.envs)
  _, _, state = reading.newest(path, lambda checkpoint: checkpoints.restore(checkpoint, built.init()))
  return built, state
