"""What exploration finds before any learning, on set #2's dice and weight pull: 64 episodes
of each exploration distribution from the reward prior's start (b = 6 and 10, the seed-0
decoder): z ~ N(0, s^2) each step, bounded (tanh) or free, decoded with the decoder's noise
(0.3); and full-action PPO's N(0, 0.5^2). Per task: the share of episodes with a success at
any step, and with each reward term positive at any step. Run from the repository's root:

  python docs/results/q-activation/explore.py        # ~1 min on 2 cores
"""

import dataclasses

import discosyn_jax

discosyn_jax.setup_jax()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import tasks.registry  # noqa: E402
from discosyn_jax import config as config_lib  # noqa: E402
from discosyn_jax.agent import networks  # noqa: E402
from discosyn_jax.env import rollouts  # noqa: E402
from discosyn_jax.synergies import physics_prior  # noqa: E402

EPISODES, NOISE = 64, 0.3
CONFIG = config_lib.load("docs/results/paper/discosyn6-l-reward-set2-seed0/config.json")


def found(env, policy) -> str:
  _, states = rollouts.run_episode(env, jax.random.split(jax.random.PRNGKey(1), EPISODES), policy)
  terms = {k.split("/")[1]: float((np.asarray(v) > 0).any(0).mean())
           for k, v in states.metrics.items() if k.startswith("reward/") and k != "reward/bias"}
  return (f"success {float(np.asarray(states.metrics['success']).max(0).mean()):.2f}, > 0: "
          + " ".join(f"{k} {v:.2f}" for k, v in terms.items()))


def synergy_policy(kernel, bias, squash, spread):
  def policy(t, key, n):
    k_z, k_a = jax.random.split(key)
    z = spread * jax.random.normal(k_z, (n, kernel.shape[0]))
    mean = (jnp.tanh(z) if squash else z) @ kernel + bias
    return jnp.clip(mean + NOISE * jax.random.normal(k_a, mean.shape), -1, 1)
  return policy


def ppo_policy(t, key, n):
  return jnp.clip(0.5 * jax.random.normal(key, (n, 20)), -1, 1)


if __name__ == "__main__":
  envs = dict(zip(CONFIG.tasks, tasks.registry.make_envs(CONFIG)))
  shown = {name: envs[name] for name in ("dice", "weight_pull")}
  for b in (6, 10):
    config = dataclasses.replace(CONFIG, n_synergies=b)
    prior = physics_prior.basis(list(envs.values()), b, "reward", "share")
    decoder = physics_prior.start(networks.random_decoder(config, 20), prior)["synergies"]
    kernel, bias = jnp.asarray(decoder["kernel"]), jnp.asarray(decoder["bias"])
    for label, squash, spread in (("bounded, s 1", True, 1.0), ("bounded, s 2", True, 2.0),
                                  ("bounded, s 3", True, 3.0), ("free, s 1", False, 1.0)):
      policy = synergy_policy(kernel, bias, squash, spread)
      print(f"b = {b}, z {label}: " + " | ".join(f"{name}: {found(env, policy)}"
                                                 for name, env in shown.items()), flush=True)
  print("full-action PPO, s 0.5: " + " | ".join(f"{name}: {found(env, ppo_policy)}"
                                               for name, env in shown.items()))
