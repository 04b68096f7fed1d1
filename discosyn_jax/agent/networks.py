"""The one Flax module: per-task policy and value heads, the shared synergy decoder, and
the discriminator.

  pi(z | s, n) = N(mu_n(s), sigma_n)        a head per task (observation sizes differ)
  V_n(s)                                     a value head per task
  p(a | z)     = N(D(z), sigma_phi)          shared by all tasks; D linear (b x 20) or an MLP;
                                             its mean D(z) is the action at evaluation; with
                                             `task_noise` sigma_phi is each task's own
  q(z | a)     = N(m(a), sigma_psi)          the discriminator
  a = D(z) + W_n z_own                       with `own_synergies` k: head n picks b + k
                                             activations, the last k through task n's own
                                             directions W_n (20 x k), which no other task
                                             acts through; q reads back all b + k
  pi(r | s, n) = N(tanh(m_n(s)), sigma_r)    with `residual` on: a full-action residual per
                                             task, added to the action with a scheduled
                                             weight (residual.py says what it does to Eq. 2)

All standard deviations are learned and state-independent. The identity decoder (full-action
PPO) has no parameters and no noise: a = z. With `decoder_noise` off the decoder acts with
its mean during training too (the sequential baselines' fixed PCA / autoencoder spaces).

The discriminator reads the action only, as in the paper's Eq. 1. The entropy bound
H[pi(a|s,n)] >= H[pi(z|s,n)] + H[p(a|z)] + E log q(z|.) holds for any q; conditioning q on
(a, s, n) would tighten it, but would also let q tell the z's apart by the state and task
instead of by the posture, taking away the pressure on the shared decoder to give each z a
posture of its own. One q over all tasks keeps that pressure, and needs no per-task inputs.
"""

from __future__ import annotations

import math
import sys
from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from discosyn_jax import decoders
from discosyn_jax.config import TrainConfig

LOG_2PI = math.log(2 * math.pi)


def gaussian_log_prob(x: jax.Array, mean: jax.Array, log_std: jax.Array) -> jax.Array:
  """log N(x; mean, exp(log_std)^2), summed over the last axis."""
  z = (x - mean) * jnp.exp(-log_std)
  return jnp.sum(-0.5 * z * z - log_std - 0.5 * LOG_2PI, axis=-1)


def gaussian_entropy(log_std: jax.Array) -> jax.Array:
  return jnp.sum(log_std + 0.5 * (1.0 + LOG_2PI), axis=-1)


class MLP(nn.Module):
  hidden: Sequence[int]
  out: int
  out_scale: float = 1.0  # a small last layer starts the output near zero

  @nn.compact
  def __call__(self, x):
    for width in self.hidden:
      x = nn.swish(nn.Dense(width)(x))
    return nn.Dense(self.out, kernel_init=nn.initializers.variance_scaling(
        self.out_scale, "fan_in", "truncated_normal"))(x)


class GaussianHead(nn.Module):
  """An MLP mean and a learned state-independent log std."""
  hidden: Sequence[int]
  out: int
  init_std: float
  out_scale: float = 0.01

  @nn.compact
  def __call__(self, x):
    mean = MLP(self.hidden, self.out, self.out_scale)(x)
    log_std = self.param("log_std", nn.initializers.constant(math.log(self.init_std)), (self.out,))
    return mean, jnp.broadcast_to(log_std, mean.shape)


class LinearDecoder(nn.Module):
  """a = W z (+ c): the columns of W are the synergies."""
  out: int
  bias: bool
  init_std: float

  @nn.compact
  def __call__(self, z):
    mean = nn.Dense(self.out, use_bias=self.bias, name="synergies")(z)
    log_std = self.param("log_std", nn.initializers.constant(math.log(self.init_std)), (self.out,))
    return mean, jnp.broadcast_to(log_std, mean.shape)


class DiscoSyn(nn.Module):
  obs_sizes: tuple[int, ...]  # one per task
  n_synergies: int
  action_size: int = 20
  decoder: str = "linear"
  decoder_bias: bool = True
  decoder_noise: bool = True
  squash_z: bool = False
  discriminator_target: str = "z"  # config.DISCRIMINATOR_TARGETS
  task_posture: bool = False  # a learned posture per task, added to the decoder's mean
  residual: bool = False  # a full-action residual head per task (residual.py)
  task_noise: bool = False  # each task's own std of p(a | z) around the shared mean
  own_synergies: int = 0  # k directions of each task's own beside the shared b
  policy_hidden: tuple[int, ...] = (128, 128)
  value_hidden: tuple[int, ...] = (128, 128)
  decoder_hidden: tuple[int, ...] = (128, 128)
  discriminator_hidden: tuple[int, ...] = (128, 128)
  init_z_std: float = 1.0
  init_action_std: float = 0.3
  init_residual_std: float = 0.05

  def setup(self):
    b = self.z_size
    self.heads = [GaussianHead(self.policy_hidden, b, self.init_z_std)
                  for _ in self.obs_sizes]
    self.values = [MLP(self.value_hidden, 1) for _ in self.obs_sizes]
    if not self.kind.full_action:  # the kind builds from this module's layers
      self.synergy_decoder = self.kind.build(self, sys.modules[__name__])
    if self.has_discriminator:
      self.discriminator = GaussianHead(self.discriminator_hidden, b, 1.0, out_scale=1.0)
    if self.task_posture:
      # each task's own resting posture: the shared synergies span the motions around it,
      # not the differences between the tasks' postures
      self.postures = self.param("postures", nn.initializers.zeros,
                                 (len(self.obs_sizes), self.action_size))
    if self.task_noise:
      # what the decoder's own log std would be, one row per task
      self.task_log_stds = self.param(
          "task_log_stds", nn.initializers.constant(math.log(self.init_action_std)),
          (len(self.obs_sizes), self.action_size))
    if self.own_synergies:
      # task n's own directions, (k, actions) each, scaled as a linear decoder's columns
      # start (lecun normal); a run replaces them with its start (synergies/start.py)
      self.own_directions = self.param(
          "own_synergies", nn.initializers.lecun_normal(in_axis=-2, out_axis=-1, batch_axis=(0,)),
          (len(self.obs_sizes), self.own_synergies, self.action_size))
    if self.residual:  # beside the z heads, not sharing their layers: z's are as without it
      self.residuals = [GaussianHead(self.policy_hidden, self.action_size, self.init_residual_std)
                        for _ in self.obs_sizes]

  @property
  def z_size(self) -> int:
    """What a head picks: the b shared activations, then the task's own k."""
    return self.n_synergies + self.own_synergies

  @property
  def kind(self) -> decoders.DecoderKind:
    return decoders.kind(self.decoder)

  @property
  def has_discriminator(self) -> bool:
    return not self.kind.full_action

  def policy(self, task: int, obs):
    """(mean, log_std) of pi(z | s, task)."""
    return self.heads[task](obs)

  def residual_policy(self, task: int, obs):
    """(mean, log_std) of pi(r | s, task): the mean bounded to [-1, 1], so that the weight's
    cap bounds what the residual carries."""
    mean, log_std = self.residuals[task](obs)
    return jnp.tanh(mean), log_std

  def value(self, task: int, obs):
    return self.values[task](obs)[..., 0]

  def decode(self, z):
    """(mean, log_std) of p(a | z) for the shared part of z (its first b); log_std is None
    for a noiseless decoder (identity, or `decoder_noise` off)."""
    if self.kind.full_action:
      return z, None
    mean, log_std = self.synergy_decoder(self.activation(z[..., :self.n_synergies]))
    return mean, log_std if self.decoder_noise else None

  def own_part(self, task: int, z):
    """What task's own synergies add to the action: W_n read at z's last k activations."""
    return self.activation(z[..., self.n_synergies:]) @ self.own_directions[task]

  def act(self, task: int, z):
    """(mean, log_std) of task's action given z: the decoder's, plus the task's own
    synergies' part, moved by the task's posture, with the task's own noise where each has
    its own."""
    mean, log_std = self.decode(z)
    if self.own_synergies:
      mean = mean + self.own_part(task, z)
    if self.task_noise and log_std is not None:
      log_std = jnp.broadcast_to(self.task_log_stds[task], mean.shape)
    return (mean + self.postures[task] if self.task_posture else mean), log_std

  def activation(self, z):
    """What the decoder reads of z: tanh(z) where z is bounded."""
    return jnp.tanh(z) if self.squash_z else z

  def discriminated(self, z):
    """What q(.|a) reads back from the action z was decoded into."""
    return self.activation(z) if self.discriminator_target == "activation" else z

  def discriminate(self, a):
    """(mean, log_std) of q(z | a)."""
    return self.discriminator(a)

  def __call__(self, observations: Sequence[jax.Array]):
    """Touch every part once (for init): observations is one batch per task."""
    out = []
    for n, obs in enumerate(observations):
      z, _ = self.policy(n, obs)
      a, _ = self.act(n, z)
      out.append((z, self.value(n, obs), a))
      if self.residual:
        self.residual_policy(n, obs)
      if self.has_discriminator:
        self.discriminate(a)
    return out


def build(config, obs_sizes: Sequence[int], action_size: int) -> DiscoSyn:
  """The module a TrainConfig describes, for tasks with these observation sizes."""
  b = action_size if config.kind.full_action else config.n_synergies
  return DiscoSyn(
      obs_sizes=tuple(int(s) for s in obs_sizes), n_synergies=b, action_size=action_size,
      decoder=config.decoder, decoder_bias=config.decoder_bias, decoder_noise=config.decoder_noise,
      squash_z=config.squash_z, discriminator_target=config.discriminator_target,
      task_posture=config.task_posture, residual=bool(config.residual),
      task_noise=config.task_noise, own_synergies=config.own_synergies,
      policy_hidden=tuple(config.policy_hidden), value_hidden=tuple(config.value_hidden),
      decoder_hidden=tuple(config.decoder_hidden),
      discriminator_hidden=tuple(config.discriminator_hidden),
      init_z_std=config.init_z_std, init_action_std=config.init_action_std,
      init_residual_std=config.init_residual_std)


# Top-level parameter collections by role: the optimiser labels them (ppo.optimizer), the
# gradient norms are logged per role (trainer.py).
def role(name: str) -> str:
  # a posture, a residual head, a task's own noise and own synergies are their task's
  if name.startswith(("heads_", "residuals_")) or name in ("postures", "task_log_stds",
                                                            "own_synergies"):
    return "heads"
  if name.startswith("values_"):
    return "values"
  if name == "synergy_decoder":
    return "decoder"
  if name == "discriminator":
    return "discriminator"
  raise ValueError(f"parameter collection {name!r} has no role")


def floor_head_std(params, held: jax.Array, floor: float):
  """`params` with the z log std of each head whose task is `held` (bool per task) raised to
  at least log(floor): a projection after the update, so that the std the next rollout
  samples with, and the one the optimiser goes on from, are the same."""
  inner = dict(params["params"])
  for n in range(held.shape[0]):
    head = dict(inner[f"heads_{n}"])
    head["log_std"] = jnp.where(held[n], jnp.maximum(head["log_std"], math.log(floor)),
                                head["log_std"])
    inner[f"heads_{n}"] = head
  return {**params, "params": inner}


def split_seed_key(key, n_tasks: int):
  """(the state's rng, the parameters' key, a reset key per task): what `Trainer.init` draws
  from the key of its seed."""
  key, init_key, *env_keys = jax.random.split(key, 2 + n_tasks)
  return key, init_key, env_keys


def random_decoder(config: TrainConfig, action_size: int):
  """The random decoder parameters a run of `config` starts from, without building its envs:
  the decoder's initialisation draws from its own path in the module, whatever the
  observation sizes of the heads (tests/test_discovery.py checks it)."""
  _, params = initial_params(config, (1,) * len(config.tasks), action_size)
  return params["params"]["synergy_decoder"]


def initial_params(config: TrainConfig, obs_sizes: Sequence[int], action_size: int):
  """(the module, the parameters a run of `config` starts from) for tasks with these
  observation sizes, without building envs: what `Trainer.init` draws for the networks."""
  model = build(config, obs_sizes, action_size)
  _, init_key, _ = split_seed_key(jax.random.PRNGKey(config.seed), len(config.tasks))
  return model, model.init(init_key, [jnp.zeros((1, s)) for s in obs_sizes])
