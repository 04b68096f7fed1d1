"""The functions of the public API that join the parts: train a config into a run folder,
evaluate a run, read a finished run. `discosyn_jax/__init__.py` exports them with the rest;
the command line is built on the same parts."""

from __future__ import annotations

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
  from discosyn_jax import assemble

  name = config if isinstance(config, str) else "run"
  if isinstance(config, str):
    config = presets.preset(config)
  config = config.validate()
  run_dir = pathlib.Path(run_dir if run_dir is not None else f"runs/{name}-seed{config.seed}")
  on_eval = None if progress_fn is None else (lambda _, row: progress_fn(row["env_steps"], row))
  done = assemble.train(config, run_dir, resume=resume, force=force, progress=progress, log=log,
                        stop_at=stop_at, on_eval=on_eval)
  return {**done, "run_dir": run_dir}


def make_env(name: str, **kwargs):
  """The Brax env of task `name` (tasks.registry.make: backend, physics, hand, task settings
  as keywords), its `success` metric summed over an episode the success at the episode's
  last step (env/wrappers.py: EpisodeSuccess): Brax's `eval/episode_success` is then the
  share of episodes that end in success, 0-1. The state's own success: `info["success"]`."""
  from discosyn_jax.env import wrappers
  from discosyn_jax.tasks import registry

  return wrappers.EpisodeSuccess(registry.make(name, **kwargs))


def evaluate(run: str | pathlib.Path, *, episodes: int | None = None,
             backend: str | None = None) -> dict[str, dict[str, float]]:
  """The deterministic policy of a run (its newest good checkpoint) or of one checkpoint:
  {task: {"success", "return"}} over `episodes` per task (default: the run's eval_envs)."""
  from discosyn_jax import assemble
  from discosyn_jax.training import evaluation

  changes = {"backend": backend} if backend else {}
  if episodes is not None:
    changes["eval_envs"] = episodes
  trainer, state = assemble.load(pathlib.Path(run), **changes)
  return evaluation.evaluate(trainer, state)


def read_run(path: str | pathlib.Path):
  """A run folder, or a run's record kept without checkpoints (docs/results/...), as a Run
  (discosyn_jax/run/folder.py: config, evaluations, metrics, closing, labels, finished;
  success, at_end(k), mean_success, curve, action_shares)."""
  from discosyn_jax.run import folder

  return folder.read(path)
