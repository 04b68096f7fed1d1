"""The training step: one pure, jit-compiled function `train_step(state) -> (state, metrics)`.

  for each task (a Python loop unrolled at trace time: tasks have different models)
    lax.scan over unroll_length control steps, num_envs envs in parallel:
      obs -> normalise -> head_n -> z -> decoder -> a -> env_n.step
      (with a residual: a += rho(step) r, r from head n's residual; agent/residual.py)
  extended reward r + alpha2 log q(z|a); GAE per task (brax's compute_gae, with truncation)
  PPO epochs over minibatches, every task's samples in every minibatch; the discriminator is
  fitted in the same optimiser steps on its own parameters (see ppo.py)

Over several devices (devices.py) the rollout runs under `shard_map`, each device stepping
its share of the envs; the rest is partitioned by XLA on the sharded env/sample axis.

The bonus log q(z|a) is computed with the discriminator as it was when the batch was
collected, then the discriminator is fitted to that batch during the same update: the
paper's Algorithm 1 fits q first, which differs by one update of q.
"""

from __future__ import annotations

import functools
from typing import Any, Sequence

import jax
import jax.numpy as jnp
import optax
from brax.envs.base import Env
from brax.training.acme import running_statistics
from brax.training.agents.ppo.losses import compute_gae
from flax import struct
from jax.sharding import PartitionSpec as P

from discosyn_jax.agent import networks, policy, ppo, residual
from discosyn_jax.agent.networks import DiscoSyn
from discosyn_jax.checks import BadInput
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import wrappers
from discosyn_jax.synergies import diagnostics
from discosyn_jax.training import devices as devices_lib
from discosyn_jax.training import evaluation

# a task counts as paid (z_std_floor) from the first rollout in which some step's reward from
# the env was at least this (positive: the weight pull pays -0.007 a step at rest, 0.01 for a
# lift of 0.9 mm): a dense task at once, a task that pays only once found not before
PAID = 0.01


@struct.dataclass
class TrainState:
  params: Any
  opt_state: Any
  normalizers: tuple  # running_statistics state per task
  env_states: tuple  # batched brax State per task
  rng: jax.Array  # uint32[2]
  step: jax.Array  # int32: train steps done
  # bool per task: its training rollouts have been paid (PAID); empty without z_std_floor,
  # so that a checkpoint of a run without it holds no such array
  paid: jax.Array


class Trainer:
  """Builds the module, the optimiser and the jitted functions for one config.

  `envs`, one per task of the config, are built by the caller (`assemble.trainer(config)` for
  the registered tasks): any Brax-style env with `episode_length`, a `success` metric and
  actions in [-1, 1] works (the tests use a tiny one). `devices`
  (a list, a count, or None for all) holds the mesh the env batch is split over.
  """

  def __init__(self, config: TrainConfig, envs: Sequence[Env], devices=None):
    self.config = config.validate()
    self.mesh = devices_lib.mesh_for(config, devices)
    self.envs = list(envs)
    if len(self.envs) != len(config.tasks):
      raise BadInput(f"{len(self.envs)} envs given for {len(config.tasks)} tasks")
    sizes = {env.action_size for env in self.envs}
    if len(sizes) != 1:
      raise BadInput(f"the tasks' action sizes differ: {sorted(sizes)}")
    self.action_size = sizes.pop()
    if config.own_synergies and config.n_synergies + config.own_synergies > self.action_size:
      raise BadInput(f"{config.n_synergies} shared + {config.own_synergies} own synergies are more "
                     f"than the hand's {self.action_size} actions")
    self.obs_sizes = tuple(env.observation_size for env in self.envs)
    self.model = networks.build(config, self.obs_sizes, self.action_size)
    self.optimizer = ppo.optimizer(config)
    self.train_envs = [wrappers.for_training(env, config.reset_pool) for env in self.envs]
    self.eval_envs = [wrappers.for_evaluation(env) for env in self.envs]  # evaluation.py
    self._fresh_state = jax.jit(self._initial_state)
    self._fresh_params = jax.jit(self._init_params)
    # the span the tasks plant, if they do (discosyn_jax/tasks/planted.py): what the decoder should find
    self.planted_span = diagnostics.union_span(
        [env.planted_span for env in self.envs if getattr(env, "planted_span", None) is not None])
    # the decoder's movement from a reference (diagnostics.py); None without a decoder
    self.decoder_drift = (jax.jit(functools.partial(diagnostics.decoder_drift, self.model,
                                                    planted=self.planted_span))
                          if self.model.has_discriminator else None)
    self.train_step = jax.jit(self._train_step, donate_argnums=0)
    # the deterministic policy's returns and success per task (evaluation.evaluate's jitted
    # part), and its episodes of one task (evaluation.py)
    self.returns = jax.jit(functools.partial(evaluation.returns, self), static_argnames=("count",))
    self.episodes = jax.jit(functools.partial(evaluation.episodes, self),
                            static_argnames=("task", "episodes", "keep_states"))

  # -- state -----------------------------------------------------------------
  def init(self, seed: int | None = None, decoder_params=None, own=None) -> TrainState:
    """A fresh state; `decoder_params` replace the initial decoder (a fitted or learned
    synergy space: the host side loads it, see `synergies.load_decoder`), `own` each task's
    own synergies, (tasks, k, actions) (synergies/start.py's)."""
    key = jax.random.PRNGKey(self.config.seed if seed is None else seed)
    # one jitted function: MJX run op by op (eagerly) takes minutes per reset
    state = self._fresh_state(key, decoder_params, own)
    return jax.device_put(state, self.state_shardings(state))

  def initial_params(self, seed: int | None = None, decoder_params=None, own=None):
    """The parameters `init(seed, decoder_params, own)` starts from, without building envs."""
    key = jax.random.PRNGKey(self.config.seed if seed is None else seed)
    return _with_start(self._fresh_params(self._split(key)[1]), decoder_params, own)

  def _split(self, key):
    return networks.split_seed_key(key, len(self.envs))

  def _init_params(self, key):
    return self.model.init(key, [jnp.zeros((1, s)) for s in self.obs_sizes])

  def _initial_state(self, key, decoder_params, own) -> TrainState:
    key, init_key, env_keys = self._split(key)
    params = _with_start(self._init_params(init_key), decoder_params, own)
    envs = tuple(env.reset(jax.random.split(k, self.config.num_envs))
                 for env, k in zip(self.train_envs, env_keys))
    norms = tuple(running_statistics.init_state(jnp.zeros((s,))) for s in self.obs_sizes)
    # every leaf an array of the dtype train_step returns: one compiled signature, one
    # checkpoint layout
    paid = jnp.zeros((len(self.envs) if self.config.z_std_floor else 0,), bool)
    state = TrainState(params=params, opt_state=self.optimizer.init(params), normalizers=norms,
                       env_states=envs, rng=key, step=jnp.zeros((), jnp.int32), paid=paid)
    return jax.tree.map(lambda x: jnp.asarray(x, dtype=jnp.asarray(x).dtype), state)

  def state_shardings(self, state: TrainState):
    """Env states split over the mesh on their env axis; everything else replicated (and
    empty arrays, e.g. a scene without sensors, which XLA always returns replicated)."""
    replicated, batched = devices_lib.replicated(self.mesh), devices_lib.batched(self.mesh)
    return state.replace(
        **{f: jax.tree.map(lambda _: replicated, getattr(state, f))
           for f in ("params", "opt_state", "normalizers", "rng", "step", "paid")},
        env_states=jax.tree.map(lambda x: batched if x.size else replicated, state.env_states))

  # -- acting ----------------------------------------------------------------
  def normalize(self, obs, norm):
    if not self.config.normalize_observations:
      return obs
    return running_statistics.normalize(obs, norm, max_abs_value=10.0)

  def act(self, params, task: int, obs, key=None, at_step=None):
    """(z, a, log pi(z, a | s)) for normalised `obs`; the means (and no log-prob) when
    `key` is None. `at_step`: the train step whose residual weight to act with (with a
    residual; None: its cap, the weight of a finished run)."""
    rho = self.rho(at_step)
    if key is None:
      return (*policy.deterministic(self.model, params, task, obs, rho), None)
    return policy.sample(self.model, params, task, obs, self._noise(key, obs.shape[0]), rho)

  def rho(self, step=None):
    """The residual's weight at train step `step` (its cap when None); None without one."""
    if not self.model.residual:
      return None
    return jnp.float32(self.config.residual) if step is None else residual.rho(self.config, step)

  def _noise(self, key, batch: int):
    return policy.noise(key, batch, self.model.z_size, self.action_size, self.model.residual)

  def _unroll(self, params, norm, env_state, key, task: int, rho=None):
    """`unroll_length` steps of every env: under shard_map, each device its own envs."""
    env = self.train_envs[task]
    keys = jax.random.split(key, self.config.unroll_length)
    noise = jax.vmap(lambda k: self._noise(k, self.config.num_envs))(keys)  # (T, B, ...)
    envs, time_envs = P(devices_lib.AXIS), P(None, devices_lib.AXIS)
    args, specs = (params, norm, env_state, noise), (P(), P(), envs, time_envs)
    if rho is not None:
      args, specs = args + (rho,), specs + (P(),)
    local = jax.shard_map(lambda *args: self._local_unroll(env, task, *args), mesh=self.mesh,
                          in_specs=specs, out_specs=(envs, time_envs), check_vma=False)
    return local(*args)

  def _local_unroll(self, env, task: int, params, norm, env_state, noise, rho=None):

    def step(env_state, noise):
      obs = env_state.obs
      z, a, log_prob = policy.sample(self.model, params, task, self.normalize(obs, norm), noise,
                                     rho)
      env_state = env.step(env_state, a)
      info = env_state.info
      out = dict(obs=obs, z=z, action=a, log_prob=log_prob, reward=env_state.reward,
                 done=env_state.done, truncation=info["truncation"],
                 episode_return=info["episode_metrics"]["sum_reward"],
                 metrics=env_state.metrics)
      return env_state, out

    return jax.lax.scan(step, env_state, noise)

  # -- the training step -----------------------------------------------------
  def _train_step(self, state: TrainState):
    cfg = self.config
    rng, update_key, *task_keys = jax.random.split(state.rng, 2 + len(self.envs))
    params = state.params
    rho = self.rho(state.step)  # None without a residual
    env_states, norms, samples, metrics, own_values, paid_now = [], [], [], {}, {}, []
    for n, name in enumerate(cfg.tasks):
      env_state, traj = self._unroll(params, state.normalizers[n], state.env_states[n],
                                     task_keys[n], n, rho)
      if rho is not None:
        metrics.update({f"{name}/{k}": v for k, v in self._action_shares(
            params, n, self.normalize(traj["obs"], state.normalizers[n]), traj["z"], rho).items()})
      norm = state.normalizers[n]
      if cfg.normalize_observations:
        norm = running_statistics.update(norm, traj["obs"].reshape(-1, traj["obs"].shape[-1]))
      obs = self.normalize(traj["obs"], norm)
      if cfg.z_std_floor:
        paid_now.append((traj["reward"] >= PAID).any())
      reward = traj["reward"] * cfg.reward_scaling
      log_q, alpha2 = jnp.zeros_like(reward), cfg.alpha2
      if self.model.has_discriminator:
        log_q = ppo.discriminator_log_prob(self.model, params, traj["z"], traj["action"])
        if cfg.bonus_cap:
          scale = bonus_scale(reward, alpha2 * log_q)
          alpha2 = alpha2 * scale
          metrics[f"{name}/bonus_scale"] = scale
        reward = reward + alpha2 * log_q
      value = self.model.apply(params, n, obs, method=DiscoSyn.value)
      bootstrap = self.model.apply(params, n, self.normalize(env_state.obs, norm),
                                   method=DiscoSyn.value)
      target, advantage = gae(reward, value, bootstrap, traj["done"], traj["truncation"], cfg)
      flat = lambda x: x.reshape((-1,) + x.shape[2:])
      samples.append(ppo.Samples(obs=flat(obs), z=flat(traj["z"]), action=flat(traj["action"]),
                                 log_prob=flat(traj["log_prob"]), advantage=flat(advantage),
                                 target=flat(target)))
      env_states.append(env_state)
      norms.append(norm)
      metrics.update({f"{name}/{k}": v for k, v in _episode_metrics(traj, log_q, alpha2).items()})
      own_values[name] = _finite_values(traj, env_state.obs)

    if self.model.has_discriminator and not cfg.freeze_decoder:
      metrics.update({f"{name}/decoder_share": share for name, share in
                      zip(cfg.tasks, self._decoder_shares(params, samples, rho))})
    params, opt_state, loss_metrics = self._update(params, state.opt_state, samples, update_key,
                                                   rho)
    if rho is not None:
      metrics["residual/rho"] = rho
    paid = state.paid
    if cfg.z_std_floor:  # a head is held open until its task first pays a rollout
      paid = paid | jnp.stack(paid_now)
      params = networks.floor_head_std(params, ~paid, cfg.z_std_floor)
      metrics.update({f"{name}/paid": paid[n] for n, name in enumerate(cfg.tasks)})
    for n, name in enumerate(cfg.tasks):
      metrics.update({f"{name}/{k}": v for k, v in loss_metrics["tasks"][n].items()})
    metrics.update(loss_metrics["shared"])
    finite = jnp.isfinite(loss_metrics["shared"]["loss"])
    for leaf in jax.tree.leaves(params):
      finite &= jnp.isfinite(leaf).all()
    metrics["finite"] = finite
    metrics["finite_values"] = own_values
    new = TrainState(params=params, opt_state=opt_state, normalizers=tuple(norms),
                     env_states=tuple(env_states), rng=rng, step=state.step + 1, paid=paid)
    # pin the layout of the returned state to the one it came in with (donation, next step)
    new = jax.lax.with_sharding_constraint(new, self.state_shardings(new))
    metrics = jax.lax.with_sharding_constraint(metrics, devices_lib.replicated(self.mesh))
    return new, metrics

  def _action_shares(self, params, task: int, obs, z, rho) -> dict[str, jax.Array]:
    """How much of a rollout's actions each part carries: the mean |.| over envs, steps and
    actuators of the synergies' part (the decoder's mean, posture included) and of the
    residual's (rho times its mean)."""
    synergy, res = policy.action_parts(self.model, params, task, obs, z, rho)
    return {"action_synergy": jnp.abs(synergy).mean(), "action_residual": jnp.abs(res).mean()}

  def _decoder_shares(self, params, samples: list[ppo.Samples], rho) -> list[jax.Array]:
    """Each task's share of the decoder's gradient, |g_n| / sum_m |g_m| with g_n the gradient
    of task n's PPO loss on the decoder, at the update's start, on the first minibatch's worth
    of its samples (a sixteenth of the update's gradient work at the default sizes): which
    tasks shape the shared synergies while the others are not yet paid."""
    size = samples[0].obs.shape[0] // self.config.num_minibatches

    def norm(n: int):
      part = jax.tree.map(lambda x: x[:size], samples[n])
      grads = jax.grad(lambda p: ppo.task_loss(self.model, p, n, part, self.config, rho)[0])(params)
      return optax.tree.norm(grads["params"]["synergy_decoder"])

    norms = [norm(n) for n in range(len(samples))]
    total = sum(norms) + 1e-12
    return [x / total for x in norms]

  def _update(self, params, opt_state, samples: list[ppo.Samples], key, rho=None):
    """`update_epochs` passes of `num_minibatches` optimiser steps over every task's samples
    (`rho`: the residual's weight they were drawn with, with a residual; None: its cap)."""
    cfg = self.config
    if rho is None:
      rho = self.rho()  # still None without a residual
    grad_fn = jax.grad(ppo.loss, has_aux=True)

    def minibatch_step(carry, batch):
      params, opt_state = carry
      grads, (per_task, shared) = grad_fn(params, self.model, batch, cfg, rho)
      updates, opt_state = self.optimizer.update(grads, opt_state, params)
      shared = dict(shared, grad_norm=optax.tree.norm(grads), **_grad_norms_by_role(grads))
      return (optax.apply_updates(params, updates), opt_state), {"tasks": per_task, "shared": shared}

    def epoch(carry, key):
      keys = jax.random.split(key, len(samples))

      def shuffle(s, k):
        perm = jax.random.permutation(k, s.obs.shape[0])
        batches = jax.tree.map(
            lambda x: x[perm].reshape((cfg.num_minibatches, -1) + x.shape[1:]), s)
        # every minibatch split over the devices: each computes its share of the gradient
        return jax.lax.with_sharding_constraint(batches, devices_lib.batched(self.mesh, 1))

      batches = [shuffle(s, k) for s, k in zip(samples, keys)]
      return jax.lax.scan(minibatch_step, carry, batches)

    (params, opt_state), metrics = jax.lax.scan(
        epoch, (params, opt_state), jax.random.split(key, cfg.update_epochs))
    return params, opt_state, jax.tree.map(jnp.mean, metrics)

def gae(reward, value, bootstrap, done, truncation, config: TrainConfig):
  """(value targets, advantages) of a (T, B) rollout, by brax's compute_gae. An episode
  ends (`done`) by termination, with nothing after it, or by truncation at the time limit:
  the auto-reset has already put the next episode's first observation after that step, so
  brax leaves it out (advantage 0, target its own value)."""
  termination = done * (1 - truncation)
  return compute_gae(truncation=truncation, termination=termination, rewards=reward,
                     values=value, bootstrap_value=bootstrap, lambda_=config.gae_lambda,
                     discount=config.discount)


def bonus_scale(reward, bonus):
  """min(1, std(reward) / std(bonus)) over a task's rollout (bonus_cap): 1 where the task's
  own reward varies at least as much as the bonus, or where there is no bonus to cap; 0
  where the task pays nothing."""
  spread = jnp.std(bonus)
  return jnp.where(spread > 0, jnp.minimum(1.0, jnp.std(reward) / jnp.maximum(spread, 1e-12)), 1.0)


def _episode_metrics(traj, log_q, alpha2) -> dict[str, jax.Array]:
  """Per-task figures of one rollout: episodes that ended in it, and per-step means; `reward`
  is the env's reward, `bonus` the alpha2 log q(z|a) added to it (after reward_scaling)."""
  done = traj["done"]
  episodes = done.sum()
  per_episode = lambda x: (x * done).sum() / jnp.maximum(episodes, 1)
  m = traj["metrics"]
  # the first control step of the rollout at which some env was paid anything (unroll_length
  # if none): how long a sparse reward takes to be seen
  paid = (traj["reward"] != 0).any(axis=1)
  first_paid = jnp.where(paid.any(), jnp.argmax(paid), paid.shape[0])
  out = {"episodes": episodes, "return": per_episode(traj["episode_return"]),
         "success": per_episode(m["success"]), "diverged": m["diverged"].sum(),
         "reward": traj["reward"].mean(), "first_reward_t": first_paid, "log_q": log_q.mean(),
         "bonus": alpha2 * log_q.mean()}
  out.update({k: v.mean() for k, v in m.items() if k.startswith("reward/")})
  return out


def _finite_values(traj, last_obs) -> dict[str, jax.Array]:
  """Whether each of a task's own values in one rollout is finite: its observations (those
  the policy saw, and the last), each reward term (the reward, for an env that names none)
  and its success, so that the loop names a NaN where it starts, not in the loss it ends in.
  What it costs: set1-disco3-linear's step (4 tasks x 128 envs x 20 steps) gains 20 isfinite
  + reduce pairs over 0.32 M floats and returns 16 booleans, beside 10,240 MuJoCo steps
  (1.7 s on 2 CPU cores, docs/BENCHMARKS.md): by its size well under 0.1 % of the step."""
  finite = lambda *values: functools.reduce(jnp.logical_and, [jnp.isfinite(v).all() for v in values])
  m = traj["metrics"]
  terms = {k: v for k, v in m.items() if k.startswith("reward/")} or {"reward": traj["reward"]}
  return {"observation": finite(traj["obs"], last_obs), **{k: finite(v) for k, v in terms.items()},
          "success": finite(m["success"])}


def _grad_norms_by_role(grads) -> dict[str, jax.Array]:
  """The loss gradient's norm per part of the module (before clipping): the heads (policy
  means and stds), the value heads, the decoder, the discriminator."""
  parts: dict[str, list] = {}
  for name, sub in grads["params"].items():
    parts.setdefault(networks.role(name), []).append(sub)
  return {f"grad_norm/{part}": optax.tree.norm(subs) for part, subs in parts.items()}


def _with_start(params, decoder_params, own):
  """`params` with the decoder and the tasks' own synergies a run starts from, where given."""
  inner = dict(params["params"])
  for name, given, what, given_is in (
      ("synergy_decoder", decoder_params, "synergy decoder (identity decoder)", "decoder does"),
      ("own_synergies", own, "own synergies (own_synergies = 0)", "own synergies do")):
    if given is None:
      continue
    if name not in inner:
      raise BadInput(f"this model has no {what} to replace")
    want = jax.tree.map(jnp.shape, inner[name])
    got = jax.tree.map(jnp.shape, given)
    if want != got:
      raise BadInput(f"the given {given_is} not fit this model: {got} != {want}")
    inner[name] = given
  return {**params, "params": inner}

