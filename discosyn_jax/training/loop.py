"""The host loop: train steps, logs, evaluations and checkpoints, and nothing else.

Everything numerical happens inside the jitted `Trainer.train_step`; between steps this
loop writes one JSON line of metrics (and TensorBoard scalars, logs.py), evaluates the
deterministic policy every `eval_every` steps, checkpoints every `checkpoint_every` steps and
at the end, where it also runs the closing evaluation (`closing_episodes` a task,
closing.json) and calls its `on_end` hook (the assembler draws the curves there). It is given
its Trainer (discosyn_jax/assemble.py builds one from a config); the decoder a run
starts from is synergies/start.py's, the progress output run/progress.py's.
"""

from __future__ import annotations

import json
import math
import pathlib
import shlex
import time
from typing import Any, Callable

import jax

from discosyn_jax import atomic, checks
from discosyn_jax import config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.env.task import label, not_finite
from discosyn_jax.run import checkpoints, layout, logs, owner, progress as progress_lib, reading, stop
from discosyn_jax.synergies import priors, start as start_lib
from discosyn_jax.training import evaluation
from discosyn_jax.training.trainer import Trainer, TrainState


class TrainingDiverged(RuntimeError):
  """A loss or a parameter became non-finite; the last good checkpoint is kept."""


class TaskNotFinite(TrainingDiverged):
  """A task's own values (a reward term, its success, its observation) became non-finite:
  a bug in the task, named where it starts; the last good checkpoint is kept."""


class WriteFailed(ValueError):
  """The run could not be written (a full disk, a folder made read-only); its last good
  checkpoint is kept, and the message says where it is."""


def restore(trainer: Trainer, checkpoint: pathlib.Path) -> TrainState:
  # the template needs no decoder source: the checkpoint holds the decoder
  return checkpoints.restore(checkpoint, trainer.init())


def resume_latest(trainer: Trainer, run_dir: pathlib.Path,
                  warn=checkpoints.warn) -> tuple[pathlib.Path | None, TrainState | None]:
  """(checkpoint, state) of the newest checkpoint of a run that restores, (None, None) when
  none does. Each damaged one on the way is named in one line and removed: the run goes
  on from an older one and writes it anew."""
  def damaged(checkpoint, err):
    checkpoints.remove(checkpoint)
    warn(f"{err}; removed it")

  return checkpoints.read_newest(run_dir, lambda path: restore(trainer, path), damaged)


def train(trainer: Trainer, run_dir: pathlib.Path, *, resume: bool = False, force: bool = False,
          progress: bool = True, log=print, stop_at: float | None = None,
          on_eval: Callable[[int, dict], None] | None = None,
          on_end: Callable[[], None] | None = None) -> dict[str, Any]:
  """Run (or continue) `trainer`'s config in `run_dir`; return the final evaluation
  ("results"), the closing one, state, trainer and compile time.
  `stop_at`: end the run (final checkpoint and all) at the first evaluation at which every
  task's deterministic success is at least this. `on_eval(step, row)`: called after each
  evaluation with its row of eval.jsonl (env_steps, wall_s, "<task>/success", ...).
  `on_end()`: called once the run has its final checkpoint and closing evaluation.

  Everything that can refuse the run (the config, the folder, the envs, the memory they
  need) is checked before the run directory is made; the run directory is then this
  process's alone to its end (owner.Writer). The trainer's config must be the one the
  folder runs (reading.run_config: a resumed run's own). Continuing a run restores its
  newest good checkpoint and cuts its logs back to that step. A new run that ends before its
  first checkpoint leaves no trace (a run it replaces is back). A write that fails mid-run
  (a full disk) stops it with WriteFailed, Ctrl-C with KeyboardInterrupt and SIGTERM with
  stop.Terminated (a KeyboardInterrupt), each naming the last good checkpoint, whoever
  calls this (run/stop.py: handled).
  """
  run_dir = pathlib.Path(run_dir)
  owner.refuse_if_written(run_dir)
  config = trainer.config
  _same_config(reading.run_config(run_dir, config, resume, force), config, run_dir)
  checks.memory(config, trainer.envs)
  if config.decoder_init in config_lib.PRIORS:
    priors.check(trainer.envs)
  # Ctrl-C and SIGTERM stop it cleanly, from a script or a notebook as from the command
  with stop.handled(), owner.Writer(run_dir) as writer:
    # again, now that it is ours: another process may have made or replaced a run there
    _same_config(reading.run_config(run_dir, config, resume, force), config, run_dir)
    if not resume:
      writer.begin(lambda: config_lib.save(config, run_dir / layout.CONFIG_FILE), replace=force)
    at = {"step": 0, "checkpoint": None}  # where the run is: what a failure names
    try:
      return _run(trainer, run_dir, resume, writer, at, progress, log, stop_at, on_eval, on_end)
    except BaseException as err:
      undone = writer.new and not writer.kept
      replaced = writer.undo() if undone else False
      where = _where(at["checkpoint"], undone, replaced)
      stopped = stop.taken(err)  # Ctrl-C or SIGTERM, also one that aborted a physics callback
      if stopped is not None:  # the same class: the CLI tells Ctrl-C from SIGTERM
        newest = None if undone else checkpoints.latest(run_dir, warn=lambda _: None)
        if newest:  # (a save the signal cut short may have made a newer one than at's)
          where = (f"it resumes from {newest}: discosyn train --out "
                   f"{shlex.quote(str(run_dir))} --resume")
        raise type(stopped)(f"training stopped at step {at['step']}; {where}") from None
      if isinstance(err, OSError):  # a full disk, a folder made read-only, a checkpoint not written
        what = str(err) if isinstance(err, checkpoints.SaveFailed) else \
            f"could not write {err.filename or run_dir}: {err.strerror or err}"
        raise WriteFailed(f"training stopped at step {at['step']}: {what}; {where}") from None
      if isinstance(err, TrainingDiverged):
        raise type(err)(f"{err}; {where}") from None
      raise


def _count(n: int, noun: str) -> str:
  return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _same_config(wanted: TrainConfig, given: TrainConfig, run_dir: pathlib.Path) -> None:
  """The trainer must run the config the folder calls for (a resumed run's own)."""
  if wanted != given:
    raise BadInput(f"{run_dir}: the trainer's config is not the run's "
                   f"({'; '.join(config_lib.mismatches(wanted, given)) or 'steps or logging differ'})")


def _run(trainer: Trainer, run_dir: pathlib.Path, resume: bool, writer: owner.Writer,
         at: dict, progress: bool, log, stop_at: float | None, on_eval, on_end) -> dict[str, Any]:
  """The run itself, in a folder that is ours; `at` follows its step and last good
  checkpoint."""
  config = trainer.config
  at["checkpoint"], state = _start(trainer, run_dir, resume, log)
  at["step"] = int(state.step)
  start = time.perf_counter()
  train_step = trainer.train_step.lower(state).compile()
  compile_s = time.perf_counter() - start
  log(f"train step compiled in {compile_s:.1f} s; {config.env_steps_per_train_step:,} env steps "
      f"per train step ({_count(len(config.tasks), 'task')} x {_count(config.num_envs, 'env')} x "
      f"{_count(config.unroll_length, 'step')})")

  def save(final: bool = False) -> None:
    at["checkpoint"] = checkpoints.save(run_dir, state, config.keep_checkpoints, final=final)
    writer.keep()

  start_step = int(state.step)
  reference = start_lib.decoder_reference(trainer, state, log)
  bar = progress_lib.bar(progress, start_step, config.steps)
  shown = {}  # training success per task, as of the last rollout in which episodes ended
  step = start_step
  results, evaluated_at = None, None  # the newest evaluation, and its step
  try:
    history = _cut_logs(run_dir, start_step) if resume else None
    # a resumed run's wall clock goes on from where its kept logs end, not from 0
    start -= history[0][-1].get("wall_s", 0.0) if history and history[0] else 0.0
    with open(run_dir / layout.METRICS_FILE, "a") as metrics_file, \
         open(run_dir / layout.EVAL_FILE, "a") as eval_file, logs.TensorBoard(run_dir, history) as board:
      if resume and _evaluates_at(config, step):  # the evaluation the cut removed, redone
        _log_eval((eval_file, board, on_eval), evaluation.evaluate(trainer, state), step, config,
                  time.perf_counter() - start)
      tick = time.perf_counter()
      while int(state.step) < config.steps:
        stop.check()  # a Ctrl-C or SIGTERM that Python dropped where it landed (a finalizer)
        state, metrics = train_step(state)
        if reference is not None:
          metrics.update(trainer.decoder_drift(reference, state.params))
        metrics = jax.device_get(metrics)
        own_values = metrics.pop("finite_values")  # checked below, not logged
        metrics = {k: float(v) for k, v in metrics.items()}
        for name in config.tasks:  # no episode ended in this rollout: no return or success to log
          if metrics.get(f"{name}/episodes") == 0:
            del metrics[f"{name}/return"], metrics[f"{name}/success"]
        step = at["step"] = int(state.step)
        now = time.perf_counter()
        metrics.update(step=step, env_steps=step * config.env_steps_per_train_step,
                       env_steps_per_s=config.env_steps_per_train_step / (now - tick),
                       wall_s=now - start)
        tick = now
        metrics_file.write(json.dumps(metrics) + "\n")
        metrics_file.flush()
        board.write(metrics, "train")
        _check_finite(own_values, metrics, step)
        if bar is not None:
          shown.update({n: metrics[f"{n}/success"] for n in config.tasks if f"{n}/success" in metrics})
          bar.set_postfix_str(" ".join(f"{label(n)}:{v:.0%}" for n, v in list(shown.items())[:6]),
                              refresh=False)
          bar.update(1)
        if _evaluates_at(config, step):
          results, evaluated_at = evaluation.evaluate(trainer, state), step
          _log_eval((eval_file, board, on_eval), results, step, config, now - start)
          if stop_at is not None and all(r["success"] >= stop_at for r in results.values()):
            log(f"every task at >= {stop_at:.0%} deterministic success at step {step}: "
                "the run ends here")
            break
        if config.checkpoint_every and step % config.checkpoint_every == 0:
          save()
      if bar is not None:
        bar.close()
        bar = None
      if evaluated_at != step:
        results = evaluation.evaluate(trainer, state)
        _log_eval((eval_file, board, on_eval), results, step, config, time.perf_counter() - start)
    save(final=True)
    closing = write_closing(trainer, state, run_dir)
    if on_end is not None:
      on_end()
  finally:
    if bar is not None:
      bar.close()
  log(evaluation.format_table(results, step, config))
  if closing is not None:
    log(evaluation.format_table(closing, step, config, config.closing_episodes, "closing "))
  return {"results": results, "closing": closing, "state": state, "compile_s": compile_s,
          "trainer": trainer}


def write_closing(trainer: Trainer, state: TrainState, run_dir: pathlib.Path):
  """The closing evaluation of a run's final state, written to closing.json (a run continued
  past its end writes it anew); None where the config asks for none."""
  config = trainer.config
  if not config.closing_episodes:
    return None
  results = evaluation.evaluate(trainer, state, closing=True)
  step = int(state.step)
  row = {"step": step, "env_steps": step * config.env_steps_per_train_step,
         "episodes": config.closing_episodes}
  row.update({f"{n}/{k}": v for n, r in results.items() for k, v in r.items()})
  atomic.write_text(run_dir / layout.CLOSING_FILE, json.dumps(row, indent=1) + "\n")
  return results


def _start(trainer: Trainer, run_dir: pathlib.Path, resume: bool, log):
  """(checkpoint, state) to start from: the newest checkpoint that restores when
  resuming (damaged ones on the way removed), else (None, a fresh state)."""
  if resume:
    checkpoints.tidy(run_dir)
    checkpoint, state = resume_latest(trainer, run_dir)
    if state is not None:
      log(f"resumed from {checkpoint} at step {int(state.step)}")
      return checkpoint, state
    log(f"{run_dir} holds no good checkpoint: starting from step 0")
  start = time.perf_counter()
  decoder = start_lib.starting_decoder(trainer)
  own = start_lib.starting_own(trainer, decoder)
  parts = []
  if trainer.config.decoder_init in config_lib.PRIORS:
    parts.append(f"the decoder starts in the {trainer.config.decoder_init} prior's subspace")
  if own is not None:
    parts.append(f"each task's {trainer.config.own_synergies} own synergies in its reward "
                 "prior's directions outside the shared start")
  if parts:
    log(f"{'; '.join(parts)} (made in {time.perf_counter() - start:.0f} s)")
  return None, trainer.init(decoder_params=decoder, own=own)


def _check_finite(own_values: dict, metrics: dict, step: int) -> None:
  """Stop a run whose numbers went non-finite in train step `step`: TaskNotFinite naming
  a task's values that did (trainer._finite_values), else TrainingDiverged."""
  for name, values in own_values.items():
    bad = [part for part, finite in values.items() if not finite]
    if bad:
      raise TaskNotFinite(not_finite(label(name), bad, f"at train step {step}") +
                          "; training stopped")
  if not metrics["finite"] or not math.isfinite(metrics["loss"]):
    raise TrainingDiverged(f"non-finite loss or parameters at step {step}; training stopped")


def _evaluates_at(config: TrainConfig, step: int) -> bool:
  """Whether the loop evaluates after train step `step` (the end of the run aside)."""
  return bool(config.eval_every) and step % config.eval_every == 0 and 0 < step < config.steps


def _cut_logs(run_dir: pathlib.Path, step: int) -> tuple[list[dict], list[dict]]:
  """The logs of a resumed run cut back to its restored step: what an unbroken run held
  then, but for the evaluation at that step, which may have been the end of a shorter run
  (the loop redoes it where an unbroken run would have made it)."""
  return (logs.cut(run_dir / layout.METRICS_FILE, step),
          logs.cut(run_dir / layout.EVAL_FILE, step - 1))


def _where(checkpoint: pathlib.Path | None, undone: bool, replaced: bool) -> str:
  """What a run that stopped left: its last good checkpoint, or nothing."""
  if checkpoint and not undone:
    return f"the last good checkpoint is {checkpoint}"
  if undone:  # a new run without a checkpoint was removed
    return ("the new run made no checkpoint and was removed; the run it was to replace is "
            "back as it was" if replaced else "the new run made no checkpoint and was removed")
  return "no checkpoint was written"


def _log_eval(outputs, results, step, config, wall_s):
  file, board, callback = outputs
  row = {"step": step, "env_steps": step * config.env_steps_per_train_step, "wall_s": wall_s}
  row.update({f"{n}/{k}": v for n, r in results.items() for k, v in r.items()})
  file.write(json.dumps(row) + "\n")
  file.flush()
  board.write(row, "eval")
  if callback is not None:
    callback(step, dict(row))
