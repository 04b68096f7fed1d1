"""The losses of one minibatch and the optimiser: multi-task PPO over the joint action
(z, a), and the discriminator's maximum likelihood.

Where each term of the extended reward (paper, Eq. 2) goes:
  alpha2 log q(z|a)  -> the reward. It depends on the sampled (z, a): the agent is paid for
                        choosing actions whose z can be read back from a, and the return
                        carries that payment to earlier steps, as Eq. 2 asks.
  alpha1 H(pi(z|s,n)), alpha3 H(p(a|z)) -> the loss, as -alpha * entropy (H(p(a|z)): the
                        mean of the tasks' where each has its own noise, task_noise). Both
                        policies have state-independent stds, so each entropy is the same
                        at every state:
                        as a reward it would add a constant per step, which the
                        score-function gradient of PPO cannot differentiate (it only sees
                        rewards through log-probabilities of sampled actions) and which the
                        value baseline would absorb. Its gradient is that of
                        sum_t gamma^t alpha H = alpha H / (1 - gamma): the same direction as
                        the loss term, which PPO's entropy bonus follows (the usual practice;
                        the 1 / (1 - gamma) factor is absorbed into alpha).
The PPO probability ratio uses log pi(a, z | s, n) = log pi(z | s, n) + log p(a | z): each
sample goes through its own task's head and every sample through the one decoder. With a
residual (residual.py) p(a | z) is the decoder's Gaussian moved by rho times the residual's
mean, r integrated out; the residual's entropy is in no bonus.
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import jax.numpy as jnp
import optax
from flax import struct

from discosyn_jax.agent import networks, policy
from discosyn_jax.agent.networks import DiscoSyn, gaussian_entropy, gaussian_log_prob
from discosyn_jax.config import TrainConfig


@struct.dataclass
class Samples:
  """One task's samples, flattened over time and envs."""
  obs: jax.Array  # normalised observations
  z: jax.Array
  action: jax.Array  # the decoder's sample a (before the env clips it to [-1, 1])
  log_prob: jax.Array  # log pi(z|s,n) + log p(a|z) when sampled
  advantage: jax.Array
  target: jax.Array  # value target


def discriminator_log_prob(model: DiscoSyn, params, z, action):
  """log q(z | a): of z, or of the activation the decoder read (model.discriminated)."""
  mean, log_std = model.apply(params, action, method=DiscoSyn.discriminate)
  return gaussian_log_prob(model.apply(params, z, method=DiscoSyn.discriminated), mean, log_std)


def task_loss(model: DiscoSyn, params, task: int, s: Samples, config: TrainConfig, rho=None):
  log_prob, z_log_std, a_log_std = policy.log_prob(model, params, task, s.obs, s.z, s.action,
                                                   rho)
  ratio = jnp.exp(log_prob - s.log_prob)
  adv = (s.advantage - s.advantage.mean()) / (s.advantage.std() + 1e-8)
  clipped = jnp.clip(ratio, 1 - config.clip_epsilon, 1 + config.clip_epsilon)
  policy_loss = -jnp.minimum(ratio * adv, clipped * adv).mean()
  value = model.apply(params, task, s.obs, method=DiscoSyn.value)
  value_loss = 0.5 * jnp.mean((value - s.target) ** 2)
  entropy_z = gaussian_entropy(z_log_std).mean()
  loss = policy_loss + config.value_coef * value_loss - config.alpha1 * entropy_z
  metrics = dict(policy_loss=policy_loss, value_loss=value_loss, entropy_z=entropy_z,
                 approx_kl=jnp.mean(s.log_prob - log_prob),
                 clip_fraction=jnp.mean(jnp.abs(ratio - 1) > config.clip_epsilon))
  return loss, metrics, a_log_std


def loss(params, model: DiscoSyn, samples: Sequence[Samples], config: TrainConfig, rho=None):
  """The whole minibatch: the mean over tasks of their PPO losses, the decoder's entropy
  bonus, and (on disjoint parameters) the discriminator's negative log-likelihood. `rho`:
  the residual's weight the samples were drawn with, with a residual."""
  total, per_task, entropies_a = 0.0, [], []
  for task, s in enumerate(samples):
    task_total, metrics, a_log_std = task_loss(model, params, task, s, config, rho)
    total += task_total / len(samples)
    if a_log_std is not None and model.task_noise:
      metrics["entropy_a"] = gaussian_entropy(a_log_std).mean()
      entropies_a.append(metrics["entropy_a"])
    per_task.append(metrics)
  shared: dict[str, Any] = {}
  if a_log_std is not None:
    # each task's own noise: the bonus is the mean of the tasks' entropies
    entropy_a = (sum(entropies_a) / len(entropies_a) if model.task_noise
                 else gaussian_entropy(a_log_std).mean())
    total -= config.alpha3 * entropy_a
    shared["entropy_a"] = entropy_a
  if model.has_discriminator:
    z = jnp.concatenate([jax.lax.stop_gradient(s.z) for s in samples])
    a = jnp.concatenate([jax.lax.stop_gradient(s.action) for s in samples])
    disc_loss = -discriminator_log_prob(model, params, z, a).mean()
    total += disc_loss
    shared["discriminator_loss"] = disc_loss
  shared["loss"] = total
  return total, (per_task, shared)


def optimizer(config: TrainConfig) -> optax.GradientTransformation:
  """Adam per role: heads and decoder share one (the PPO objective), the discriminator has
  its own learning rate, a frozen decoder gets no updates at all. A decoder weight decay
  shrinks the decoder's weights (kernels, not biases or noise) as AdamW does, constant or
  falling linearly to nothing over `decoder_weight_decay_steps` train steps."""

  def transform(lr, decay=0.0):
    step = optax.adam(lr)  # without decay: the optimiser state of every earlier run
    if decay:
      if config.decoder_weight_decay_steps:
        updates_per_step = config.num_minibatches * config.update_epochs
        decay = optax.linear_schedule(decay, 0.0,
                                      config.decoder_weight_decay_steps * updates_per_step)
        decayed = optax.inject_hyperparams(optax.add_decayed_weights, static_args="mask")(
            decay, mask=_decoder_weights)
      else:
        decayed = optax.add_decayed_weights(decay, _decoder_weights)
      step = optax.chain(optax.scale_by_adam(), decayed, optax.scale_by_learning_rate(lr))
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), step)

  def labels(params):
    def label(name):
      kind = networks.role(name)
      if kind == "decoder" and config.freeze_decoder:
        return "frozen"
      return "discriminator" if kind == "discriminator" else "policy"  # one PPO objective
    return {"params": {name: jax.tree.map(lambda _: label(name), sub)
                       for name, sub in params["params"].items()}}

  return optax.multi_transform(
      {"policy": transform(config.learning_rate,
                           0.0 if config.freeze_decoder else config.decoder_weight_decay),
       "discriminator": transform(config.discriminator_learning_rate),
       "frozen": optax.set_to_zero()}, labels)


def _decoder_weights(params):
  """True at the decoder's kernels: what the decoder weight decay shrinks."""
  def weight(path, _):
    names = [str(getattr(k, "key", k)) for k in path]
    return "synergy_decoder" in names and names[-1] == "kernel"
  return jax.tree_util.tree_map_with_path(weight, params)
