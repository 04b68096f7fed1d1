"""Once per process, before this package's JAX work: MJX imported quietly (quiet_mjx.py) and
the persistent compile cache turned on (compile_cache.py). The task registry and the command
line call it; `import discosyn_jax` does not, so that `discosyn --help` answers without JAX."""

from __future__ import annotations

from discosyn_jax import quiet_mjx

_ready = False


def setup_jax() -> None:
  global _ready
  if _ready:
    return
  quiet_mjx.import_mjx()
  from discosyn_jax.run import compile_cache

  compile_cache.enable()
  _ready = True
