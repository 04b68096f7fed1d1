"""MJX: MuJoCo in JAX, the accelerator path (MuJoCo Warp's implementation where asked for)."""

from __future__ import annotations

import importlib.util
import os

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx

from discosyn_jax.env.physics.view import PhysicsView

IMPLS = ("jax", "warp")


def default_impl() -> str:
  """`DISCOSYN_MJX_IMPL` (jax | warp) where set, else MJX's JAX implementation. Warp is
  asked for, never chosen by itself: its contact buffers are not yet sized for our scenes
  and the free dice leaves MJX's trajectory in its first control step."""
  chosen = os.environ.get("DISCOSYN_MJX_IMPL", "").strip()
  return check_impl(chosen) if chosen else "jax"


def check_impl(impl: str) -> str:
  if impl not in IMPLS:
    raise ValueError(f"unknown MJX implementation {impl!r}; known: {', '.join(IMPLS)}")
  if impl == "warp" and not importlib.util.find_spec("mujoco_warp"):
    raise ValueError('MJX implementation "warp" needs mujoco_warp: pip install ".[warp]"')
  return impl


class MjxBackend:
  name = "mjx"

  def __init__(self, model: mujoco.MjModel, n_substeps: int, impl: str | None = None):
    self.mj_model = model
    self.n_substeps = int(n_substeps)
    self.impl = check_impl(impl) if impl else default_impl()
    self.model = mjx.put_model(model, impl=self.impl)
    # Warp's make_data takes the MjModel (it sizes its buffers from it), JAX's either
    self._data0 = mjx.make_data(model if self.impl == "warp" else self.model, impl=self.impl)

  def init(self, qpos: jax.Array, qvel: jax.Array) -> mjx.Data:
    data = self._data0.replace(qpos=qpos.astype(jnp.float32), qvel=qvel.astype(jnp.float32))
    return mjx.forward(self.model, data)

  def step(self, data: mjx.Data, ctrl: jax.Array) -> mjx.Data:
    data = data.replace(ctrl=ctrl.astype(data.ctrl.dtype))
    return jax.lax.fori_loop(0, self.n_substeps, lambda _, d: mjx.step(self.model, d), data)

  def view(self, data: mjx.Data) -> PhysicsView:
    return PhysicsView(qpos=data.qpos, qvel=data.qvel, sensordata=data.sensordata)

  def to_mjdata(self, data: mjx.Data) -> mujoco.MjData:
    """One environment's state as an MjData (forward evaluated), e.g. for rendering."""
    out = mjx.get_data(self.mj_model, data)
    mujoco.mj_forward(self.mj_model, out)
    return out
