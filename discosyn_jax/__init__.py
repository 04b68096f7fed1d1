"""DiscoSyn-JAX: hand synergies discovered with multi-task RL, in JAX."""

import os as _os
import sys as _sys

# XLA's CPU runtime deadlocked on batched MJX steps with its concurrency-optimised
# scheduler (5 of 5 runs, DESIGN.md); the flag must be set before jax is imported.
_FLAG = "--xla_cpu_enable_concurrency_optimized_scheduler=false"
if _FLAG.split("=")[0] not in _os.environ.get("XLA_FLAGS", ""):
  _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "") + " " + _FLAG).strip()

# Offscreen rendering (render.py) on a headless Linux machine: MuJoCo picks its OpenGL
# platform once, when it is imported, so the default (EGL) must be set before that.
if _sys.platform.startswith("linux") and not _os.environ.get("DISPLAY"):
  _os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"


def _import_mjx_quietly() -> None:
  """mujoco.mjx prints "Failed to import warp" on stdout wherever the optional Warp
  package is absent (the CPU path never needs it); keep that line out of our output."""
  import contextlib
  import io
  import sys

  captured = io.StringIO()
  with contextlib.redirect_stdout(captured):
    import mujoco.mjx  # noqa: F401
  for line in captured.getvalue().splitlines():
    if not line.startswith(("Failed to import warp", "Failed to import mujoco_warp")):
      print(line, file=sys.stdout)


_import_mjx_quietly()

from discosyn_jax import compile_cache as _compile_cache  # noqa: E402

_compile_cache.enable()
