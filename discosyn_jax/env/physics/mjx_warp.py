"""MuJoCo Warp through MJX (`DISCOSYN_MJX_IMPL=warp`): its kernels on a CUDA GPU, or on
the CPU (Warp's CPU device; slow, for checks).

What differs from MJX's JAX implementation, and why:
- The state carried between control steps is the integration state (`WarpState`), not
  MJX's Data. Under vmap, Warp's contact arrays are one pool shared by the whole batch
  (not one row per env), which the training wrappers' per-env selections (`jnp.where` on
  finished episodes, the reset pool's rows) cannot take. Each step rebuilds the Data from
  the integration state, as `mj_step` needs nothing else.
- The buffers are sized from the scene and the batch: the batch's contact pool holds
  `contacts_per_env` for every env of the vmapped batch (known inside the step through
  `custom_vmap`), the constraint rows `constraints_per_env` per env.
- Box-box contacts as MuJoCo C makes them: Warp's own default for them is its general convex
  collision (GJK/EPA), whose contact points differ from C's box-box primitive, enough to turn
  the dice differently where it lands on the palm; MuJoCo's NATIVECCD disable bit, which
  Warp reads for nothing else, selects Warp's box-box primitive. The C engine's model is
  left as it is (docs/BENCHMARKS.md, "MuJoCo Warp").
- A buffer outgrown in a step (contacts, constraint rows, ...) is never a silent wrong
  contact: Warp prints its one line ("narrowphase overflow - ..."), the env's bits are in
  `WarpState.overflow`, and its qpos comes back NaN, which `HandEnv` counts as diverged
  (the `diverged` figure of the training logs) and ends the episode.
"""

from __future__ import annotations

import copy
import functools
import os

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from flax import struct
from mujoco import mjx

from discosyn_jax.checks import BadInput
from discosyn_jax.env.physics.view import PhysicsView

GRAPH_MODES = ("none", "jax", "warp", "warp_staged", "warp_staged_ex")


@struct.dataclass
class WarpState:
  """One env's integration state (mjSTATE_INTEGRATION's fields, less the applied forces,
  eq_active, actuator history and plugin state, which no scene of ours changes), the sensors
  of its last substep, and the buffer overflows of its last step (0: none)."""
  time: jax.Array
  qpos: jax.Array
  qvel: jax.Array
  act: jax.Array
  qacc_warmstart: jax.Array
  ctrl: jax.Array
  mocap_pos: jax.Array
  mocap_quat: jax.Array
  sensordata: jax.Array
  overflow: jax.Array


_CARRIED = ("time", "qpos", "qvel", "act", "qacc_warmstart", "ctrl", "mocap_pos", "mocap_quat")


def colliding_geoms(model: mujoco.MjModel) -> int:
  return int(((model.geom_contype != 0) | (model.geom_conaffinity != 0)).sum())


def contacts_per_env(model: mujoco.MjModel) -> int:
  """One env's share of the batch's contact pool, which holds the broadphase's candidate
  pairs and then the contacts: 4 per colliding geom. The most our scenes reached at once,
  per env, over scripted and random motions of both hands: 36 pairs (1.3 per colliding geom,
  valve_cylinder on the shadow hand) and 11 contacts (the dice on the palm):
  docs/BENCHMARKS.md, "MuJoCo Warp"."""
  return 4 * colliding_geoms(model)


def constraints_per_env(model: mujoco.MjModel) -> int:
  """Constraint rows one env may need: every limited joint and tendon at its limit, every
  dof and tendon with dry friction, every equality, and 2 contacts per colliding geom of the
  scene's largest condim (2 (condim - 1) rows each when pyramidal, condim when elliptic).
  The most our scenes reached: 72 rows (the dice), 35 % of its 204."""
  condim = int(model.geom_condim.max(initial=3))
  per_contact = condim if model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC else 2 * (condim - 1)
  equality = {mujoco.mjtEq.mjEQ_CONNECT: 3, mujoco.mjtEq.mjEQ_WELD: 6}
  rows = (int(model.jnt_limited.sum()) + int(model.tendon_limited.sum())
          + int((model.dof_frictionloss > 0).sum()) + int((model.tendon_frictionloss > 0).sum())
          + sum(equality.get(int(kind), 1) for kind in model.eq_type))
  return rows + per_contact * 2 * colliding_geoms(model)


def graph_mode() -> str | None:
  """`DISCOSYN_WARP_GRAPH_MODE` (GRAPH_MODES) where set, else MJX's default (on a GPU Warp
  captures CUDA graphs itself, `warp`; on the CPU `jax`)."""
  chosen = os.environ.get("DISCOSYN_WARP_GRAPH_MODE", "").strip().lower()
  if chosen and chosen not in GRAPH_MODES:
    raise BadInput(f"environment variable DISCOSYN_WARP_GRAPH_MODE must be one of "
                   f"{', '.join(GRAPH_MODES)}, not {chosen!r}")
  return chosen or None


def buffer_bits() -> int:
  """MuJoCo Warp's overflow bits of buffers that a step outgrew (contacts, constraint rows,
  collision scratch); not its solver's iteration limits, where MuJoCo C too stops silently."""
  from mujoco.mjx.third_party.mujoco_warp._src.types import OverflowType

  return int(OverflowType.ALL & ~(OverflowType.ITERATIONS | OverflowType.LS_ITERATIONS))


def _batched(fn):
  """fn(worlds, *args) for one env as a function that vmap batches whole: under vmap, fn runs
  vmapped with `worlds` = the batch size (Warp sizes its contact pool by it)."""

  @jax.custom_batching.custom_vmap
  def one(*args):
    return fn(1, *args)

  @one.def_vmap
  def rule(axis_size, in_batched, *args):
    args = jax.tree.map(lambda x, b: x if b else jnp.broadcast_to(x, (axis_size, *x.shape)),
                        list(args), list(in_batched))
    out = jax.vmap(functools.partial(fn, axis_size))(*args)
    return out, jax.tree.map(lambda _: True, out)

  return one


class WarpBackend:
  name = "mjx"
  impl = "warp"

  def __init__(self, model: mujoco.MjModel, n_substeps: int, contacts: int | None = None,
               constraints: int | None = None, primitive_box_box: bool = True):
    """`contacts`, `constraints`: per env (default: sized from the scene);
    `primitive_box_box` False: Warp's own GJK/EPA box-box (studies/warp_parity.py)."""
    import warp as wp  # the optional extra, checked by mjx_backend.check_impl

    # no banner, no line per kernel module compiled; warnings stay
    wp.config.log_level = max(wp.config.log_level, wp.LOG_WARNING)
    self.mj_model = model
    self.n_substeps = int(n_substeps)
    self.contacts = contacts or contacts_per_env(model)
    self.constraints = constraints or constraints_per_env(model)
    self._warp_model = copy.deepcopy(model)
    if primitive_box_box:
      self._warp_model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_NATIVECCD
    mode = graph_mode()
    model_w = mjx.put_model(self._warp_model, impl="warp",
                            graph_mode=mode and wp.JaxCallableGraphMode[mode.upper()])
    self.buffers = buffer_bits()
    opt = model_w.opt  # Warp prints a line for these overflows only
    warn = opt._impl.replace(warn_overflow=self.buffers)
    self.model = model_w.replace(opt=opt.replace(_impl=warn))
    self._datas: dict[int, mjx.Data] = {}
    self.init = _batched(self._init)
    self.step = _batched(self._step)

  def _data0(self, worlds: int) -> mjx.Data:
    """MJX's Warp Data for `worlds` envs vmapped together (the contact pool is theirs)."""
    if worlds not in self._datas:
      with jax.ensure_compile_time_eval():  # made while a step is traced, kept for the next
        self._datas[worlds] = mjx.make_data(self._warp_model, impl="warp", njmax=self.constraints,
                                            naconmax=self.contacts * worlds)
    return self._datas[worlds]

  def _data(self, worlds: int, state: WarpState) -> mjx.Data:
    return self._data0(worlds).replace(**{k: getattr(state, k) for k in _CARRIED})

  def _state(self, data: mjx.Data) -> WarpState:
    overflow = data._impl.overflow & self.buffers
    qpos = jnp.where(overflow != 0, jnp.nan, data.qpos)  # reported as diverged
    return WarpState(**{k: getattr(data, k) for k in _CARRIED}, sensordata=data.sensordata,
                     overflow=overflow).replace(qpos=qpos)

  def _blank(self) -> WarpState:
    d = self._data0(1)
    return WarpState(**{k: getattr(d, k) for k in _CARRIED},
                     sensordata=d.sensordata, overflow=jnp.zeros((), jnp.int32))

  def _init(self, worlds: int, qpos: jax.Array, qvel: jax.Array) -> WarpState:
    state = self._blank().replace(qpos=qpos.astype(jnp.float32), qvel=qvel.astype(jnp.float32))
    return self._state(mjx.forward(self.model, self._data(worlds, state)))

  def _step(self, worlds: int, state: WarpState, ctrl: jax.Array) -> WarpState:
    data = self._data(worlds, state.replace(ctrl=ctrl.astype(jnp.float32)))
    data = jax.lax.fori_loop(0, self.n_substeps, lambda _, d: mjx.step(self.model, d), data)
    return self._state(data)

  def view(self, state: WarpState) -> PhysicsView:
    return PhysicsView(qpos=state.qpos, qvel=state.qvel, sensordata=state.sensordata)

  def from_mjdata(self, data: mujoco.MjData) -> WarpState:
    """The state of an MjData (forward evaluated), e.g. a native env's, to step on Warp."""
    f32 = lambda x: jnp.asarray(np.asarray(x, np.float32))
    return WarpState(**{k: f32(getattr(data, k)) for k in _CARRIED},
                     sensordata=f32(data.sensordata), overflow=jnp.zeros((), jnp.int32))

  def to_mjdata(self, state: WarpState) -> mujoco.MjData:
    """One environment's state as an MjData (forward evaluated), e.g. for rendering."""
    out = mujoco.MjData(self.mj_model)
    out.time = float(state.time)
    for k in _CARRIED[1:]:
      getattr(out, k)[...] = np.asarray(getattr(state, k), np.float64)
    mujoco.mj_forward(self.mj_model, out)
    return out
