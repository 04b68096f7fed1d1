"""Checks of input that the configs, the CLI and the environment variables share: each
raises BadInput with one line that names the setting, before anything is built or written.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import typing

# jax.random.PRNGKey keeps 32 bits of a seed with x64 off (2**32 is seed 0 again), and the
# evaluation draws with seed + 1
MAX_SEED = 2**32 - 2
_PLURALS = {str: "strings", int: "whole numbers", float: "finite numbers", bool: "true/false values"}


class BadInput(ValueError):
  """What a user gave (a config field, a flag, a file, a task, a plan, a hand, an environment
  variable, a name) cannot be used: one line that says which and why. The command prints it
  alone, exit status 2; any other exception is a bug in discosyn. A ValueError, so that
  `except ValueError` catches it too."""


def shortened(text: str, limit: int = 40) -> str:
  """A value's text as a one-line message names it: at most `limit` characters."""
  return text if len(text) <= limit else text[:limit - 3] + "..."


def _kind_problem(kind, value) -> str | None:
  """What `value` should be to have the type `kind`, or None when it has it."""
  if kind is bool:
    return None if isinstance(value, bool) else "true or false"
  if kind is int:
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    return None if ok else "a whole number"
  if kind is float:
    ok = (isinstance(value, numbers.Real) and not isinstance(value, bool)
          and math.isfinite(value))
    return None if ok else "a finite number"
  if kind is str:
    return None if isinstance(value, str) else "text"
  if typing.get_origin(kind) is tuple:
    args = typing.get_args(kind)
    if len(args) == 2 and args[1] is Ellipsis:
      wrong = not isinstance(value, tuple) or any(_kind_problem(args[0], v) for v in value)
      return f"a list of {_PLURALS.get(args[0], 'values')}" if wrong else None
  return None  # a type these checks do not know


def fields(obj) -> None:
  """Raise BadInput naming the first field of the dataclass `obj` whose value does not
  have its declared type (numbers finite, whole numbers whole, flags true or false)."""
  hints = typing.get_type_hints(type(obj))
  for field in dataclasses.fields(obj):
    value = getattr(obj, field.name)
    problem = _kind_problem(hints.get(field.name), value)
    if problem:
      raise BadInput(f"{field.name} must be {problem}, not {value!r}")


def seed(value: int, name: str = "seed") -> int:
  if not isinstance(value, numbers.Integral) or not 0 <= value <= MAX_SEED:
    raise BadInput(f"{name} must be a whole number between 0 and {MAX_SEED}, not {value!r}")
  return int(value)


def env_int(name: str, default: int, minimum: int = 1) -> int:
  """The whole number in environment variable `name` (`default` when unset or empty)."""
  text = os.environ.get(name, "").strip()
  if not text:
    return default
  try:
    value = int(text)
  except ValueError:
    value = None
  if value is None or value < minimum:
    raise BadInput(f"environment variable {name} must be a whole number of at least {minimum}, "
                   f"not {text!r}")
  return value


def _state_bytes(env) -> int:
  import jax

  state = jax.eval_shape(env.reset, jax.random.PRNGKey(0))
  return sum(leaf.size * leaf.dtype.itemsize for leaf in jax.tree.leaves(state))


def memory_needed(config, envs) -> int:
  """A lower bound of the bytes a training run holds at once: every env's state, the
  rollout's per-step arrays (observation, z, action and a dozen scalars, float32) and the
  evaluation's env states; on the native backend MuJoCo's own buffer for each simulation."""
  total = 0
  for env in envs:
    per_env = _state_bytes(env)
    if env.backend == "native":
      per_env += env.mj_model.nbuffer
    per_step = 4 * (env.observation_size + config.n_synergies + env.action_size + 12)
    total += config.num_envs * (per_env + config.unroll_length * per_step)
    total += config.eval_envs * per_env
  return total


def memory_available() -> int:
  """Bytes of the accelerators' memory, or of the host's on a CPU."""
  import jax

  stats = jax.devices()[0].memory_stats() or {}
  if "bytes_limit" in stats:
    return stats["bytes_limit"] * jax.device_count()
  return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def memory(config, envs) -> None:
  """Refuse a config whose envs cannot fit in memory, before it fails deep in an allocation."""
  needed, have = memory_needed(config, envs), memory_available()
  if needed > have:
    raise BadInput(f"{len(envs)} task(s) x {config.num_envs} envs (and {config.eval_envs} "
                   f"evaluation episodes) need at least {needed / 2**30:,.1f} GiB, more than the "
                   f"{have / 2**30:,.1f} GiB here; lower num_envs or eval_envs")


_JAX_ENVIRONMENT_CHECKED: set[tuple[str, str]] = set()


def jax_environment(own_xla_flags: str) -> None:
  """Refuse in one line a JAX_PLATFORMS that names no backend and an XLA_FLAGS holding a flag
  XLA does not know. XLA ends the process on such a flag the moment JAX first starts a backend
  (its own fatal line, exit 1), so the user's flags (XLA_FLAGS less `own_xla_flags`, the
  package's) are tried first in a child process (~1 s, once per process and value; none when
  the user set none, or when this process's backends already started)."""
  from jax._src import xla_bridge

  platforms, flags = os.environ.get("JAX_PLATFORMS", ""), os.environ.get("XLA_FLAGS", "")
  if (platforms, flags) in _JAX_ENVIRONMENT_CHECKED or xla_bridge.backends_are_initialized():
    return
  if flags.replace(own_xla_flags, "").strip():
    import subprocess
    import sys

    probe = subprocess.run([sys.executable, "-c", "import jax; jax.devices('cpu')"],
                           env={**os.environ, "JAX_PLATFORMS": "cpu"}, capture_output=True,
                           text=True)
    unknown = [line.split("XLA_FLAGS:", 1)[1].strip() for line in probe.stderr.splitlines()
               if "Unknown flag" in line and "XLA_FLAGS:" in line]
    if probe.returncode and unknown:
      raise BadInput(f"environment variable XLA_FLAGS holds a flag XLA does not know: "
                     f"{unknown[0]}")
  if platforms.strip():
    import jax

    try:
      jax.devices()
    except RuntimeError as err:
      reason = str(err).splitlines()[0].split(" (set JAX_PLATFORMS")[0]
      raise BadInput(f"environment variable JAX_PLATFORMS={platforms!r}: {reason}") from None
  _JAX_ENVIRONMENT_CHECKED.add((platforms, flags))
