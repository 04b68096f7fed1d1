"""The tasks: one module per task, the registry that builds their environments
(registry.py) and the task sets (sets.py). The run on them is assembled above, in
discosyn_jax/assemble.py.

`import tasks` is light: it holds TASK_SETS. Anything else (`tasks.make`, `tasks.REGISTRY`,
...) loads the registry, and with it JAX and MuJoCo, on first use.
"""

import importlib

from discosyn_jax.tasks.sets import TASK_SETS

__all__ = ["TASK_SETS"]  # and, loaded on first use, the registry's names


def __getattr__(name: str):
  registry = importlib.import_module("discosyn_jax.tasks.registry")  # (not `from discosyn_jax.tasks import`: it asks here)
  try:
    return getattr(registry, name)
  except AttributeError:
    raise AttributeError(f"module 'tasks' has no attribute {name!r}") from None
