"""MuJoCo's C engine called from inside jit: `jax.pure_callback` into `mujoco.batch`.

The whole integration state (`mjSTATE_INTEGRATION`: time, qpos, qvel, act, warm start,
ctrl, ...) travels through JAX as float64 bit-cast to uint32 pairs, so it round-trips
exactly with x64 off and a trajectory equals plain `mj_step` on one MjData. The callback
is vectorised (`vmap_method="broadcast_all"`): under vmap it receives every environment
of the batch in one call and steps them on a thread pool.

Divergence: where accelerations or velocities blow up, MuJoCo's C engine does not produce
NaN; it resets the simulation with a warning. Stepping through `Batch.rollout`, which stops
a simulation whose warnings rise, shows it as a substep whose time did not advance; such an
environment comes back with NaN qpos, which `HandEnv` reports as diverged (and ends).
"""

from __future__ import annotations

import os
import threading

import jax
import jax.numpy as jnp
import mujoco
import mujoco.batch
import numpy as np
from flax import struct

from discosyn_jax import checks
from discosyn_jax.env.physics.view import PhysicsView

_INTEGRATION = mujoco.mjtState.mjSTATE_INTEGRATION
_CTRL = mujoco.mjtState.mjSTATE_CTRL
_TIME = mujoco.mjtState.mjSTATE_TIME


@struct.dataclass
class NativeState:
  raw: jax.Array  # uint32[2 * nstate]: the float64 integration state, bit for bit
  qpos: jax.Array  # float32 copies for the tasks
  qvel: jax.Array
  sensordata: jax.Array


class NativeBackend:
  name = "native"

  def __init__(self, model: mujoco.MjModel, n_substeps: int, nthread: int | None = None):
    self.mj_model = model
    self.n_substeps = int(n_substeps)
    if nthread is None:
      nthread = checks.env_int("DISCOSYN_NATIVE_THREADS", os.cpu_count() or 1)
    self.nthread = int(nthread)
    self.nstate = mujoco.mj_stateSize(model, _INTEGRATION)
    self._batches: dict[int, mujoco.batch.Batch] = {}
    self._lock = threading.Lock()  # a Batch must not serve two calls at once
    f32 = np.float32
    self._out = NativeState(
        raw=jax.ShapeDtypeStruct((2 * self.nstate,), np.uint32),
        qpos=jax.ShapeDtypeStruct((model.nq,), f32),
        qvel=jax.ShapeDtypeStruct((model.nv,), f32),
        sensordata=jax.ShapeDtypeStruct((model.nsensordata,), f32),
    )

  # -- host side -------------------------------------------------------------
  def _batch(self, nsim: int) -> mujoco.batch.Batch:
    if nsim not in self._batches:
      self._batches[nsim] = mujoco.batch.Batch(self.mj_model, nsim, nthread=min(self.nthread, nsim))
    return self._batches[nsim]

  def _read(self, batch: mujoco.batch.Batch, lead: tuple[int, ...]):
    f32 = np.float32
    return (
        batch.state.copy().view(np.uint32).reshape(*lead, -1),
        batch.qpos.astype(f32).reshape(*lead, -1),
        batch.qvel.astype(f32).reshape(*lead, -1),
        batch.sensordata.astype(f32).reshape(*lead, -1),
    )

  def _host_init(self, qpos, qvel):
    lead = qpos.shape[:-1]
    nsim = int(np.prod(lead, dtype=int))
    with self._lock:
      batch = self._batch(nsim)
      batch.reset(stage=mujoco.mjtStage.mjSTAGE_NONE)
      batch.qpos[:] = np.asarray(qpos, np.float64).reshape(nsim, -1)
      batch.qvel[:] = np.asarray(qvel, np.float64).reshape(nsim, -1)
      batch.forward()
      return self._read(batch, lead)

  def _host_step(self, raw, ctrl):
    lead = raw.shape[:-1]
    nsim = int(np.prod(lead, dtype=int))
    with self._lock:
      batch = self._batch(nsim)
      state = np.ascontiguousarray(raw).reshape(nsim, -1).view(np.float64)
      batch.state[:] = state
      control = np.repeat(np.asarray(ctrl, np.float64).reshape(nsim, 1, -1), self.n_substeps, axis=1)
      times = batch.rollout(self.n_substeps, control=control, control_spec=_CTRL,
                            record=(_TIME,))[_TIME][..., 0]
      dt = self.mj_model.opt.timestep
      expected = state[:, :1] + dt * np.arange(1, self.n_substeps + 1)
      diverged = np.any(np.abs(times - expected) > 0.5 * dt, axis=1)
      out = self._read(batch, lead)
      out[1].reshape(nsim, -1)[diverged] = np.nan  # qpos
      return out

  # -- traced side -----------------------------------------------------------
  def _call(self, fn, *args) -> NativeState:
    shapes = (self._out.raw, self._out.qpos, self._out.qvel, self._out.sensordata)
    out = jax.pure_callback(fn, shapes, *args, vmap_method="broadcast_all")
    return NativeState(*out)

  def init(self, qpos: jax.Array, qvel: jax.Array) -> NativeState:
    return self._call(self._host_init, qpos.astype(jnp.float32), qvel.astype(jnp.float32))

  def step(self, state: NativeState, ctrl: jax.Array) -> NativeState:
    return self._call(self._host_step, state.raw, ctrl.astype(jnp.float32))

  def view(self, state: NativeState) -> PhysicsView:
    return PhysicsView(qpos=state.qpos, qvel=state.qvel, sensordata=state.sensordata)

  def to_mjdata(self, state: NativeState) -> mujoco.MjData:
    """One environment's state as an MjData (forward evaluated), e.g. for rendering."""
    data = mujoco.MjData(self.mj_model)
    mujoco.mj_setState(self.mj_model, data, np.asarray(state.raw).view(np.float64), _INTEGRATION)
    mujoco.mj_forward(self.mj_model, data)
    return data


def deepest_penetration(model: mujoco.MjModel, raw: np.ndarray, stride: int = 1) -> float:
  """Deepest contact penetration (m) over native states `raw` (..., 2 * nstate), every
  `stride`-th state: a check that contacts stay stiff enough for manipulation."""
  data = mujoco.MjData(model)
  deepest = 0.0
  for row in np.asarray(raw).reshape(-1, raw.shape[-1])[::stride]:
    mujoco.mj_setState(model, data, row.view(np.float64), _INTEGRATION)
    mujoco.mj_forward(model, data)
    if data.ncon:
      deepest = max(deepest, -float(data.contact.dist[: data.ncon].min()))
  return deepest
