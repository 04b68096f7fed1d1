"""Finding, checking and reading a run folder (its layout: layout.py): which folder holds a
run, whether a run may be started, continued or replaced there, and its config and newest
good checkpoint, read even while another process writes the run."""

from __future__ import annotations

import os
import pathlib
from typing import Any

from discosyn_jax import config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.run import checkpoints, layout, owner


def run_config(run_dir: pathlib.Path, config: TrainConfig, resume: bool, force: bool) -> TrainConfig:
  """Check the run directory against what is asked, writing nothing, and return the config
  to run.

  A directory that holds a run is only continued (`resume`) or replaced (`force`, a run
  this product made only), never silently overwritten, and never while another process
  writes it; resuming keeps the run's config, except the fields that say how long and how
  often (config.RESUMABLE), which are taken from `config`.
  """
  run_dir = pathlib.Path(run_dir)
  if run_dir.exists() and not run_dir.is_dir():
    raise BadInput(f"{run_dir} is a file, not a run directory")
  holds_run = (run_dir / layout.CONFIG_FILE).is_file()
  if resume:
    if not holds_run:
      raise BadInput(f"--resume: {run_dir} holds no run to continue")
    _check_writable(run_dir)
    saved = config_lib.load(run_dir / layout.CONFIG_FILE)
    differs = config_lib.mismatches(saved, config)
    if differs:
      raise BadInput(f"--resume: the run in {run_dir} does not match: {differs[0]}")
    return saved.replace(**{k: getattr(config, k) for k in config_lib.RESUMABLE}).validate()
  if holds_run and not force:
    raise BadInput(f"{run_dir} already holds a run; pass --resume to continue it or "
                   f"--force to replace it")
  # --force replaces a run, never a folder of something else
  if holds_run and not owner.is_run(run_dir):
    raise BadInput(f"{run_dir} holds a {layout.CONFIG_FILE} but no run of discosyn (none of "
                   f"{', '.join(sorted(layout.RUN_NAMES - {layout.ASIDE}))}); --force replaces "
                   f"only a run: choose another directory")
  if run_dir.exists() and not holds_run and owner.contents(run_dir):
    raise BadInput(f"{run_dir} is not empty and holds no run; choose another directory")
  _check_writable(run_dir)
  return config.validate()


def _check_writable(path: pathlib.Path) -> None:
  """Refuse a path that cannot be written (or created): a file in the way, a read-only
  folder or file system."""
  existing = next(p for p in (path, *path.parents) if p.exists() or p == p.parent)
  if not existing.is_dir():
    raise BadInput(f"cannot write {path}: {existing} is a file, not a folder")
  if not os.access(existing, os.W_OK | os.X_OK):
    raise BadInput(f"cannot write {path}: {existing} is not writable")


def find_run_dir(path: pathlib.Path) -> pathlib.Path:
  """The run directory that is or holds `path` (a checkpoint folder in it)."""
  path = pathlib.Path(path)
  for run_dir in (path, *path.parents):
    if (run_dir / layout.CONFIG_FILE).is_file():
      return run_dir
  raise BadInput(f"{path} is not a run directory or a checkpoint in one")


def newest(path: pathlib.Path, read,
             warn=checkpoints.warn) -> tuple[TrainConfig, pathlib.Path, Any]:
  """(config, checkpoint, read(checkpoint)) of a run directory (its newest checkpoint that
  `read` takes, a snapshot even of a run being written: checkpoints.read_newest) or of a
  checkpoint folder. Of a run another process is writing, one line says so and what was read."""
  path = pathlib.Path(path)
  run_dir = find_run_dir(path)
  config = config_lib.load(run_dir / layout.CONFIG_FILE)
  if path != run_dir:
    return config, path, read(path)
  checkpoint, value = checkpoints.read_newest(
      run_dir, read, lambda damaged, err: warn(f"{err}; skipped it"))
  writer = owner.writer_of(run_dir)
  if checkpoint is None:
    raise BadInput(f"{run_dir} holds no good checkpoint yet"
                   + (f" (it is being written by {writer})" if writer else ""))
  if writer:
    warn(f"{run_dir} is being written by {writer}: read its checkpoint {checkpoint}, "
         f"step {checkpoints.verify(checkpoint)}")
  return config, checkpoint, value
