"""The Flax module, the losses and the jitted train step, on a tiny pure-JAX task."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from discosyn_jax.agent import networks, policy, ppo
from discosyn_jax.agent.networks import DiscoSyn
from discosyn_jax.config import TrainConfig
from discosyn_jax.training.trainer import Trainer, _episode_metrics
from tests.toy_env import ReachAction

TARGET = np.linspace(-0.8, 0.8, 20)
SMALL = dict(policy_hidden=(32, 32), value_hidden=(32, 32), decoder_hidden=(32, 32),
             discriminator_hidden=(32, 32), num_envs=32, unroll_length=10, num_minibatches=4,
             update_epochs=4, learning_rate=1e-2, eval_envs=8, squash_z=False, decoder_init="random")
PPO = dict(decoder="identity", n_synergies=20, alpha2=0.0, alpha3=0.0, init_z_std=0.5)


def two_task_trainer(devices=None, **overrides):
  config = TrainConfig(tasks=("a", "b"), **{**SMALL, "n_synergies": 2, **overrides})
  return Trainer(config, envs=[ReachAction(TARGET), ReachAction(-TARGET, obs_size=5)],
                 devices=devices)


def random_samples(key, obs_size, n=16, b=3):
  k = jax.random.split(key, 6)
  return ppo.Samples(obs=jax.random.normal(k[0], (n, obs_size)), z=jax.random.normal(k[1], (n, b)),
                     action=jax.random.normal(k[2], (n, 20)), log_prob=jax.random.normal(k[3], (n,)),
                     advantage=jax.random.normal(k[4], (n,)), target=jax.random.normal(k[5], (n,)))


@pytest.mark.parametrize("decoder", ["linear", "mlp", "identity"])
def test_module_shapes(decoder):
  b = 20 if decoder == "identity" else 3
  config = TrainConfig(**PPO) if decoder == "identity" else TrainConfig(squash_z=False, decoder_init="random", decoder=decoder, n_synergies=b)
  model = networks.build(config, obs_sizes=(7, 11), action_size=20)
  params = model.init(jax.random.PRNGKey(0), [jnp.zeros((1, 7)), jnp.zeros((1, 11))])
  for task, size in enumerate((7, 11)):
    mean, log_std = model.apply(params, task, jnp.ones((5, size)), method=DiscoSyn.policy)
    assert mean.shape == log_std.shape == (5, b)
    assert model.apply(params, task, jnp.ones((5, size)), method=DiscoSyn.value).shape == (5,)
  z = jax.random.normal(jax.random.PRNGKey(1), (64, b))
  a, a_log_std = model.apply(params, z, method=DiscoSyn.decode)
  assert a.shape == (64, 20)
  top = set(params["params"])
  assert {"heads_0", "heads_1", "values_0", "values_1"} <= top
  if decoder == "identity":
    assert a_log_std is None and np.array_equal(a, z)
    assert "synergy_decoder" not in top and "discriminator" not in top
    return
  assert a_log_std.shape == (64, 20)
  mean, log_std = model.apply(params, a, method=DiscoSyn.discriminate)
  assert mean.shape == log_std.shape == (64, b)
  # the decoder's postures span (at most) b dimensions around its output at z = 0
  centred = a - model.apply(params, jnp.zeros((1, b)), method=DiscoSyn.decode)[0]
  rank = np.linalg.matrix_rank(np.asarray(centred), tol=1e-4)
  if decoder == "linear":
    assert params["params"]["synergy_decoder"]["synergies"]["kernel"].shape == (b, 20)
    assert rank == b
  else:
    assert rank > b  # a curved manifold leaves the linear span


def test_head_gets_gradient_only_from_its_own_task():
  trainer = two_task_trainer()
  params = trainer.init().params
  config = trainer.config
  s0 = random_samples(jax.random.PRNGKey(0), 3, b=2)
  s1 = random_samples(jax.random.PRNGKey(1), 5, b=2)
  s1_other = random_samples(jax.random.PRNGKey(2), 5, b=2)
  grad = jax.jit(jax.grad(ppo.loss, has_aux=True), static_argnums=(1, 3))
  g, _ = grad(params, trainer.model, (s0, s1), config)
  g_other, _ = grad(params, trainer.model, (s0, s1_other), config)
  for name in ("heads_0", "values_0"):
    jax.tree.map(np.testing.assert_array_equal, g["params"][name], g_other["params"][name])
  moved = jax.tree.map(lambda x, y: bool(jnp.any(x != y)), g["params"]["heads_1"],
                       g_other["params"]["heads_1"])
  assert any(jax.tree.leaves(moved))
  assert any(bool(jnp.any(x != 0)) for x in jax.tree.leaves(g["params"]["synergy_decoder"]))


def test_identity_decoder_is_plain_ppo():
  """Full-action PPO: the loss equals the textbook clipped Gaussian PPO loss."""
  config = TrainConfig(tasks=("a",), **{**SMALL, **PPO}, alpha1=0.01)
  trainer = Trainer(config, envs=[ReachAction(TARGET)])
  params = trainer.init().params
  s = random_samples(jax.random.PRNGKey(3), 3, b=20)
  s = s.replace(action=s.z)
  total, (per_task, shared) = ppo.loss(params, trainer.model, (s,), config)

  mean, log_std = trainer.model.apply(params, 0, s.obs, method=DiscoSyn.policy)
  var = jnp.exp(2 * log_std)
  log_prob = jnp.sum(-0.5 * (s.action - mean) ** 2 / var - 0.5 * jnp.log(2 * jnp.pi * var), -1)
  ratio = jnp.exp(log_prob - s.log_prob)
  adv = (s.advantage - s.advantage.mean()) / (s.advantage.std() + 1e-8)
  pg = -jnp.mean(jnp.minimum(ratio * adv, jnp.clip(ratio, 0.8, 1.2) * adv))
  value = trainer.model.apply(params, 0, s.obs, method=DiscoSyn.value)
  entropy = jnp.sum(0.5 * jnp.log(2 * jnp.pi * jnp.e * var), -1).mean()
  expected = pg + 0.5 * 0.5 * jnp.mean((value - s.target) ** 2) - 0.01 * entropy
  np.testing.assert_allclose(total, expected, rtol=1e-5)
  assert set(shared) == {"loss"}  # no decoder entropy, no discriminator


@pytest.mark.parametrize("decoder", ["identity", "linear"])
def test_training_solves_the_tiny_task(decoder):
  """Eval return (10 steps, 1 per step at best) rises from ~7.5 to >= 9.5 in 150 steps."""
  if decoder == "identity":
    trainer = Trainer(TrainConfig(tasks=("a",), **SMALL, **PPO), envs=[ReachAction(TARGET)])
  else:
    trainer = two_task_trainer(decoder=decoder)
  state = trainer.init()
  key = jax.random.PRNGKey(1)
  before = trainer.returns(state.params, state.normalizers, key)
  for _ in range(150):
    state, metrics = trainer.train_step(state)
  after = trainer.returns(state.params, state.normalizers, key)
  for task in trainer.config.tasks:
    assert float(before[task]["return"]) < 8.0
    assert float(after[task]["return"]) >= 9.5, (task, after)
  assert int(state.step) == 150 and bool(metrics["finite"])


def test_frozen_decoder_is_unchanged_and_heads_learn():
  trainer = two_task_trainer(freeze_decoder=True)
  state = trainer.init()
  decoder = jax.device_get(state.params["params"]["synergy_decoder"])
  head = jax.device_get(state.params["params"]["heads_0"])
  for _ in range(3):
    state, _ = trainer.train_step(state)
  jax.tree.map(np.testing.assert_array_equal, decoder,
               jax.device_get(state.params["params"]["synergy_decoder"]))
  changed = jax.tree.map(lambda x, y: bool(np.any(x != y)), head,
                         jax.device_get(state.params["params"]["heads_0"]))
  assert all(jax.tree.leaves(changed))


class PaysNothing(ReachAction):
  """ReachAction paid a small constant below zero (as the weight pull at rest): a task not
  yet found."""

  def step(self, state, action):
    return super().step(state, action).replace(reward=jnp.full((), -0.007))


def _head_stds(state, n_tasks: int = 2) -> np.ndarray:
  return np.stack([np.exp(jax.device_get(state.params["params"][f"heads_{n}"]["log_std"]))
                   for n in range(n_tasks)])


def test_a_floored_head_keeps_its_z_std_until_its_task_pays():
  """z_std_floor: while a task pays nothing its head's z std stays at the floor, where the
  bonus narrows it below without one; a task paid in its first rollout (a dense one) is
  never held: with every task dense the run is the run without the floor, number for
  number, and `paid` says so."""
  narrowing = dict(alpha2=1.0, alpha1=0.0)  # a strong bonus: the heads narrow at once
  config = TrainConfig(tasks=("a", "b"), **{**SMALL, "n_synergies": 2, **narrowing})
  unpaid = [ReachAction(TARGET), PaysNothing(-TARGET, obs_size=5)]
  free, held = Trainer(config, unpaid), Trainer(config.replace(z_std_floor=1.0), unpaid)
  assert held.init().paid.shape == (2,) and free.init().paid.shape == (0,)
  states = {"free": free.init(), "held": held.init()}
  for _ in range(4):
    states["free"], _ = free.train_step(states["free"])
    states["held"], metrics = held.train_step(states["held"])
  assert _head_stds(states["free"])[1].min() < 0.97
  assert _head_stds(states["held"])[1].min() == pytest.approx(1.0)
  assert bool(metrics["a/paid"]) and not bool(metrics["b/paid"])

  dense = [ReachAction(TARGET), ReachAction(-TARGET, obs_size=5)]
  plain, floored = Trainer(config, dense), Trainer(config.replace(z_std_floor=2.0), dense)
  a, b = plain.init(), floored.init()
  for _ in range(3):
    a, _ = plain.train_step(a)
    b, metrics = floored.train_step(b)
  assert bool(metrics["a/paid"]) and bool(metrics["b/paid"])
  jax.tree.map(np.testing.assert_array_equal, jax.device_get(a.params), jax.device_get(b.params))
  assert _head_stds(b).max() < 2.0  # the floor above the start was never applied


def test_each_tasks_share_of_the_decoders_gradient():
  """decoder_share: a task whose samples carry no advantage gives the decoder nothing (its
  share 0, the other's 1); in a train step the shares are logged per task and sum to 1;
  nothing is logged where the decoder does not learn."""
  trainer = two_task_trainer()
  params = trainer.init().params
  keys = jax.random.split(jax.random.PRNGKey(3), 2)
  paid, unpaid = random_samples(keys[0], 3, b=2), random_samples(keys[1], 5, b=2)
  # drawn by the policy as it is (ratio 1), the unpaid task with no advantage at all
  on_policy = lambda n, s: s.replace(log_prob=policy.log_prob(trainer.model, params, n, s.obs, s.z,
                                                              s.action)[0])
  paid = on_policy(0, paid)
  unpaid = on_policy(1, unpaid).replace(advantage=jnp.zeros_like(unpaid.advantage))
  shares = [float(x) for x in trainer._decoder_shares(params, [paid, unpaid], None)]
  assert shares == pytest.approx([1.0, 0.0])
  _, metrics = trainer.train_step(trainer.init())
  got = [float(metrics[f"{task}/decoder_share"]) for task in ("a", "b")]
  assert sum(got) == pytest.approx(1.0) and min(got) > 0
  frozen = two_task_trainer(freeze_decoder=True)
  assert "a/decoder_share" not in frozen.train_step(frozen.init())[1]


def test_a_given_decoder_is_installed_and_a_misfit_refused():
  trainer = two_task_trainer(freeze_decoder=True)
  decoder = trainer.init(seed=7).params["params"]["synergy_decoder"]
  state = trainer.init(seed=0, decoder_params=decoder)
  jax.tree.map(np.testing.assert_array_equal, decoder, state.params["params"]["synergy_decoder"])
  wrong = jax.tree.map(lambda x: jnp.zeros(x.shape + (2,)), decoder)
  with pytest.raises(ValueError, match="does not fit"):
    trainer.init(decoder_params=wrong)


def test_a_task_posture_moves_only_its_own_tasks_actions():
  model = networks.build(TrainConfig(squash_z=False, decoder_init="random", n_synergies=3, task_posture=True), obs_sizes=(7, 11),
                         action_size=20)
  params = model.init(jax.random.PRNGKey(0), [jnp.zeros((1, 7)), jnp.zeros((1, 11))])
  assert params["params"]["postures"].shape == (2, 20)
  z = jax.random.normal(jax.random.PRNGKey(1), (8, 3))
  shared = model.apply(params, z, method=DiscoSyn.decode)[0]
  np.testing.assert_array_equal(model.apply(params, 0, z, method=DiscoSyn.act)[0], shared)
  moved = jax.tree.map(lambda x: x, params)
  moved["params"]["postures"] = params["params"]["postures"].at[1].set(TARGET)
  np.testing.assert_array_equal(model.apply(moved, 0, z, method=DiscoSyn.act)[0], shared)
  np.testing.assert_allclose(model.apply(moved, 1, z, method=DiscoSyn.act)[0], shared + TARGET,
                             rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("posture", [False, True])
def test_task_postures_reach_what_one_frozen_synergy_cannot(posture):
  """Two targets off one frozen random synergy's line: with a posture per task, learned
  beside the frozen decoder, both are held (return >= 9.5 of 10); without, neither is."""
  trainer = two_task_trainer(n_synergies=1, freeze_decoder=True, task_posture=posture)
  state = trainer.init()
  for _ in range(150):
    state, _ = trainer.train_step(state)
  after = trainer.returns(state.params, state.normalizers, jax.random.PRNGKey(1))
  for task in trainer.config.tasks:
    assert (float(after[task]["return"]) >= 9.5) == posture, (task, after)


def _fitted_log_q(target: str, spread: float) -> float:
  """The mean log q of a discriminator fitted (300 Adam steps) to bounded synergies: z of
  std `spread`, decoded as a = tanh(z) W + noise."""
  model = networks.build(TrainConfig(decoder_init="random", n_synergies=3, squash_z=True, discriminator_target=target),
                         obs_sizes=(3,), action_size=20)
  params = model.init(jax.random.PRNGKey(0), [jnp.zeros((1, 3))])
  k1, k2, k3 = jax.random.split(jax.random.PRNGKey(1), 3)
  z = spread * jax.random.normal(k1, (512, 3))
  a = jnp.tanh(z) @ jax.random.normal(k2, (3, 20)) + 0.3 * jax.random.normal(k3, (512, 20))

  def nll(p):
    return -ppo.discriminator_log_prob(model, p, z, a).mean()

  opt = optax.adam(3e-3)

  @jax.jit
  def step(params, opt_state):
    updates, opt_state = opt.update(jax.grad(nll)(params), opt_state)
    return optax.apply_updates(params, updates), opt_state

  opt_state = opt.init(params)
  for _ in range(300):
    params, opt_state = step(params, opt_state)
  return float(-nll(params))


def test_the_discriminator_reads_back_the_activation_where_z_saturates():
  """z deep in tanh's saturation (std 3) cannot be read back from the action: q of z falls
  (its bonus would pay a head for narrowing z); q of the activation the decoder read does not."""
  z_near, z_far = _fitted_log_q("z", 1.0), _fitted_log_q("z", 3.0)
  act_near, act_far = _fitted_log_q("activation", 1.0), _fitted_log_q("activation", 3.0)
  assert z_near - z_far > 2.0, (z_near, z_far)
  assert abs(act_near - act_far) < 0.5 and act_far > z_far + 2.0, (act_near, act_far)


def test_discriminator_likelihood_rises_on_a_fixed_batch():
  model = networks.build(TrainConfig(squash_z=False, decoder_init="random", n_synergies=3), obs_sizes=(3,), action_size=20)
  params = model.init(jax.random.PRNGKey(0), [jnp.zeros((1, 3))])
  k1, k2, k3 = jax.random.split(jax.random.PRNGKey(1), 3)
  z = jax.random.normal(k1, (256, 3))
  a = z @ jax.random.normal(k2, (3, 20)) * 0.3 + 0.05 * jax.random.normal(k3, (256, 20))

  def nll(p):
    return -ppo.discriminator_log_prob(model, p, z, a).mean()

  opt = optax.adam(3e-3)
  opt_state = opt.init(params)
  start = float(-nll(params))

  @jax.jit
  def step(params, opt_state):
    grads = jax.grad(nll)(params)
    updates, opt_state = opt.update(grads, opt_state)
    return optax.apply_updates(params, updates), opt_state

  for _ in range(200):
    params, opt_state = step(params, opt_state)
  end = float(-nll(params))
  # z is nearly a linear function of a here: q must do far better than its start (~ -4.3)
  assert end > start + 3.0, (start, end)


def test_episode_metrics_average_over_the_episodes_that_ended():
  done = np.array([[0, 0, 1], [1, 0, 0], [0, 0, 1], [0, 1, 0]], np.float32)  # 4 episodes
  garbage = np.full((4, 3), 100.0, np.float32)  # the values at steps that ended nothing
  ended = lambda *values: np.where(done > 0, np.array(values, np.float32).reshape(4, 3), garbage)
  traj = dict(done=done, reward=np.arange(12, dtype=np.float32).reshape(4, 3),
              episode_return=ended(0, 0, 3, 5, 0, 0, 0, 0, 7, 0, 1, 0),
              metrics={"success": ended(0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0),
                       "diverged": done * np.array([1, 0, 0], np.float32),
                       "reward/reach": np.full((4, 3), 0.25, np.float32)})
  log_q = np.linspace(-2, 0, 12, dtype=np.float32).reshape(4, 3)
  m = jax.tree.map(float, _episode_metrics(traj, log_q, 0.1))
  assert m["episodes"] == 4 and m["diverged"] == 1
  assert m["return"] == pytest.approx((3 + 5 + 7 + 1) / 4)
  assert m["success"] == pytest.approx(2 / 4)
  assert m["reward"] == pytest.approx(5.5) and m["reward/reach"] == pytest.approx(0.25)
  assert m["log_q"] == pytest.approx(-1.0) and m["bonus"] == pytest.approx(-0.1)
  assert m["first_reward_t"] == 0  # the first row already pays env 1 and 2
  none = _episode_metrics(dict(traj, done=np.zeros((4, 3), np.float32)), log_q, 0.1)
  assert float(none["episodes"]) == 0 and float(none["return"]) == 0


def test_config_rejects_impossible_settings():
  with pytest.raises(ValueError, match="between 1 and 20"):
    TrainConfig(squash_z=False, decoder_init="random", n_synergies=0).validate()
  with pytest.raises(ValueError, match="between 1 and 20"):
    TrainConfig(squash_z=False, decoder_init="random", n_synergies=21).validate()
  with pytest.raises(ValueError, match="unknown decoder"):
    TrainConfig(squash_z=False, decoder_init="random", decoder="cubic").validate()
  with pytest.raises(ValueError, match="unknown discriminator_target 'u'; known: z, activation"):
    TrainConfig(squash_z=False, decoder_init="random", discriminator_target="u").validate()
  with pytest.raises(ValueError, match="minibatches"):
    TrainConfig(squash_z=False, decoder_init="random", num_envs=3, unroll_length=5, num_minibatches=4).validate()
  with pytest.raises(ValueError, match="alpha2"):
    TrainConfig(squash_z=False, decoder_init="random", decoder="identity", n_synergies=20).validate()
  with pytest.raises(ValueError, match="task posture"):
    TrainConfig(**PPO, task_posture=True).validate()
