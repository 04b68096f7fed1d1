"""JAX's persistent compilation cache, on by default.

A compiled executable is kept on disk and reused by the next process that compiles the
same function for the same devices, so a second run (or a resumed one) skips XLA.
The folder is `DISCOSYN_JAX_CACHE` (default ~/.cache/discosyn/jax); "off" disables it.

JAX never writes an executable that holds host callbacks to the cache: the native
backend's train step (MuJoCo C through `jax.pure_callback`) is compiled anew in every
process; the MJX path (pure JAX) and the callback-free functions are cached.
"""

from __future__ import annotations

import os
import pathlib

ENV_VAR = "DISCOSYN_JAX_CACHE"
DEFAULT = pathlib.Path("~/.cache/discosyn/jax")


def folder() -> pathlib.Path | None:
  """The cache folder `DISCOSYN_JAX_CACHE` names, or the default; None when it says off."""
  value = os.environ.get(ENV_VAR, "").strip()
  if value.lower() in ("off", "0", "none", "false"):
    return None
  return pathlib.Path(value or DEFAULT).expanduser()


def enable(path: str | os.PathLike | None = None) -> pathlib.Path | None:
  """Point JAX's persistent cache at `path` (default: `folder()`); return the folder used."""
  import jax

  path = pathlib.Path(path).expanduser() if path is not None else folder()
  if path is None:
    return None
  try:
    path.mkdir(parents=True, exist_ok=True)
  except OSError:  # a read-only home: run uncached rather than fail
    return None
  jax.config.update("jax_compilation_cache_dir", str(path))
  # cache everything that took a second or more to compile, however small its binary
  jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
  jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
  return path
