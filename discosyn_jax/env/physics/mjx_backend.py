"""MJX: MuJoCo in JAX, the accelerator path (MuJoCo Warp's implementation where asked for:
mjx_warp.py)."""

from __future__ import annotations

import importlib.util
import os

import jax
import jax.numpy as jnp
import mujoco
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from mujoco import mjx

from discosyn_jax.checks import BadInput
from discosyn_jax.env.physics.view import PhysicsView

IMPLS = ("jax", "warp")


def default_impl() -> str:
  """`DISCOSYN_MJX_IMPL` (jax | warp) where set, else MJX's JAX implementation. Warp is
  asked for, never chosen by itself: on a GPU it is not yet measured against JAX's."""
  chosen = os.environ.get("DISCOSYN_MJX_IMPL", "").strip()
  return check_impl(chosen, "environment variable DISCOSYN_MJX_IMPL") if chosen else "jax"


def check_impl(impl: str, name: str = "MJX implementation") -> str:
  if impl not in IMPLS:
    raise BadInput(f"{name}: unknown MJX implementation {impl!r}; known: {', '.join(IMPLS)}")
  # MJX carries its own copy of MuJoCo Warp (mujoco.mjx.third_party); it needs warp-lang
  if impl == "warp" and not importlib.util.find_spec("warp"):
    raise BadInput(f'{name}: MJX implementation "warp" needs warp-lang: pip install ".[warp]"')
  return impl


def check_environment() -> None:
  """Refuse in one line a bad DISCOSYN_MJX_IMPL (and, for Warp, DISCOSYN_WARP_GRAPH_MODE)."""
  if default_impl() == "warp":
    from discosyn_jax.env.physics import mjx_warp

    mjx_warp.graph_mode()


def make(model: mujoco.MjModel, n_substeps: int, impl: str | None = None, **kwargs):
  """The MJX backend of `impl` (default_impl() when None)."""
  impl = check_impl(impl) if impl else default_impl()
  if impl == "warp":
    from discosyn_jax.env.physics.mjx_warp import WarpBackend

    return WarpBackend(model, n_substeps, **kwargs)
  return MjxBackend(model, n_substeps)


class MjxBackend:
  """MJX's JAX implementation: its Data is the state."""
  name = "mjx"
  impl = "jax"

  def __init__(self, model: mujoco.MjModel, n_substeps: int):
    self.mj_model = model
    self.n_substeps = int(n_substeps)
    self.model = mjx.put_model(model, impl="jax")
    self._data0 = mjx.make_data(self.model, impl="jax")

  def init(self, qpos: jax.Array, qvel: jax.Array) -> mjx.Data:
    data = self._data0.replace(qpos=qpos.astype(jnp.float32), qvel=qvel.astype(jnp.float32))
    return mjx.forward(self.model, data)

  def step(self, data: mjx.Data, ctrl: jax.Array) -> mjx.Data:
    data = data.replace(ctrl=ctrl.astype(data.ctrl.dtype))
    return jax.lax.fori_loop(0, self.n_substeps, lambda _, d: mjx.step(self.model, d), data)

  def view(self, data: mjx.Data) -> PhysicsView:
    return PhysicsView(qpos=data.qpos, qvel=data.qvel, sensordata=data.sensordata)

  def from_mjdata(self, data: mujoco.MjData) -> mjx.Data:
    """The state of an MjData (forward evaluated), e.g. a native env's, to step on MJX."""
    return mjx.put_data(self.mj_model, data, impl="jax")

  def to_mjdata(self, data: mjx.Data) -> mujoco.MjData:
    """One environment's state as an MjData (forward evaluated), e.g. for rendering."""
    out = mjx.get_data(self.mj_model, data)
    mujoco.mj_forward(self.mj_model, out)
    return out
