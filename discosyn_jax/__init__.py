"""DiscoSyn-JAX: hand synergies discovered with multi-task RL, in JAX."""

import os as _os

# XLA's CPU runtime deadlocked on batched MJX steps with its concurrency-optimised
# scheduler (5 of 5 runs, DESIGN.md); the flag must be set before jax is imported.
_FLAG = "--xla_cpu_enable_concurrency_optimized_scheduler=false"
if _FLAG.split("=")[0] not in _os.environ.get("XLA_FLAGS", ""):
  _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "") + " " + _FLAG).strip()

__version__ = "0.1.0"
