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


_jax_ready = False


def setup_jax() -> None:
  """Once per process, before this package's JAX work: MuJoCo's MJX imported without the
  "Failed to import warp" lines it prints on stdout wherever the optional Warp package is
  absent (the CPU path never needs it), and the persistent compile cache turned on
  (compile_cache.py). `import tasks` and the CLI call it; the package's own import does
  not, so that `discosyn --help` answers without importing JAX."""
  global _jax_ready
  if _jax_ready:
    return
  import contextlib
  import io

  captured = io.StringIO()
  with contextlib.redirect_stdout(captured):
    import mujoco.mjx  # noqa: F401
  for line in captured.getvalue().splitlines():
    if not line.startswith(("Failed to import warp", "Failed to import mujoco_warp")):
      print(line, file=_sys.stdout)

  from discosyn_jax.run import compile_cache

  compile_cache.enable()
  _jax_ready = True
