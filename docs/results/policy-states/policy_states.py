"""Do the action directions a sensitivity reads at a solving policy's states lie where that
policy acts? Set #2's full-action PPO runs (their checkpoints) against PCA4 of their actions.

  python docs/results/policy-states/policy_states.py runs/paper [--set set2] [--b 6]

FOLDER holds `discosyn experiment`'s runs with checkpoints: ppo-<set>-seed<n> and the fit's
synergies-<set>-seed<n>/actions.npz (both trained again by `discosyn experiment table2`
where only the records are kept). For each seed, three b-direction spaces:

- the reward prior as the product makes it: the reward's response to pushes at a uniform
  random policy's states (physics_prior.py);
- the same response read at the trained PPO policy's own states (`acts`);
- the return's sensitivity along PPO's own rollouts, by Stein's identity: with the policy's
  standardised action noise eps and the normalised GAE advantage A,
  E[(A^2 - E A^2) eps eps^T] / 2 = E[grad A grad A^T] (in the noise's units, mapped back
  to actions), no pushes and no physics beyond the rollouts.

Each is pooled as the reward prior pools ("share"), then compared with PCA4 of the policy's
actions (overlap, chance max(p, q) / 20) and per task the share of its action variance it
holds. Output beside this file; docs/notes/2026-12-04-g-decoder-moves.md reads it.
"""

import argparse
import functools
import pathlib
import sys

import jax
import jax.numpy as jnp
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]
sys.path[:0] = [str(ROOT), str(ROOT / "experiments")]

import tasks  # noqa: E402
from discosyn_jax.agent.networks import DiscoSyn  # noqa: E402
from discosyn_jax.synergies import diagnostics, fitting, physics_prior  # noqa: E402
from discosyn_jax.training import loop  # noqa: E402
from discosyn_jax.training import train as train_lib  # noqa: E402
from solving_actions import variance_share  # noqa: E402

ROLLOUTS = 20  # train-step-sized rollouts per task for Stein's estimate (25,600 samples)


def return_sensitivity(trainer, state, n: int) -> np.ndarray:
  """(actions, actions): E[grad_a A grad_a A^T] along the policy's rollouts of task n."""
  cfg, model, params, norm = trainer.config, trainer.model, state.params, state.normalizers[n]

  @jax.jit
  def collect(env_state, key):
    env_state, traj = trainer._unroll(params, norm, env_state, key, n)
    obs = trainer.normalize(traj["obs"], norm)
    mean, log_std = model.apply(params, n, obs, method=DiscoSyn.policy)
    eps = ((traj["z"] - mean) / jnp.exp(log_std)).reshape(-1, mean.shape[-1])
    value = model.apply(params, n, obs, method=DiscoSyn.value)
    boot = model.apply(params, n, trainer.normalize(env_state.obs, norm), method=DiscoSyn.value)
    _, adv = train_lib.gae(traj["reward"] * cfg.reward_scaling, value, boot, traj["done"],
                           traj["truncation"], cfg)
    a2 = (((adv - adv.mean()) / (adv.std() + 1e-8)) ** 2).reshape(-1)
    return env_state, jnp.einsum("i,ia,ib->ab", a2 - a2.mean(), eps, eps) / (2 * a2.size), log_std[0, 0]

  env_state, total = state.env_states[n], 0.0
  for r in range(ROLLOUTS):
    env_state, m, log_std = collect(env_state, jax.random.PRNGKey(1000 + r))
    total = total + np.asarray(m, np.float64)
  scale = np.exp(-np.asarray(log_std, np.float64))  # grad_a = grad_eps / sigma
  m = scale[:, None] * (total / ROLLOUTS) * scale[None, :]
  m = (m + m.T) / 2
  values = np.linalg.eigvalsh(m)
  return m / values[values > 0].sum()


def seed_rows(folder: pathlib.Path, task_set: str, seed: int, b: int) -> list[str]:
  trainer, state = loop.load_trained(folder / f"ppo-{task_set}-seed{seed}", tasks.trainer,
                                     backend="native")
  with np.load(folder / f"synergies-{task_set}-seed{seed}" / "actions.npz") as data:
    actions = {t: data[t] for t in data.files}
  top = fitting.fit_pca(np.concatenate(list(actions.values())), 4)[0]["synergies"]["kernel"].T
  acts = [functools.partial(lambda obs, key, n: trainer.act(
      state.params, n, trainer.normalize(obs, state.normalizers[n]), key)[1], n=n)
      for n in range(len(trainer.envs))]
  spaces = {
      "reward prior, random states (the product's)":
          physics_prior.basis(trainer.envs, b, "reward", "share"),
      "reward prior, PPO's states": physics_prior.basis(trainer.envs, b, "reward", "share", acts),
      "return sensitivity, PPO's rollouts (Stein)": physics_prior.pool(
          [return_sensitivity(trainer, state, n) for n in range(len(trainer.envs))], b, "share"),
  }
  chance = diagnostics.chance_overlap(4, b, top.shape[0])
  return [f"| {seed} | {name} | {float(diagnostics.overlap(top, span)):.2f} (chance {chance:.2f}) | "
          + " | ".join(f"{variance_share(a, span):.2f}" for a in actions.values()) + " |"
          for name, span in spaces.items()]


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("folder", type=pathlib.Path)
  parser.add_argument("--set", default="set2")
  parser.add_argument("--b", type=int, default=6)
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
  args = parser.parse_args(argv)
  names = tasks.expand([args.set])
  print(f"| seed | space (b = {args.b}) | overlap with PCA4 of PPO's actions | "
        + " | ".join(names) + " (share of PPO's action variance held) |")
  print("|---" * (len(names) + 3) + "|")
  for seed in args.seeds:
    for row in seed_rows(args.folder, args.set, seed, args.b):
      print(row, flush=True)


if __name__ == "__main__":
  main()
