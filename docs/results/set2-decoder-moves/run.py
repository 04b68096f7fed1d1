"""Two tries at a set-#2 decoder that moves further from its start (docs/notes/2026-12-04-g-decoder-moves.md,
"Set #2: what the one-step reward cannot see"), each Table II's config of seed S with one
change, trained from Python:

  python docs/results/set2-decoder-moves/run.py {lr5,mlp-reward,task-share} SEED OUT

lr5: DiscoSyn6-L-reward (the default) with the decoder on its own Adam at 5x the heads'
learning rate (its gradient clipped apart from theirs). mlp-reward: DiscoSyn6-NL (the
paper's MLP decoder) started in the reward prior's subspace: the seed's random MLP with its
output layer projected onto span(prior) and scaled back to its norm, so that every posture
it starts from lies in that span and the MLP is free to leave it. task-share: the default
with each task's gradient on the decoder's synergies (W and c) scaled to the same norm
(1 / tasks) before the tasks' are summed, so that no task's outweighs another's on the
one decoder. The base configs are the
committed records' (docs/results/paper/); the change is not in them, so this folder keeps
no config.json beside the logs.
"""

import pathlib
import sys

import jax
import numpy as np
import optax

import tasks
from discosyn_jax import config as config_lib
from discosyn_jax.agent import networks, ppo
from discosyn_jax.synergies import physics_prior
from discosyn_jax.training import loop

RECORDS = pathlib.Path(__file__).resolve().parents[1] / "paper"
BASE = {"lr5": "discosyn6-l-reward", "mlp-reward": "discosyn6-nl",
        "task-share": "discosyn6-l-reward"}


def decoder_at_5x(config):
  """ppo.optimizer's Adam with the decoder on a learning rate of its own."""
  def transform(lr):
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(lr))

  def labels(params):
    def label(name):
      role = networks.role(name)
      return role if role in ("decoder", "discriminator") else "policy"
    return {"params": {name: jax.tree.map(lambda _: label(name), sub)
                       for name, sub in params["params"].items()}}

  return optax.multi_transform({"policy": transform(config.learning_rate),
                                "decoder": transform(5 * config.learning_rate),
                                "discriminator": transform(config.discriminator_learning_rate)},
                               labels)


def mlp_in_prior(trainer):
  """The seed's random MLP decoder, its output layer projected onto the reward prior."""
  config = trainer.config
  prior = physics_prior.basis(trainer.envs, config.n_synergies, "reward", "share")
  params = jax.tree.map(np.asarray, networks.random_decoder(config, trainer.action_size))
  layer = params["MLP_0"][sorted(params["MLP_0"])[-1]]
  projected = layer["kernel"] @ prior @ prior.T
  layer["kernel"] = (projected * np.linalg.norm(layer["kernel"])
                     / np.linalg.norm(projected)).astype(np.float32)
  return params


@jax.custom_vjp
def _unit_gradient(tree, scale):
  return tree


def _unit_forward(tree, scale):
  return tree, scale


def _unit_backward(scale, grads):
  norm = optax.tree.norm(grads)
  return jax.tree.map(lambda g: g * scale / (norm + 1e-8), grads), None


_unit_gradient.defvjp(_unit_forward, _unit_backward)
_task_loss = ppo.task_loss


def task_loss_sharing_the_decoder(model, params, task, s, config):
  """ppo.task_loss, its gradient on the decoder's synergies scaled to norm 1 / tasks."""
  decoder = dict(params["params"]["synergy_decoder"])
  decoder["synergies"] = _unit_gradient(decoder["synergies"], 1.0 / len(config.tasks))
  shared = {**params, "params": {**params["params"], "synergy_decoder": decoder}}
  return _task_loss(model, shared, task, s, config)


if __name__ == "__main__":
  variant, seed, out = sys.argv[1], int(sys.argv[2]), pathlib.Path(sys.argv[3])
  config = config_lib.load(RECORDS / f"{BASE[variant]}-set2-seed{seed}" / "config.json")
  if variant == "lr5":
    ppo.optimizer = decoder_at_5x
  elif variant == "task-share":
    ppo.task_loss = task_loss_sharing_the_decoder
  else:
    loop.starting_decoder = mlp_in_prior
  loop.train(config, out, make_trainer=tasks.trainer, progress=False)
