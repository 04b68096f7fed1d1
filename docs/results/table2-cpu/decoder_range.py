# The exact script of the 2026-12-01 measurement in docs/TRAINING_NOTES.md ("Why Random-NL is so weak"):
# the spread of actions a randomly initialised linear / MLP decoder gives over bounded z.
import jax
import jax.numpy as jnp
import numpy as np

from discosyn_jax.agent.networks import DiscoSyn

for kind in ("linear", "mlp"):
  for b in (3, 4):
    net = DiscoSyn(obs_sizes=(8,), n_synergies=b, decoder=kind, squash_z=True)
    res = []
    for seed in range(3):
      p = net.init(jax.random.PRNGKey(seed), [jnp.zeros((1, 8))])
      z = jax.random.normal(jax.random.PRNGKey(99), (4000, b)) * 1.0
      zc = jnp.sign(jax.random.normal(jax.random.PRNGKey(7), (4000, b))) * 10.0  # tanh at the corners
      a, _ = net.apply(p, z, method=DiscoSyn.decode)
      ac, _ = net.apply(p, zc, method=DiscoSyn.decode)
      res.append((float(jnp.std(a, 0).mean()), float(jnp.abs(ac).max(0).mean())))
    print(kind, b, "per-actuator std of a for z~N(0,1): %s; mean over actuators of max|a| at the corners: %s" %
          (" ".join(f"{r[0]:.3f}" for r in res), " ".join(f"{r[1]:.3f}" for r in res)))
