"""The physics prior (discosyn_jax/physics_prior.py): the action directions that move the
objects most, the same for every seed; each seed's decoder starts in that subspace with its
own scale and bias."""

import numpy as np
import pytest

import tasks
from discosyn_jax import config as config_lib
from discosyn_jax import diagnostics, loop, physics_prior, synergies, train
from experiments import presets

TINY = dict(num_envs=2, unroll_length=4, num_minibatches=2, update_epochs=1, steps=1,
            eval_every=0, eval_envs=2, checkpoint_every=0, backend="native")


@pytest.fixture(autouse=True)
def few_states(monkeypatch):
  """4 random episodes per task, every 25th step: 16 states (the product uses 640)."""
  monkeypatch.setattr(physics_prior, "ENVS", 4)
  monkeypatch.setattr(physics_prior, "EVERY", 25)


@pytest.fixture(scope="module")
def valve3():
  return tasks.make("valve3", backend="native")


def test_the_prior_is_the_directions_that_move_the_object_most(valve3):
  jac = physics_prior.object_jacobians(valve3)
  assert jac.shape == (16, 1, 20) and np.isfinite(jac).all()
  assert np.abs(jac).max() > 0  # some push moved the valve
  basis = physics_prior.basis([valve3], 3)
  assert basis.shape == (20, 3)
  np.testing.assert_allclose(basis.T @ basis, np.eye(3), atol=1e-6)
  np.testing.assert_allclose(physics_prior.basis([valve3], 3), basis)  # no seed in it
  # the object moves more along each prior direction than along any direction outside it
  motion = lambda u: float(np.mean(np.sum((jac @ u) ** 2, axis=1)))
  outside = np.linalg.qr(np.eye(20) - basis @ basis.T)[0][:, :17]
  assert min(motion(u) for u in basis.T) >= max(motion(u) for u in outside.T) - 1e-9


def test_a_start_keeps_the_seeds_own_scale_and_bias_in_the_prior_subspace(valve3):
  basis = physics_prior.basis([valve3], 3)
  config = presets.preset("set1-disco3-linear")
  for seed in (0, 1):
    own = train.random_decoder(config.replace(seed=seed), 20)
    start = physics_prior.start(own, basis)
    kernel, own_kernel = start["synergies"]["kernel"], np.asarray(own["synergies"]["kernel"])
    assert diagnostics.overlap(kernel.T, basis) == pytest.approx(1.0, abs=1e-5)
    np.testing.assert_allclose(np.linalg.svd(kernel, compute_uv=False),
                               np.linalg.svd(own_kernel, compute_uv=False), rtol=1e-5)
    np.testing.assert_array_equal(start["synergies"]["bias"], own["synergies"]["bias"])


def test_every_seed_of_a_run_starts_in_the_same_subspace_and_only_there():
  starts = []
  for seed in (0, 1):
    config = presets.preset("set1-disco3-linear").replace(
        tasks=("valve3",), seed=seed, **TINY).validate()
    trainer = tasks.trainer(config)
    starts.append(synergies.basis(synergies.architecture(config.to_dict()),
                                  loop.starting_decoder(trainer)))
    random_start = synergies.basis(synergies.architecture(config.to_dict()),
                                   train.random_decoder(config, 20))
  assert diagnostics.overlap(*starts) == pytest.approx(1.0, abs=1e-5)
  assert diagnostics.overlap(starts[1], random_start) < 0.9  # not the seed's own subspace


def test_the_prior_is_refused_where_it_cannot_start_the_decoder():
  config = presets.preset("set1-disco3-linear")
  assert synergies.method_name(config) == "DiscoSyn3-L-prior"
  assert synergies.method_name(config.replace(freeze_decoder=True)) == "Prior3-L"
  for bad in (dict(decoder="mlp"), dict(decoder_from="x.npz"), dict(decoder_init="pca")):
    with pytest.raises(ValueError):
      config.replace(**bad).validate()
  assert config_lib.ADDED["decoder_init"] == "random" == config_lib.TrainConfig().decoder_init
  with pytest.raises(ValueError, match="needs hand tasks"):
    physics_prior.basis([tasks.make("planted0")], 3)


def test_chunking_the_pushes_changes_nothing(valve3, monkeypatch):
  """The pushes go through lax.map in chunks (MJX memory): chunking changes nothing."""
  whole = physics_prior.object_jacobians(valve3)
  monkeypatch.setattr(physics_prior, "CHUNK", 3)
  np.testing.assert_allclose(physics_prior.object_jacobians(valve3), whole, atol=1e-6)
