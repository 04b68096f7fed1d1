"""Once per process, before this package's JAX work: MJX imported quietly (quiet_mjx.py), the
persistent compile cache turned on (compile_cache.py), and what Brax's own trainers still call
of JAX where JAX has removed it (brax_compatible). The task registry and the command line call
it (so `ds.make_env` has); `import discosyn_jax` does not, so that `discosyn --help` answers
without JAX."""

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
  brax_compatible()
  _ready = True


def brax_compatible() -> None:
  """Give JAX back `jax.device_put_replicated`, removed in JAX 0.10 and still called by Brax
  0.14.2's PPO and SAC (`brax.training.agents.*.train`), where this JAX lacks it: a leading
  axis of one copy per device, which their pmap splits. A JAX that still has it keeps its own."""
  import jax
  import jax.numpy as jnp

  if not hasattr(jax, "device_put_replicated"):
    jax.device_put_replicated = lambda tree, devices: jax.tree.map(
        lambda x: jnp.stack([jnp.asarray(x)] * len(devices)), tree)
