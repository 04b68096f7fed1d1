"""A synergy prior from the physics: the action directions that move the task objects most,
pooled over the task set (issue 26's tie-breaker; docs/TRAINING_NOTES.md has its runs).

For each env: states of a uniform random policy (a fixed seed, never the run's); at each,
every action pushed by +-DELTA for one control step, and the objects' velocities after it
(the qvel of every joint that is not the hand's) differenced into a Jacobian J (object dofs
x actions). M_env = the sum over states of J^T J, scaled to trace 1 so that each task counts
alike; the prior basis is the top-b eigenvectors of their sum. It depends on the tasks, the
hand and the physics, never on a training seed, so every seed's decoder starts in the same
subspace (`start`: each keeps its own random scale, bias and noise).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax import hands, synergies

DELTA = 0.5  # the push on each action, in its [-1, 1] range
ENVS, EVERY = 32, 5  # random episodes per task, and every EVERY-th step of them kept
SEED = 0  # the prior's own: the same prior for every training seed
CHUNK = 64  # states whose pushes are stepped at once (bounds the memory of MJX envs)


def _object_dofs(env) -> list[int]:
  """The qvel addresses of what is not the hand; ValueError where there is nothing to move."""
  if not hasattr(env, "mj_model"):
    raise ValueError(f"the physics prior needs hand tasks; {type(env).__name__} has no physics")
  hand_v = set(hands.qvel_indices(env.mj_model).tolist())
  dofs = [i for i in range(env.mj_model.nv) if i not in hand_v]
  if not dofs:
    raise ValueError(f"the physics prior needs objects that move: {type(env.task).__name__}'s "
                     "scene has none")
  return dofs


def check(envs) -> None:
  """ValueError in one line where the prior cannot be made (before a run folder is)."""
  for env in envs:
    _object_dofs(env)


def object_jacobians(env) -> np.ndarray:
  """(states, object dofs, actions) of one hand env (module docstring)."""
  size = env.action_size
  obj_v = jnp.asarray(_object_dofs(env), jnp.int32)

  @jax.jit
  def collect(key):
    def body(state, key):
      action = jax.random.uniform(key, (ENVS, size), minval=-1, maxval=1)
      return jax.vmap(env.step)(state, action), (state, action)

    start = jax.vmap(env.reset)(jax.random.split(key, ENVS))
    keys = jax.random.split(jax.random.fold_in(key, 1), env.episode_length)
    _, (states, actions) = jax.lax.scan(body, start, keys)
    kept = lambda x: x[::EVERY].reshape((x[::EVERY].shape[0] * ENVS,) + x.shape[2:])
    return jax.tree.map(kept, (states, actions))

  def jacobian(pair):
    state, action = pair

    def object_velocity(a):
      after = env.step(state, jnp.clip(a, -1, 1))
      return env.physics.view(after.pipeline_state).qvel[obj_v]

    push = DELTA * jnp.eye(size)
    plus = jax.vmap(lambda d: object_velocity(action + d))(push)
    minus = jax.vmap(lambda d: object_velocity(action - d))(push)
    return ((plus - minus) / (2 * DELTA)).T

  states, actions = collect(jax.random.PRNGKey(SEED))
  return np.asarray(jax.jit(lambda s, a: jax.lax.map(jacobian, (s, a), batch_size=CHUNK))(
      states, actions))


def basis(envs, b: int) -> np.ndarray:
  """(actions, b): the top-b eigenvectors of the pooled, per-task normalised metrics."""
  pooled = 0.0
  for env in envs:
    jac = object_jacobians(env)
    metric = np.einsum("soa,sob->ab", jac, jac)
    pooled = pooled + metric / max(np.trace(metric), 1e-12)
  values, vectors = np.linalg.eigh(pooled)
  return vectors[:, np.argsort(values)[::-1][:b]]


def start(random_decoder: dict, prior: np.ndarray) -> dict:
  """A linear decoder's random initialisation turned into span(prior), keeping its singular
  values, bias and noise (synergies.in_subspace_of)."""
  own = jax.tree.map(np.asarray, random_decoder)
  return synergies.in_subspace_of(own, {"synergies": {"kernel": prior.T.astype(np.float32)}})
