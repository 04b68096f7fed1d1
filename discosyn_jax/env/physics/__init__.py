"""Two physics backends behind one small interface.

Tasks never see a backend's own structures: they read a `PhysicsView` (qpos, qvel and
the sensors named in the MJCF) and compute observations and rewards from it in JAX.

A backend holds one compiled model and offers, for a single environment (vmap batches
them; the native backend's callback receives the whole batch at once):
  init(qpos, qvel) -> physics state   (forward dynamics evaluated at that state)
  step(state, ctrl) -> physics state  (`n_substeps` MuJoCo steps with ctrl held)
  view(state) -> PhysicsView
Sensor readings follow `mj_step`'s convention in both backends: they are computed at the
start of the last substep (one physics timestep before the returned qpos).
"""

from __future__ import annotations

import jax
import mujoco

from discosyn_jax.checks import BadInput
from discosyn_jax.env.settings import BACKENDS as _CHOICES
from discosyn_jax.env.physics.view import PhysicsView

__all__ = ["BACKENDS", "PhysicsView", "make_backend", "resolve"]
BACKENDS = _CHOICES[1:]  # "auto" resolves to one of them


def resolve(backend: str) -> str:
  """Map "auto" to `native` on CPU and `mjx` on accelerators; check the name."""
  if backend == "auto":
    return "native" if jax.default_backend() == "cpu" else "mjx"
  if backend not in BACKENDS:
    raise BadInput(f"unknown physics backend {backend!r}; known: auto, {', '.join(BACKENDS)}")
  return backend


def make_backend(backend: str, model: mujoco.MjModel, n_substeps: int, **kwargs):
  backend = resolve(backend)
  if backend == "native":
    from discosyn_jax.env.physics.native import NativeBackend

    return NativeBackend(model, n_substeps, **kwargs)
  from discosyn_jax.env.physics import mjx_backend

  return mjx_backend.make(model, n_substeps, **kwargs)
