"""Once per process, before this package's JAX work: MJX imported quietly (quiet_mjx.py), the
persistent compile cache turned on (compile_cache.py), and what Brax's own trainers still call
of JAX where JAX has removed it (quiet_mjx.brax_compatible: also done as Brax is imported,
whenever that is). The assembler of a run and the command line call it; `ds.make_env` and
`import discosyn_jax` do not (an env changes nothing global; `discosyn --help` answers
without JAX)."""

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
  quiet_mjx.brax_compatible()
  _ready = True
