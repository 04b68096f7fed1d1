"""MuJoCo Warp (MJX's Warp implementation, on Warp's CPU device here) beside MuJoCo C and MJX's
JAX implementation: the same start states (a native reset), the same actions (each task's
scripted motion), and the largest |qpos difference| between each pair over the steps; and
how much of Warp's buffers (sized by env/physics/mjx_warp.py) the batch used.

  python -m studies.warp_parity                           # every task, both hands
  python -m studies.warp_parity --tasks dice valve3 --hands shadow20 --steps 10
  python -m studies.warp_parity --no-jax                  # Warp against C only (quicker)
  python -m studies.warp_parity --tasks dice --native-ccd # Warp's own box-box (GJK/EPA)

Columns: `warp-C`, `jax-C`, `warp-jax`: max |qpos difference| over the steps and envs (rad
or m), of the hand's joints, then of the object's; `contacts`, `pairs`: the most contacts
and broadphase pairs of the batch at once against its pool (mjx_warp: contacts_per_env x
batch); `rows`: the most constraint rows of one env against its buffer; `solver limits`: the
share of env steps where Warp's solver reached its iteration limit (it), its line search's
(ls).
"""

from __future__ import annotations

import argparse
import os
import time

ALL_TASKS = ["valve0", "valve1", "valve2", "valve3", "dice", "weight_pull", "screw",
             "valve_cylinder", "valve_cw", "screw_topdown", "valve_goal"]
ITERATIONS, LS_ITERATIONS = 1 << 9, 1 << 10  # MuJoCo Warp's OverflowType bits


def native_run(env, start, actions):
  """MuJoCo C from `start` (the native env's batched state) through actions (T, B, nu)."""
  import jax

  step = jax.jit(lambda s, a: jax.lax.scan(lambda s, a: (jax.vmap(env.step)(s, a),) * 2, s, a)[1])
  return step(start, actions)


def mjx_run(backend, datas, ctrl, usage: bool):
  """qpos (T, B, nq) of `backend` from the MjData `datas` through ctrl; with `usage`, Warp's
  buffer use too (its internals: the Data of each step, under vmap)."""
  import jax
  import jax.numpy as jnp
  import numpy as np
  from mujoco import mjx

  start = jax.tree.map(lambda *x: jnp.stack(x), *[backend.from_mjdata(d) for d in datas])
  batch = len(datas)

  def warp_step(state, c):
    data = backend._data(batch, state.replace(ctrl=c))

    def substep(_, carry):
      d, most = carry
      d = mjx.step(backend.model, d)
      now = jnp.stack([d._impl.nacon[0], d._impl.ncollision[0], d._impl.nefc])
      return d, jnp.maximum(most, now)

    data, most = jax.lax.fori_loop(0, backend.n_substeps, substep, (data, jnp.zeros(3, jnp.int32)))
    return backend._state(data), (most, data._impl.overflow)

  if usage:
    one = lambda s, c: jax.vmap(warp_step)(s, c)
  else:
    one = lambda s, c: (jax.vmap(backend.step)(s, c), None)

  def scan_step(state, c):
    state, extra = one(state, c)
    return state, (state.qpos, extra)

  qpos, extra = jax.jit(lambda s, a: jax.lax.scan(scan_step, s, a)[1])(start, ctrl)
  return np.asarray(qpos), jax.device_get(extra)


def measure(name: str, hand: str, batch: int, steps: int, with_jax: bool, native_ccd: bool):
  import jax
  import jax.numpy as jnp
  import numpy as np

  from discosyn_jax import tasks
  from discosyn_jax.env import hands
  from discosyn_jax.env.physics import mjx_backend
  from discosyn_jax.env.physics.mjx_warp import WarpBackend

  native = tasks.make(name, backend="native", hand=hand)
  model, n = native.mj_model, native.task.config.n_substeps
  start = jax.jit(jax.vmap(native.reset))(jax.random.split(jax.random.PRNGKey(0), batch))
  actions = np.repeat(native.task.motion.actions(steps, native.dt, hand)[:, None], batch, axis=1)
  actions = jnp.asarray(actions, jnp.float32)
  ctrl = native.action_to_ctrl(actions)
  host = jax.device_get(start.pipeline_state)
  datas = [native.physics.to_mjdata(jax.tree.map(lambda x: x[i], host)) for i in range(batch)]
  qpos = {"C": np.asarray(native_run(native, start, actions).pipeline_state.qpos)}
  warp = WarpBackend(model, n, primitive_box_box=not native_ccd)
  qpos["warp"], (most, overflow) = mjx_run(warp, datas, ctrl, usage=True)
  if with_jax:
    qpos["jax"], _ = mjx_run(mjx_backend.MjxBackend(model, n), datas, ctrl, usage=False)
  most = np.asarray(most).max(axis=(0, 1))
  overflow = np.asarray(overflow)
  hand_q = hands.qpos_indices(model)
  object_q = np.setdiff1d(np.arange(model.nq), hand_q)

  def diff(a, b):  # (hand, object)
    if a not in qpos or b not in qpos:
      return None
    d = np.abs(qpos[a] - qpos[b])
    return float(d[..., hand_q].max()), float(d[..., object_q].max(initial=0.0))

  return dict(warp_c=diff("warp", "C"), jax_c=diff("jax", "C"), warp_jax=diff("warp", "jax"),
              contacts=(int(most[0]), warp.contacts * batch),
              pairs=(int(most[1]), warp.contacts * batch), rows=(int(most[2]), warp.constraints),
              buffers=int((overflow & warp.buffers).max()),
              it=float(((overflow & ITERATIONS) > 0).mean()),
              ls=float(((overflow & LS_ITERATIONS) > 0).mean()))


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--tasks", nargs="+", default=ALL_TASKS)
  parser.add_argument("--hands", nargs="+", default=["shadow20", "leap16"])
  parser.add_argument("--batch", type=int, default=4, help="envs (default: %(default)s)")
  parser.add_argument("--steps", type=int, default=10, help="control steps (default: %(default)s)")
  parser.add_argument("--no-jax", dest="jax", action="store_false",
                      help="leave MJX's JAX implementation out (its compile is most of the time)")
  parser.add_argument("--native-ccd", action="store_true",
                      help="Warp's own box-box collision (GJK/EPA) instead of its primitive")
  args = parser.parse_args(argv)
  from discosyn_jax.run import jax_setup

  jax_setup.setup_jax()
  when = time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())
  print(f"# {args.batch} envs x {args.steps} control steps of each task's scripted motion from a "
        f"native reset; load {os.getloadavg()[0]:.1f}; {when}")
  print("| hand | task | warp-C | jax-C | warp-jax | contacts | pairs | rows | "
        "buffers overflowed | solver limits (it, ls) | s |")
  print("|---|---|---|---|---|---|---|---|---|---|---|")
  fmt = lambda x: "-" if x is None else f"{x[0]:.1e}, {x[1]:.1e}"
  for hand in args.hands:
    for name in args.tasks:
      start = time.perf_counter()
      r = measure(name, hand, args.batch, args.steps, args.jax, args.native_ccd)
      print(f"| {hand} | {name} | {fmt(r['warp_c'])} | {fmt(r['jax_c'])} | {fmt(r['warp_jax'])} | "
            f"{r['contacts'][0]} / {r['contacts'][1]} | {r['pairs'][0]} / {r['pairs'][1]} | "
            f"{r['rows'][0]} / {r['rows'][1]} | {r['buffers'] or 'none'} | "
            f"{r['it']:.0%}, {r['ls']:.0%} | {time.perf_counter() - start:.0f} |", flush=True)


if __name__ == "__main__":
  main()
