"""The host loop: train steps, logs, evaluations and checkpoints, and nothing else.

Everything numerical happens inside the jitted `Trainer.train_step`; between steps this
loop writes one JSON line of metrics (and TensorBoard scalars, logs.py), evaluates the deterministic policy every
`eval_every` steps, checkpoints every `checkpoint_every` steps and at the end, where it
also draws the training curves (plots.py).
"""

from __future__ import annotations

import json
import math
import pathlib
import shutil
import sys
import time
from typing import Any

import jax

from discosyn_jax import checkpoints, logs, plots
from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.train import Trainer, TrainState

CONFIG_FILE = "config.json"


class TrainingDiverged(RuntimeError):
  """A loss or a parameter became non-finite; the last good checkpoint is kept."""


def prepare_run_dir(run_dir: pathlib.Path, config: TrainConfig, resume: bool, force: bool) -> TrainConfig:
  """Check the run directory against what is asked, and return the config to run.

  A directory that holds a run is only continued (`resume`) or replaced (`force`), never
  silently overwritten; resuming keeps the run's config, except the fields that say how
  long and how often (config.RESUMABLE), which are taken from `config`.
  """
  run_dir = pathlib.Path(run_dir)
  holds_run = (run_dir / CONFIG_FILE).is_file()
  if resume:
    if not holds_run:
      raise ValueError(f"--resume: {run_dir} holds no run to continue")
    saved = config_lib.load(run_dir / CONFIG_FILE)
    differs = config_lib.mismatches(saved, config)
    if differs:
      raise ValueError(f"--resume: the run in {run_dir} does not match: {differs[0]}")
    return saved.replace(**{k: getattr(config, k) for k in config_lib.RESUMABLE}).validate()
  if holds_run and not force:
    raise ValueError(f"{run_dir} already holds a run; pass --resume to continue it or "
                     f"--force to replace it")
  if run_dir.exists() and not holds_run and any(run_dir.iterdir()) and not force:
    raise ValueError(f"{run_dir} is not empty and holds no run; choose another directory")
  config.validate()
  if force and run_dir.exists():
    shutil.rmtree(run_dir)
  run_dir.mkdir(parents=True, exist_ok=True)
  config_lib.save(config, run_dir / CONFIG_FILE)
  return config


def find_run_dir(path: pathlib.Path) -> pathlib.Path:
  """The run directory that is or holds `path` (a checkpoint folder in it)."""
  path = pathlib.Path(path)
  for run_dir in (path, *path.parents):
    if (run_dir / CONFIG_FILE).is_file():
      return run_dir
  raise ValueError(f"{path} is not a run directory or a checkpoint in one")


def load_run(path: pathlib.Path) -> tuple[TrainConfig, pathlib.Path]:
  """(config, checkpoint) of a run directory (its latest checkpoint) or a checkpoint folder."""
  path = pathlib.Path(path)
  run_dir = find_run_dir(path)
  config = config_lib.load(run_dir / CONFIG_FILE)
  checkpoint = checkpoints.latest(run_dir) if path == run_dir else path
  if checkpoint is None:
    raise ValueError(f"{run_dir} holds no checkpoint yet")
  return config, checkpoint


def restore(trainer: Trainer, checkpoint: pathlib.Path) -> TrainState:
  return checkpoints.restore(checkpoint, trainer.init(load_decoder=False))


def load_trained(path: pathlib.Path, make_trainer=Trainer, **changes) -> tuple[Trainer, TrainState]:
  """The trainer and the restored state of a run (its latest checkpoint) or of a checkpoint;
  `changes` replace config fields that do not change the state's layout (backend, eval_envs);
  `make_trainer(config)` builds the trainer (tests give tiny envs)."""
  config, checkpoint = load_run(pathlib.Path(path))
  trainer = make_trainer(config.replace(**changes).validate())
  return trainer, restore(trainer, checkpoint)


def evaluate(trainer: Trainer, state: TrainState) -> dict[str, dict[str, float]]:
  """Deterministic evaluation; its key depends on the step only, never on training's rng."""
  key = jax.random.fold_in(jax.random.PRNGKey(trainer.config.seed + 1), int(state.step))
  out = trainer.evaluate(state.params, state.normalizers, key)
  return jax.tree.map(float, jax.device_get(out))


def format_table(results: dict[str, dict[str, float]], step: int, config: TrainConfig) -> str:
  """The evaluation table that ends a run and that `discosyn eval` prints."""
  lines = [f"evaluation at step {step} ({step * config.env_steps_per_train_step:,} env steps, "
           f"{config.eval_envs} deterministic episodes per task)",
           f"{'task':16s} {'success':>8s} {'return':>9s}"]
  for name, r in results.items():
    lines.append(f"{name:16s} {r['success']:8.1%} {r['return']:9.2f}")
  return "\n".join(lines)


def train(config: TrainConfig, run_dir: pathlib.Path, *, resume: bool = False, force: bool = False,
          progress: bool = True, trainer: Trainer | None = None, log=print,
          devices=None) -> dict[str, Any]:
  """Run (or continue) a training run in `run_dir`; return the final evaluation.
  `devices`: the count to split the env batch over (default: all; see devices.py)."""
  run_dir = pathlib.Path(run_dir)
  config = prepare_run_dir(run_dir, config, resume, force)
  trainer = trainer or Trainer(config, devices=devices)
  checkpoint = checkpoints.latest(run_dir) if resume else None
  if checkpoint is not None:
    state = restore(trainer, checkpoint)
    log(f"resumed from {checkpoint} at step {int(state.step)}")
  else:
    state = trainer.init()
  start_step = int(state.step)

  start = time.perf_counter()
  train_step = trainer.train_step.lower(state).compile()
  compile_s = time.perf_counter() - start
  log(f"train step compiled in {compile_s:.1f} s; {config.env_steps_per_train_step:,} env steps "
      f"per train step ({len(config.tasks)} tasks x {config.num_envs} envs x "
      f"{config.unroll_length} steps)")

  bar = _progress(progress, start_step, config.steps)
  shown = {}  # training success per task, as of the last rollout in which episodes ended
  last_good = checkpoints.latest(run_dir)
  with open(run_dir / logs.METRICS_FILE, "a") as metrics_file, \
       open(run_dir / logs.EVAL_FILE, "a") as eval_file, logs.TensorBoard(run_dir) as board:
    tick = time.perf_counter()
    while int(state.step) < config.steps:
      state, metrics = train_step(state)
      metrics = {k: float(v) for k, v in jax.device_get(metrics).items()}
      for name in config.tasks:  # no episode ended in this rollout: no return or success to log
        if metrics.get(f"{name}/episodes") == 0:
          del metrics[f"{name}/return"], metrics[f"{name}/success"]
      step = int(state.step)
      now = time.perf_counter()
      metrics.update(step=step, env_steps=step * config.env_steps_per_train_step,
                     env_steps_per_s=config.env_steps_per_train_step / (now - tick),
                     wall_s=now - start)
      tick = now
      metrics_file.write(json.dumps(metrics) + "\n")
      metrics_file.flush()
      board.write(metrics, "train")
      if not metrics["finite"] or not math.isfinite(metrics["loss"]):
        where = f"the last good checkpoint is {last_good}" if last_good else "no checkpoint was written"
        raise TrainingDiverged(f"non-finite loss or parameters at step {step}; training stopped, "
                               f"{where}")
      if bar is not None:
        shown.update({n: metrics[f"{n}/success"] for n in config.tasks if f"{n}/success" in metrics})
        bar.set_postfix_str(" ".join(f"{n}:{v:.0%}" for n, v in list(shown.items())[:6]), refresh=False)
        bar.update(1)
      if config.eval_every and step % config.eval_every == 0 and step < config.steps:
        _log_eval((eval_file, board), evaluate(trainer, state), step, config, now - start)
      if config.checkpoint_every and step % config.checkpoint_every == 0:
        last_good = checkpoints.save(run_dir, state, config.keep_checkpoints)
    if bar is not None:
      bar.close()
    results = evaluate(trainer, state)
    _log_eval((eval_file, board), results, int(state.step), config, time.perf_counter() - start)
  checkpoints.save(run_dir, state, config.keep_checkpoints, final=True)
  curves = plots.run_curves(run_dir, run_dir / plots.PLOTS_DIR)
  log(f"training curves: {', '.join(str(p) for p in curves)}")
  log(format_table(results, int(state.step), config))
  return {"results": results, "state": state, "compile_s": compile_s}


def _log_eval(outputs, results, step, config, wall_s):
  file, board = outputs
  row = {"step": step, "env_steps": step * config.env_steps_per_train_step, "wall_s": wall_s}
  row.update({f"{n}/{k}": v for n, r in results.items() for k, v in r.items()})
  file.write(json.dumps(row) + "\n")
  file.flush()
  board.write(row, "eval")


def _progress(enabled: bool, start: int, total: int):
  """A tqdm bar on a terminal; elsewhere (a log file, a notebook's captured stderr) one
  line every tenth of the run, since a bar's carriage returns would flood the log."""
  if not enabled:
    return None
  if not sys.stderr.isatty():
    return _ProgressLines(start, total, every=max(1, total // 10))
  from tqdm import tqdm

  return tqdm(total=total, initial=start, unit="step", dynamic_ncols=True)


class _ProgressLines:
  """The part of tqdm's interface the loop uses, as plain lines on stderr."""

  def __init__(self, start: int, total: int, every: int):
    self.n, self.start, self.total, self.every, self.postfix = start, start, total, every, ""
    self.began = time.perf_counter()

  def update(self, n: int) -> None:
    self.n += n
    if self.n % self.every == 0 or self.n == self.total:
      rate = (self.n - self.start) / (time.perf_counter() - self.began)
      print(f"step {self.n}/{self.total}, {rate:.2f} steps/s {self.postfix}".rstrip(),
            file=sys.stderr, flush=True)

  def set_postfix_str(self, text: str, refresh: bool = True) -> None:
    del refresh  # a line is written by update() only
    self.postfix = text

  def close(self) -> None:
    pass

