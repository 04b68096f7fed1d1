"""ppo.loss and ppo.optimizer against independent references (tests/reference.py): SciPy
densities, the textbook clipped PPO loss in NumPy, finite differences of it, and Adam's
first step. The samples are drawn from the policy itself and their old log-probs are the
new ones perturbed a little, so the ratios sit around 1 as in training (some clipped)."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from discosyn_jax.agent import networks, policy, ppo
from discosyn_jax.config import TrainConfig
from tests import reference

OBS_SIZES = (3, 5)
HIDDEN = dict(policy_hidden=(16, 16), value_hidden=(16, 16), decoder_hidden=(16, 16),
              discriminator_hidden=(16, 16), squash_z=False, decoder_init="random")
ALPHAS = dict(alpha1=0.05, alpha2=0.1, alpha3=0.07)
NO_ENTROPY = dict(alpha1=0.0, alpha3=0.0)

# jitted once per (model, config), shared by the tests: eager Flax is slow
value_and_grad = jax.jit(jax.value_and_grad(ppo.loss, has_aux=True), static_argnums=(1, 3))


def config_for(decoder, **changes):
  b = 20 if decoder == "identity" else 3
  alphas = dict(ALPHAS, alpha2=0.0, alpha3=0.0) if decoder == "identity" else ALPHAS
  return TrainConfig(tasks=("a", "b"), decoder=decoder, n_synergies=b,
                     **{**HIDDEN, **alphas, **changes}).validate()


@functools.cache
def setup(decoder, n=64):
  """(model, params, samples): random params in the module's layout (stds differ per
  dimension), samples drawn from the policy at those params."""
  model = networks.build(config_for(decoder), OBS_SIZES, action_size=20)
  shapes = jax.eval_shape(model.init, jax.random.PRNGKey(0),
                          [jnp.zeros((1, s)) for s in OBS_SIZES])
  rng = np.random.default_rng(0)

  def draw(path, leaf):
    x = rng.normal(size=leaf.shape)
    if path[-1].key == "log_std":
      x = np.log(0.4) + 0.2 * x
    elif path[-1].key == "kernel":
      x = x / np.sqrt(leaf.shape[0])
    else:
      x = 0.2 * x
    return jnp.asarray(x, jnp.float32)

  params = jax.tree_util.tree_map_with_path(draw, shapes)
  p = reference.as_numpy(params["params"])
  samples = []
  for task, size in enumerate(OBS_SIZES):
    obs = rng.normal(size=(n, size))
    z_mean, z_log_std = reference.gaussian_head(p[f"heads_{task}"], obs)
    z = z_mean + np.exp(z_log_std) * rng.normal(size=z_mean.shape)
    a_mean, a_log_std = reference.decode(p, decoder, z)
    a = a_mean if a_log_std is None else a_mean + np.exp(a_log_std) * rng.normal(size=a_mean.shape)
    new = reference.joint_log_prob(p, decoder, task, obs, z, a)
    samples.append(ppo.Samples(
        obs=obs.astype(np.float32), z=z.astype(np.float32), action=a.astype(np.float32),
        log_prob=(new + 0.15 * rng.normal(size=n)).astype(np.float32),
        advantage=rng.normal(size=n).astype(np.float32),
        target=rng.normal(size=n).astype(np.float32)))
  return model, params, tuple(samples)


def numpy_samples(samples):
  return [jax.tree.map(lambda x: np.asarray(x, np.float64), s) for s in samples]


def test_gaussian_log_prob_and_entropy_are_scipys():
  rng = np.random.default_rng(0)
  x, mean, log_std = rng.normal(size=(3, 7, 5))
  np.testing.assert_allclose(networks.gaussian_log_prob(x, mean, log_std),
                             reference.log_prob(x, mean, log_std), rtol=1e-5)
  np.testing.assert_allclose(networks.gaussian_entropy(log_std), reference.entropy(log_std),
                             rtol=1e-5)


@pytest.mark.parametrize("decoder", ["identity", "linear", "mlp"])
def test_joint_log_prob_is_head_plus_decoder(decoder):
  model, params, samples = setup(decoder)
  got = jax.jit(lambda params: [policy.log_prob(model, params, task, s.obs, s.z, s.action)[0]
                                for task, s in enumerate(samples)])(params)
  p = reference.as_numpy(params["params"])
  for task, s in enumerate(numpy_samples(samples)):
    want = reference.joint_log_prob(p, decoder, task, s.obs, s.z, s.action)
    np.testing.assert_allclose(got[task], want, rtol=1e-5, atol=1e-4)


# the configs whose gradients other tests need (one compilation each); the identity
# decoder's has the head entropy, the linear decoder's every term
@pytest.mark.parametrize("decoder,alphas", [("identity", {}), ("linear", {}), ("mlp", NO_ENTROPY)])
def test_loss_is_the_textbook_clipped_ppo_loss(decoder, alphas):
  model, params, samples = setup(decoder)
  config = config_for(decoder, **alphas)
  (total, (per_task, _)), _ = value_and_grad(params, model, samples, config)
  want = reference.ppo_loss(reference.as_numpy(params["params"]), decoder,
                            numpy_samples(samples), config)
  np.testing.assert_allclose(total, want, rtol=1e-5, atol=1e-5)
  # the ratios are realistic: near 1, with both branches of the clip in use
  for m in per_task:
    assert 0.05 < float(m["clip_fraction"]) < 0.6
    assert abs(float(m["approx_kl"])) < 0.1


def test_entropy_bonuses_enter_with_their_sign_and_scale():
  """alpha1 and alpha3 lower the loss by alpha times the mean head entropy / the decoder
  entropy, and push the stds up (a descent step raises log_std)."""
  model, params, samples = setup("linear")
  p = reference.as_numpy(params["params"])
  h_z = np.mean([reference.entropy(p[f"heads_{n}"]["log_std"]) for n in range(2)])
  h_a = reference.entropy(p["synergy_decoder"]["log_std"])
  (with_bonus, _), g = value_and_grad(params, model, samples, config_for("linear"))
  (without, _), g0 = value_and_grad(params, model, samples, config_for("linear", **NO_ENTROPY))
  a1, a3 = ALPHAS["alpha1"], ALPHAS["alpha3"]
  assert float(with_bonus - without) == pytest.approx(-a1 * h_z - a3 * h_a, rel=1e-4)
  # d/dlog_std of -alpha3 H(p(a|z)) is -alpha3 in every action dimension; of -alpha1
  # H(pi(z|s,n)), averaged over the two tasks, -alpha1 / 2 in every head dimension
  g, g0 = g["params"], g0["params"]
  np.testing.assert_allclose(g["synergy_decoder"]["log_std"] - g0["synergy_decoder"]["log_std"],
                             -a3, rtol=1e-4)
  for head in ("heads_0", "heads_1"):
    np.testing.assert_allclose(g[head]["log_std"] - g0[head]["log_std"], -a1 / 2, rtol=1e-4)


def finite_differences(p, part, decoder, samples, config, grad, per_leaf=24):
  """(jax's gradient, central differences of the NumPy loss) at up to `per_leaf` random
  entries of every leaf of params[`part`]."""
  ref_samples = numpy_samples(samples)
  leaves, treedef = jax.tree.flatten(p[part])
  got_leaves = jax.tree.leaves(grad["params"][part])
  rng = np.random.default_rng(1)
  got, want = [], []
  for i, leaf in enumerate(leaves):
    for j in rng.choice(leaf.size, size=min(leaf.size, per_leaf), replace=False):
      index = np.unravel_index(j, leaf.shape)
      diffs = []
      for sign in (1, -1):
        moved = [x.copy() for x in leaves]
        moved[i][index] += sign * 1e-6
        diffs.append(reference.ppo_loss({**p, part: jax.tree.unflatten(treedef, moved)},
                                        decoder, ref_samples, config))
      want.append((diffs[0] - diffs[1]) / 2e-6)
      got.append(float(np.asarray(got_leaves[i])[index]))
  return np.array(got), np.array(want)


@pytest.mark.parametrize("decoder", ["linear", "mlp"])
def test_decoder_gradient_is_the_surrogates(decoder):
  """The decoder's gradient with no entropy bonus (the PPO term alone) matches central
  differences of the NumPy loss in float64, and is far from negligible at these ratios."""
  model, params, samples = setup(decoder)
  config = config_for(decoder, **NO_ENTROPY)
  _, grad = value_and_grad(params, model, samples, config)
  got, want = finite_differences(reference.as_numpy(params["params"]), "synergy_decoder",
                                 decoder, samples, config, grad)
  scale = np.abs(want).max()
  assert scale > 1e-2, scale
  np.testing.assert_allclose(got, want, rtol=1e-3, atol=1e-3 * scale)


def test_discriminator_is_fitted_by_its_own_likelihood_and_optimiser():
  model, params, samples = setup("linear")
  (_, _), grad = value_and_grad(params, model, samples, config_for("linear"))
  # its gradient is the NLL's alone (the PPO terms do not reach it): central differences
  # of the NumPy loss, whose discriminator part is the NLL
  p = reference.as_numpy(params["params"])
  np.testing.assert_allclose(*finite_differences(p, "discriminator", "linear", samples,
                                                 config_for("linear"), grad), rtol=1e-3)

  # Adam's first step moves every parameter by about its group's learning rate
  config = config_for("linear", learning_rate=1e-2, discriminator_learning_rate=1e-4)
  opt = ppo.optimizer(config)
  update = jax.jit(opt.update)
  updates, _ = update(grad, opt.init(params), params)
  step = {name: np.concatenate([np.abs(np.ravel(x)) for x in jax.tree.leaves(sub)])
          for name, sub in updates["params"].items()}
  assert np.median(step["discriminator"]) == pytest.approx(1e-4, rel=1e-2)
  for name in ("heads_0", "heads_1", "values_0", "synergy_decoder"):
    assert np.median(step[name]) == pytest.approx(1e-2, rel=1e-2), name

  # each group is clipped by its own gradient norm: a huge discriminator gradient leaves
  # the policy's updates alone, over several steps
  def policy_updates(disc_scales):
    state, out = opt.init(params), []
    for k, scale in enumerate(disc_scales):
      g = jax.tree.map(lambda x: (k + 1) * x, grad["params"])
      g["discriminator"] = jax.tree.map(lambda x: scale * x, g["discriminator"])
      u, state = update({"params": g}, state, params)
      out.append({n: v for n, v in u["params"].items() if n != "discriminator"})
    return out

  jax.tree.map(np.testing.assert_array_equal, policy_updates((1.0, 1.0, 1.0)),
               policy_updates((1e6, 1.0, 1e3)))

