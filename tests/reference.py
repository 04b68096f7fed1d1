"""Independent references for the objective tests: the DiscoSyn module's forward pass in
NumPy (float64) from its Flax parameters, Gaussian densities from SciPy, the textbook
clipped PPO loss, and GAE written from its definition. Nothing here calls discosyn_jax."""

import numpy as np
from scipy import stats


def as_numpy(tree):
  """A parameter tree as nested dicts of float64 arrays."""
  if isinstance(tree, dict):
    return {k: as_numpy(v) for k, v in tree.items()}
  return np.asarray(tree, np.float64)


def mlp(p, x):
  """flax Dense layers Dense_0..Dense_k with swish between them."""
  n = len(p)
  for i in range(n):
    x = x @ p[f"Dense_{i}"]["kernel"] + p[f"Dense_{i}"]["bias"]
    if i < n - 1:
      x = x / (1.0 + np.exp(-x))  # swish
  return x


def gaussian_head(p, x):
  mean = mlp(p["MLP_0"], x)
  return mean, np.broadcast_to(p["log_std"], mean.shape)


def decode(p, decoder, z):
  """(mean, log_std) of p(a|z); log_std None for the identity decoder."""
  if decoder == "identity":
    return z, None
  if decoder == "linear":
    mean = z @ p["synergy_decoder"]["synergies"]["kernel"] + p["synergy_decoder"]["synergies"]["bias"]
    return mean, np.broadcast_to(p["synergy_decoder"]["log_std"], mean.shape)
  return gaussian_head(p["synergy_decoder"], z)


def log_prob(x, mean, log_std):
  return stats.norm.logpdf(x, mean, np.exp(log_std)).sum(-1)


def entropy(log_std):
  return stats.norm.entropy(scale=np.exp(log_std)).sum(-1)


def joint_log_prob(p, decoder, task, obs, z, a):
  z_mean, z_log_std = gaussian_head(p[f"heads_{task}"], obs)
  lp = log_prob(z, z_mean, z_log_std)
  a_mean, a_log_std = decode(p, decoder, z)
  return lp if a_log_std is None else lp + log_prob(a, a_mean, a_log_std)


def value(p, task, obs):
  return mlp(p[f"values_{task}"], obs)[..., 0]


def ppo_loss(p, decoder, samples, config):
  """ppo.loss written out: per task the clipped surrogate on standardised advantages, the
  value loss and -alpha1 H(pi(z|s)), averaged over tasks; -alpha3 H(p(a|z)); the
  discriminator's negative log-likelihood over all samples. `p` is params["params"]."""
  eps = config.clip_epsilon
  total = 0.0
  for task, s in enumerate(samples):
    ratio = np.exp(joint_log_prob(p, decoder, task, s.obs, s.z, s.action) - s.log_prob)
    adv = (s.advantage - s.advantage.mean()) / (s.advantage.std() + 1e-8)
    surrogate = np.minimum(ratio * adv, np.clip(ratio, 1 - eps, 1 + eps) * adv).mean()
    value_loss = 0.5 * np.mean((value(p, task, s.obs) - s.target) ** 2)
    _, z_log_std = gaussian_head(p[f"heads_{task}"], s.obs)
    total += (-surrogate + config.value_coef * value_loss
              - config.alpha1 * entropy(z_log_std).mean()) / len(samples)
  if decoder != "identity":
    z = np.concatenate([s.z for s in samples])
    a = np.concatenate([s.action for s in samples])
    _, a_log_std = decode(p, decoder, z)
    total -= config.alpha3 * entropy(a_log_std).mean()
    q_mean, q_log_std = gaussian_head(p["discriminator"], a)
    total -= log_prob(z, q_mean, q_log_std).mean()
  return total


def gae(reward, value, bootstrap, termination, truncation, discount, lam):
  """(value targets, advantages) of a (T, B) rollout of auto-reset envs, as Brax defines
  them: the target is v_t + sum_k (gamma lambda)^k delta_{t+k} over the rest of the
  episode, the advantage r_t + gamma target_{t+1} - v_t (IMPALA's form; the textbook GAE
  advantage at lambda = 1). A terminated step has nothing after it. A truncated step
  (time limit) is followed in the rollout by the next episode's first state, so it is
  left out (advantage 0, target its own value) and the step before it bootstraps from
  its value."""
  T = reward.shape[0]
  next_value = np.concatenate([value[1:], bootstrap[None]])
  target, advantage = np.zeros_like(reward), np.zeros_like(reward)
  acc = np.zeros_like(bootstrap)
  for t in reversed(range(T)):
    keep = 1.0 - truncation[t]
    cont = 1.0 - termination[t]
    delta = reward[t] + discount * cont * next_value[t] - value[t]
    acc = keep * (delta + discount * lam * cont * acc)
    target[t] = value[t] + acc
  next_target = np.concatenate([target[1:], bootstrap[None]])
  advantage = (1.0 - truncation) * (reward + discount * (1.0 - termination) * next_target - value)
  return target, advantage
