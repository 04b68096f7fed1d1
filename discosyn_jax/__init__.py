"""DiscoSyn-JAX: hand synergies discovered with multi-task RL, in JAX.

    import discosyn_jax as ds

    config = ds.preset("quickstart").replace(seed=1)        # or ds.TrainConfig(...)
    done = ds.train(config, "runs/mine", progress_fn=lambda steps, row: print(steps, row))
    ds.evaluate("runs/mine")                  # {task: {"success": ..., "return": ...}}
    ds.read_run("runs/mine").success          # each task's success at the last evaluation
    env = ds.make_env("valve3")               # a Brax Env: reset / step, actions in [-1, 1]
    ds.load_task("my_task.py:Slider")         # a task of one's own (docs/YOUR_TASK.md)
    ds.shipped_synergies()                    # the synergy files that ship, by name
    syn = ds.Synergies.load("shadow20-set1")  # .decode(z), .matrix, .actuators, .learned_on
    ds.synergy_env(env, syn)                  # env's action: the b synergies (any JAX RL library)

The config: TrainConfig (its defaults are the recommended setup: a linear decoder of 3
synergies started in the reward prior, z bounded, on task set #1), preset, PRESETS;
a decoder kind of one's own: DecoderKind, register_decoder (discosyn_jax/decoders.py).
Tasks: Task, TaskConfig, TASK_SETS, task_names, make_env, register_task, load_task.
Runs: train, evaluate, read_run, Run. Synergies: Synergies, shipped_synergies, synergy_env
(docs/TAKE_HOME.md). BadInput: the ValueError that every check of what a user gave raises
(one line: which input and why); any other exception is a bug. setup_jax: MJX imported
quietly, the compile cache on, and what Brax's own trainers still call of JAX given back
where JAX removed it.
Every name loads on first use, so that `import discosyn_jax` itself imports no JAX.
"""

import os as _os
import sys as _sys

# XLA's CPU runtime deadlocked on batched MJX steps with its concurrency-optimised
# scheduler (5 of 5 runs); the flag must be set before jax is imported.
XLA_FLAG = "--xla_cpu_enable_concurrency_optimized_scheduler=false"
if XLA_FLAG.split("=")[0] not in _os.environ.get("XLA_FLAGS", ""):
  _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "") + " " + XLA_FLAG).strip()

# Offscreen rendering (render.py) on a headless Linux machine: MuJoCo picks its OpenGL
# platform once, when it is imported, so the default (EGL) must be set before that.
if _sys.platform.startswith("linux") and not _os.environ.get("DISPLAY"):
  _os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

# MJX's "Failed to import warp" lines kept back wherever MJX is imported from now on, by
# Brax in a user's script too (no JAX imported here)
from discosyn_jax import quiet_mjx as _quiet_mjx  # noqa: E402,F401


def setup_jax() -> None:
  """MJX imported quietly, the persistent compile cache on, and `jax.device_put_replicated`
  given back where JAX removed it, for Brax's own trainers (run/jax_setup.py)."""
  from discosyn_jax.run import jax_setup

  jax_setup.setup_jax()


# name -> (module, attribute): loaded on first use (PEP 562), so that the command line's
# --help and the presets answer without importing JAX
_API = {
    "TrainConfig": ("discosyn_jax.config", "TrainConfig"),
    "preset": ("discosyn_jax.experiments.presets", "preset"),
    "PRESETS": ("discosyn_jax.experiments.presets", "PRESETS"),
    "DecoderKind": ("discosyn_jax.decoders", "DecoderKind"),
    "register_decoder": ("discosyn_jax.decoders", "register"),
    "Task": ("discosyn_jax.env.task", "Task"),
    "TaskConfig": ("discosyn_jax.env.task", "TaskConfig"),
    "TASK_SETS": ("discosyn_jax.tasks.sets", "TASK_SETS"),
    "task_names": ("discosyn_jax.tasks.registry", "names"),
    "make_env": ("discosyn_jax.api", "make_env"),
    "register_task": ("discosyn_jax.tasks.registry", "register"),
    "load_task": ("discosyn_jax.tasks.registry", "load"),
    "train": ("discosyn_jax.api", "train"),
    "evaluate": ("discosyn_jax.api", "evaluate"),
    "read_run": ("discosyn_jax.api", "read_run"),
    "Run": ("discosyn_jax.run.folder", "Run"),
    "Synergies": ("discosyn_jax.synergies.artefact", "Synergies"),
    # not ds.synergies: that is the subpackage discosyn_jax.synergies once it is imported
    "shipped_synergies": ("discosyn_jax.synergies.artefact", "shipped"),
    "synergy_env": ("discosyn_jax.synergies.action_space", "synergy_env"),
    "BadInput": ("discosyn_jax.checks", "BadInput"),
}
__all__ = [*_API, "setup_jax"]


def __getattr__(name: str):
  if name not in _API:
    raise AttributeError(f"module 'discosyn_jax' has no attribute {name!r}")
  import importlib

  module, attribute = _API[name]
  value = getattr(importlib.import_module(module), attribute)
  globals()[name] = value  # once
  return value


def __dir__():
  return sorted(set(globals()) | set(__all__))
