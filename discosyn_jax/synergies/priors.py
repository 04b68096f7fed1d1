"""Synergy priors from the physics: the action directions that matter most to the task set,
the same for every seed (a tie-breaker; docs/notes/2026-12-02-f-physics-prior.md has its runs).

For each env: states of a uniform random policy (a fixed seed, never the run's; another
policy's where one is given, for diagnostics: docs/results/policy-states/); at each,
every action pushed by +-DELTA for one control step, and the step's outcome differenced into
a Jacobian J (outputs x actions). The outcome (`response`) is either the velocity of every
object dof (the joints that are not the hand's) or the task's reward of the step. M_env =
the sum over states of J^T J, scaled to trace 1 so that each task counts alike (`metric`);
the tasks' metrics make b directions (`pool`: the top-b of their sum, or each task its share
in turns). The priors a config names are config.PRIORS. A prior depends on the tasks, the
hand and the physics, never on a training seed, so every seed's decoder starts in the same
subspace (`start`: each keeps its own random scale, bias and noise). It is measured on
MuJoCo C (the reference physics, on the CPU) whatever backend the run trains on
(`reference`): a CPU and a GPU run of a set start alike, and MJX on a GPU spent 4 minutes
compiling the measurement (docs/notes/2026-12-04-d-gpu-h200.md).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.env import hand_env, hands
from discosyn_jax.env.task import not_finite
from discosyn_jax.synergies import fitting

DELTA = 0.5  # the push on each action, in its [-1, 1] range
ENVS, EVERY = 32, 5  # random episodes per task, and every EVERY-th step of them kept
SEED = 0  # the prior's own: the same prior for every training seed
CHUNK = 64  # states whose pushes are stepped at once (bounds the memory of MJX envs)


def _object_dofs(env) -> list[int]:
  """The qvel addresses of what is not the hand; BadInput where there is nothing to move."""
  if not hasattr(env, "mj_model"):
    raise BadInput(f"a prior needs hand tasks; {type(env).__name__} has no physics")
  hand_v = set(hands.qvel_indices(env.mj_model).tolist())
  dofs = [i for i in range(env.mj_model.nv) if i not in hand_v]
  if not dofs:
    raise BadInput(f"the objects prior needs objects that move: {type(env.task).__name__}'s "
                   "scene has none")
  return dofs


def check(envs) -> None:
  """BadInput in one line where the prior cannot be made (before a run folder is)."""
  for env in envs:
    _object_dofs(env)


RESPONSES = ("objects", "reward")  # what the pushes are read by (module docstring)
POOLINGS = ("trace", "share")  # how the tasks' metrics make one basis (`pool`)


def reference(env):
  """`env` on MuJoCo C: itself where it is native already (or is no hand env)."""
  if not isinstance(env, hand_env.HandEnv) or env.backend == "native":
    return env
  return type(env)(env.task, backend="native", hand=env.hand)


def jacobians(env, response: str = "objects", act=None) -> np.ndarray:
  """(states, outputs, actions): how one control step's outcome answers each action pushed,
  at states of a policy, on MuJoCo C (`reference`). `response` "objects": the
  velocity of every object dof; "reward": the task's reward of the step, what the task asks
  for (one output). `act(obs, key) -> actions` is the policy whose states are read (jittable,
  batched); None: a uniform random one, the prior's."""
  if response not in RESPONSES:
    raise BadInput(f"the prior's response must be one of {', '.join(RESPONSES)}, not "
                   f"{response!r}")
  env = reference(env)
  try:
    cpu = jax.devices("cpu")[0]
  except RuntimeError:  # JAX_PLATFORMS without cpu: the callbacks still run on the host
    cpu = None
  with jax.default_device(cpu):
    return _jacobians(env, response, act)


def _jacobians(env, response: str, act) -> np.ndarray:
  size = env.action_size
  # the reward is read from any env (a planted task's too); object velocities need a scene
  obj_v = jnp.asarray(_object_dofs(env), jnp.int32) if response == "objects" else None

  @jax.jit
  def collect(key):
    def body(state, key):
      action = (jax.random.uniform(key, (ENVS, size), minval=-1, maxval=1) if act is None
                else jnp.clip(act(state.obs, key), -1, 1))
      return jax.vmap(env.step)(state, action), (state, action)

    start = jax.vmap(env.reset)(jax.random.split(key, ENVS))
    keys = jax.random.split(jax.random.fold_in(key, 1), env.episode_length)
    _, (states, actions) = jax.lax.scan(body, start, keys)
    kept = lambda x: x[::EVERY].reshape((x[::EVERY].shape[0] * ENVS,) + x.shape[2:])
    return jax.tree.map(kept, (states, actions))

  def jacobian(pair):
    state, action = pair

    def outcome(a):
      """(the response, {part: its values}): the parts it is made of, checked finite."""
      after = env.step(state, jnp.clip(a, -1, 1))
      if response == "reward":
        return after.reward[None], {k: v for k, v in after.metrics.items() if k.startswith("reward/")}
      qvel = env.physics.view(after.pipeline_state).qvel[obj_v]
      return qvel, {"object velocity": qvel}

    push = DELTA * jnp.eye(size)
    plus, plus_parts = jax.vmap(lambda d: outcome(action + d))(push)
    minus, minus_parts = jax.vmap(lambda d: outcome(action - d))(push)
    finite = {k: jnp.isfinite(plus_parts[k]).all() & jnp.isfinite(minus_parts[k]).all()
              for k in plus_parts}
    return ((plus - minus) / (2 * DELTA)).T, finite

  states, actions = collect(jax.random.PRNGKey(SEED))
  jac, finite = jax.jit(lambda s, a: jax.lax.map(jacobian, (s, a), batch_size=CHUNK))(
      states, actions)
  # a NaN in a task's reward leaves the eigen-decomposition without convergence: named here
  bad = [part for part, ok in finite.items() if not np.all(ok)]
  if bad:
    raise BadInput(not_finite(type(env.task).__name__, bad,
                                f"at the states the {response} prior is measured at "
                                "(the decoder's start, before training)"))
  return np.asarray(jac)


def metric(env, response: str = "objects", act=None) -> np.ndarray:
  """(actions, actions): the task's response metric, the sum over states of J^T J, scaled to
  trace 1 so that each task counts alike (at the states of `act`, as `jacobians`)."""
  jac = jacobians(env, response, act)
  value = np.einsum("soa,sob->ab", jac, jac)
  return value / max(np.trace(value), 1e-12)


def pool(metrics: list[np.ndarray], b: int, pooling: str = "trace") -> np.ndarray:
  """(actions, b) orthonormal directions from the tasks' metrics. "trace": the top-b
  eigenvectors of their sum (a task whose response is spread thin can get none); "share":
  each task its share, in turns: task after task, the top direction of what its metric
  keeps outside the directions chosen so far."""
  if pooling not in POOLINGS:
    raise BadInput(f"the prior's pooling must be one of {', '.join(POOLINGS)}, not "
                   f"{pooling!r}")
  if pooling == "trace":
    values, vectors = np.linalg.eigh(sum(metrics))
    return vectors[:, np.argsort(values)[::-1][:b]]
  size = metrics[0].shape[0]
  chosen = np.zeros((size, 0))
  for turn in range(b):
    rest = np.eye(size) - chosen @ chosen.T  # the projector off the chosen directions
    values, vectors = np.linalg.eigh(rest @ metrics[turn % len(metrics)] @ rest)
    if values[-1] <= 1e-12:  # nothing of this task left outside the chosen: the pooled rest
      values, vectors = np.linalg.eigh(rest @ sum(metrics) @ rest)
    direction = rest @ vectors[:, -1]
    chosen = np.column_stack([chosen, direction / np.linalg.norm(direction)])
  return chosen


def own(metrics: list[np.ndarray], shared: np.ndarray, k: int) -> np.ndarray:
  """(tasks, actions, k): each task's k orthonormal directions of its own, the top k of
  what its metric holds outside span(shared) (actions, b), orthogonal to that span."""
  size = metrics[0].shape[0]
  # an orthonormal basis of the complement: the metric is read there alone, so that even a
  # metric with nothing outside the span gives directions outside it
  u = np.linalg.svd(shared, full_matrices=True)[0] if shared.shape[1] else np.eye(size)
  rank = int(np.linalg.matrix_rank(shared)) if shared.shape[1] else 0
  rest = u[:, rank:]
  if rest.shape[1] < k:
    raise BadInput(f"{k} own synergies do not fit beside a {rank}-dimensional shared space "
                   f"in {size} actions")
  out = []
  for metric_ in metrics:
    values, vectors = np.linalg.eigh(rest.T @ metric_ @ rest)
    out.append(rest @ vectors[:, np.argsort(values)[::-1][:k]])
  return np.stack(out)


def captured(directions: np.ndarray, metric_: np.ndarray) -> float:
  """The share of a task's metric (trace 1) that span(directions) holds."""
  q, _ = np.linalg.qr(directions)
  return float(np.trace(q.T @ metric_ @ q) / max(np.trace(metric_), 1e-12))


def basis(envs, b: int, response: str = "objects", pooling: str = "trace",
          acts=None) -> np.ndarray:
  """(actions, b): the prior's directions for a task set (module docstring); read at the
  states of `acts`, a policy per env (as `jacobians`), where given."""
  acts = [None] * len(envs) if acts is None else acts
  return pool([metric(env, response, a) for env, a in zip(envs, acts)], b, pooling)


def start(random_decoder: dict, prior: np.ndarray) -> dict:
  """A linear decoder's random initialisation turned into span(prior), keeping its singular
  values, bias and noise (fitting.in_subspace_of)."""
  own = jax.tree.map(np.asarray, random_decoder)
  return fitting.in_subspace_of(own, {"synergies": {"kernel": prior.T.astype(np.float32)}})
