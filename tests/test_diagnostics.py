"""The decoder-movement diagnostics: a frozen decoder does not move, a trained one does, and
the principal-angle cosines see rotations, not rescalings."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from discosyn_jax.agent import networks
from discosyn_jax.config import TrainConfig
from discosyn_jax.synergies import diagnostics


def model_and_params(decoder: str, seed: int = 0):
  config = TrainConfig(squash_z=False, decoder_init="random", tasks=("a",), n_synergies=3, decoder=decoder)
  model = networks.build(config, (5,), 20)
  return model, model.init(jax.random.PRNGKey(seed), [jnp.zeros((1, 5))])


def test_principal_cosines_of_known_subspaces():
  e = np.eye(4)
  same = diagnostics.principal_cosines(e[:, :2], e[:, :2] @ np.array([[2.0, 1.0], [0.0, 3.0]]))
  np.testing.assert_allclose(same, [1, 1], atol=1e-6)
  theta = 0.3  # the second axis turned by theta towards the third
  turned = np.stack([e[:, 0], np.cos(theta) * e[:, 1] + np.sin(theta) * e[:, 2]], axis=1)
  np.testing.assert_allclose(diagnostics.principal_cosines(e[:, :2], turned),
                             [1, np.cos(theta)], atol=1e-6)
  np.testing.assert_allclose(diagnostics.principal_cosines(e[:, :2], e[:, 2:]), [0, 0], atol=1e-6)


def test_a_decoder_that_did_not_move_reports_change_0_and_cosines_1():
  for decoder in ("linear", "mlp"):
    model, params = model_and_params(decoder)
    drift = diagnostics.decoder_drift(model, params, params)
    assert float(drift["decoder/change"]) == 0.0
    np.testing.assert_allclose([float(drift[f"decoder/cos_{k}"]) for k in (1, 2, 3)], 1, atol=1e-5)


def test_the_linear_basis_is_the_synergy_matrix_and_rescaling_keeps_the_subspace():
  model, params = model_and_params("linear")
  kernel = params["params"]["synergy_decoder"]["synergies"]["kernel"]  # (b, 20)
  np.testing.assert_array_equal(diagnostics.synergy_basis(model, params), kernel.T)
  scaled = jax.tree.map(lambda x: x, params)
  scaled["params"]["synergy_decoder"]["synergies"]["kernel"] = 2 * kernel
  drift = diagnostics.decoder_drift(model, params, scaled)
  np.testing.assert_allclose(float(drift["decoder/change"]), 1.0, rtol=1e-5)
  np.testing.assert_allclose(float(drift["decoder/cos_min"]), 1.0, atol=1e-5)


def test_a_decoder_trained_towards_another_subspace_moves_there():
  for decoder in ("linear", "mlp"):
    model, params = model_and_params(decoder)
    _, other = model_and_params(decoder, seed=1)
    target = diagnostics.synergy_basis(model, other)
    zs = jax.random.normal(jax.random.PRNGKey(2), (256, 3))
    actions = zs @ target.T  # postures of another subspace

    def loss(p):
      mean, _ = model.apply(p, zs, method=networks.DiscoSyn.decode)
      return jnp.mean((mean - actions) ** 2)

    opt = optax.adam(1e-2)
    state = opt.init(params)
    trained = params

    @jax.jit
    def step(p, s):
      updates, s = opt.update(jax.grad(loss)(p), s, p)
      return optax.apply_updates(p, updates), s

    for _ in range(300):
      trained, state = step(trained, state)
    start = diagnostics.principal_cosines(diagnostics.synergy_basis(model, params), target)
    drift = diagnostics.decoder_drift(model, params, trained)
    reached = diagnostics.principal_cosines(diagnostics.synergy_basis(model, trained), target)
    assert float(drift["decoder/change"]) > 0.3
    assert float(drift["decoder/cos_min"]) < 0.9
    assert float(reached.min()) > float(start.min()) + 0.2


def test_solving_actions_reads_where_a_policys_actions_lie(tmp_path):
  """A decoder spanning the plane a policy's actions lie in holds all of their variance and
  overlaps PCA-4 of them fully; one orthogonal to it holds none."""
  from discosyn_jax.synergies import fitting
  from studies import solving_actions

  rng = np.random.default_rng(0)
  basis = np.linalg.qr(rng.normal(size=(20, 20)))[0]
  plane, rest = basis[:, :4], basis[:, 4:8]
  actions = {"a": rng.normal(size=(200, 4)) @ plane.T,
             "b": rng.normal(size=(200, 4)) @ plane.T + 0.3 * plane[:, 0]}
  fit = tmp_path / "synergies-setx-seed0"
  fit.mkdir()
  np.savez(fit / "actions.npz", **actions)
  fields = dict(decoder="linear", n_synergies=4, decoder_bias=True, decoder_hidden=(128, 128))
  for name, span in (("inside", plane @ rng.normal(size=(4, 4))), ("outside", rest)):
    params = {"synergies": {"kernel": span.T.astype(np.float32),
                            "bias": np.zeros(20, np.float32)},
              "log_std": np.zeros(20, np.float32)}
    (tmp_path / f"{name}-setx-seed0").mkdir()
    fitting.save(tmp_path / f"{name}-setx-seed0" / "decoder.npz", params, fields)
  rows = solving_actions.table(tmp_path, "setx", 4).splitlines()[2:]
  assert rows == ["| 0 | inside-setx-seed0 | 1.00 (chance 0.20) | 1.00 | 1.00 |",
                  "| 0 | outside-setx-seed0 | 0.00 (chance 0.20) | 0.00 | 0.00 |"]
  with pytest.raises(ValueError, match="holds no synergies-set2"):
    solving_actions.table(tmp_path, "set2", 4)
