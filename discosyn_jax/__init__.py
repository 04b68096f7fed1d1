"""DiscoSyn-JAX: hand synergies discovered with multi-task RL, in JAX."""

import os as _os
import sys as _sys

# XLA's CPU runtime deadlocked on batched MJX steps with its concurrency-optimised
# scheduler (5 of 5 runs, DESIGN.md); the flag must be set before jax is imported.
XLA_FLAG = "--xla_cpu_enable_concurrency_optimized_scheduler=false"
if XLA_FLAG.split("=")[0] not in _os.environ.get("XLA_FLAGS", ""):
  _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "") + " " + XLA_FLAG).strip()

# Offscreen rendering (render.py) on a headless Linux machine: MuJoCo picks its OpenGL
# platform once, when it is imported, so the default (EGL) must be set before that.
if _sys.platform.startswith("linux") and not _os.environ.get("DISPLAY"):
  _os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"




def setup_jax() -> None:
  """MJX imported quietly and the persistent compile cache on (run/jax_setup.py)."""
  from discosyn_jax.run import jax_setup

  jax_setup.setup_jax()
