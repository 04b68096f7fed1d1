"""What steers a task's exploration before it is found. Each task's own decoder noise
(`task_noise`): off, nothing changes; on, each task samples and is scored with its own std
around the shared decoder's mean, and a task that pays narrows its own noise, not that of a
task that pays nothing. The bonus capped at what a task pays (`bonus_cap`): a task that pays
nothing is steered by no bonus."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.agent import networks, policy, ppo
from discosyn_jax.config import TrainConfig
from discosyn_jax.experiments.method import Method
from discosyn_jax.synergies import fitting
from discosyn_jax.training.trainer import Trainer, bonus_scale
from tests.test_residual import SMALL, TARGET, assert_same_tree, run
from tests.toy_env import ReachAction


class Unpaid(ReachAction):
  """ReachAction that pays nothing: a task not yet found."""

  def step(self, state, action):
    state = super().step(state, action)
    return state.replace(reward=jnp.zeros(()))


def trainer(**overrides):
  config = TrainConfig(**{**SMALL, **overrides})
  return Trainer(config, envs=[ReachAction(TARGET), Unpaid(-TARGET, obs_size=5)])


def test_off_it_adds_nothing_and_trains_as_a_config_that_never_named_it(tmp_path):
  old = {k: v for k, v in trainer().config.to_dict().items() if k != "task_noise"}
  (tmp_path / "config.json").write_text(json.dumps(old))
  assert config_lib.upgrade(tmp_path / "config.json") == ["task_noise"]
  upgraded = config_lib.load(tmp_path / "config.json")
  assert upgraded.task_noise is False
  plain = trainer()
  assert "task_log_stds" not in plain.initial_params()["params"]
  state, logs = run(plain, 2)
  again, logs_again = run(Trainer(upgraded, envs=plain.envs), 2)
  assert_same_tree(state, again)
  assert_same_tree(logs, logs_again)
  assert "a/entropy_a" not in logs[0]


def test_each_task_samples_and_is_scored_with_its_own_std():
  t = trainer(task_noise=True)
  model, params = t.model, t.initial_params()
  stds = params["params"]["task_log_stds"]
  assert stds.shape == (2, 20)
  np.testing.assert_allclose(np.exp(stds), 0.3, rtol=1e-6)  # init_action_std, each task
  assert networks.role("task_log_stds") == "heads"  # a task's own: learns beside a frozen decoder
  params = {"params": {**params["params"],
                       "task_log_stds": jnp.log(jnp.array([[0.01] * 20, [1.0] * 20]))}}
  batch = 4000
  for task, obs_size, std in ((0, 3, 0.01), (1, 5, 1.0)):
    obs = jnp.ones((batch, obs_size))
    draws = policy.noise(jax.random.PRNGKey(task), batch, 2, 20)
    z, a, log_prob = policy.sample(model, params, task, obs, draws)
    mean = model.apply(params, task, z, method=networks.DiscoSyn.act)[0]
    assert float(jnp.std(a - mean)) == pytest.approx(std, rel=0.05)
    again, _, a_log_std = policy.log_prob(model, params, task, obs, z, a)
    np.testing.assert_allclose(again, log_prob, rtol=1e-5)
    np.testing.assert_allclose(np.exp(a_log_std), std, rtol=1e-5)


def _log_std_gradients(t):
  """The PPO loss's gradient on the parameters, from one batch per task where task 0's
  advantage pays the samples nearest the decoder's mean (a task paid for precision) and
  task 1's is zero (a task that pays nothing)."""
  model, params, config = t.model, t.initial_params(), t.config
  samples = []
  for task, obs_size in ((0, 3), (1, 5)):
    obs = jnp.ones((512, obs_size))
    z, a, log_prob = policy.sample(model, params, task, obs,
                                   policy.noise(jax.random.PRNGKey(task), 512, 2, 20))
    mean = model.apply(params, task, z, method=networks.DiscoSyn.act)[0]
    advantage = -jnp.sum((a - mean) ** 2, axis=-1) if task == 0 else jnp.zeros(512)
    samples.append(ppo.Samples(obs=obs, z=z, action=a, log_prob=log_prob, advantage=advantage,
                               target=jnp.zeros(512)))
  grads, _ = jax.grad(ppo.loss, has_aux=True)(params, model, samples, config)
  return grads["params"]


def test_a_task_that_pays_narrows_its_own_noise_not_the_unpaid_tasks():
  """The reason for it: with one std shared, the paid task's precision narrows the noise
  the unpaid task explores with too; with its own, the unpaid task's is left to its bonus."""
  shared = _log_std_gradients(trainer())["synergy_decoder"]["log_std"]
  assert float(shared.mean()) > 0  # descent narrows the one std both tasks act with
  own = _log_std_gradients(trainer(task_noise=True))
  paid, unpaid = own["task_log_stds"]
  assert float(paid.mean()) > 0  # the paid task narrows its own
  # the unpaid task's is moved by the entropy bonus alone: alpha3 / tasks, widening
  np.testing.assert_allclose(unpaid, -1e-3 / 2, rtol=1e-4)
  # and the decoder's own std, unused, is moved by nothing
  assert float(jnp.abs(own["synergy_decoder"]["log_std"]).max()) == 0.0


def test_it_is_named_refused_where_there_is_no_decoder_noise_and_one_flag_away(tmp_path, capsys):
  assert Method.of(TrainConfig(task_noise=True)).name.endswith("-tasknoise")
  with pytest.raises(ValueError, match="task_noise"):
    TrainConfig(task_noise=True, decoder="identity", alpha2=0.0, alpha3=0.0).validate()
  out = tmp_path / "ppo"
  assert cli.main(["train", "--preset", "set1-ppo", "--task-noise", "yes", "--out", str(out)]) == 2
  assert "task_noise" in capsys.readouterr().err and not out.exists()


def test_its_synergies_frozen_elsewhere_give_each_new_task_its_own_noise(tmp_path):
  """The decoder of a run with its tasks' own noise never trained its own std: frozen on a
  new task, the new task learns its own noise rather than act with that untrained one."""
  t = trainer(task_noise=True)
  params = t.initial_params()["params"]
  path = fitting.save(tmp_path / "own-noise.npz", params["synergy_decoder"],
                      fitting.meta_of(t.config), decoder_init=t.config.decoder_init)
  meta, _ = fitting.read(path)
  assert Method.of(meta).name.endswith("-tasknoise")  # the frozen rows say what it was
  frozen = TrainConfig(**{**SMALL, **fitting.frozen_fields(meta, path), "tasks": ("a",)}).validate()
  assert frozen.task_noise and frozen.freeze_decoder
  target = Trainer(frozen, envs=[ReachAction(TARGET)])
  assert "task_log_stds" in target.initial_params()["params"]
  shared = fitting.save(tmp_path / "shared.npz", params["synergy_decoder"],
                        fitting.meta_of(trainer().config), decoder_init="random")
  assert fitting.frozen_fields(fitting.read(shared)[0], shared)["task_noise"] is False


# -- the bonus capped at what a task pays ------------------------------------------------
def test_the_bonus_scale_is_the_rewards_spread_over_the_bonus_capped_at_one():
  bonus = jnp.array([0.0, 0.2, 0.0, 0.2])  # std 0.1
  assert float(bonus_scale(jnp.full(4, -0.3), bonus)) == 0.0  # pays nothing that varies
  assert float(bonus_scale(jnp.array([0.0, 0.1, 0.0, 0.1]), bonus)) == pytest.approx(0.5)
  assert float(bonus_scale(jnp.array([0.0, 1.0, 0.0, 1.0]), bonus)) == 1.0
  assert float(bonus_scale(jnp.array([0.0, 1.0]), jnp.zeros(2))) == 1.0  # no bonus to cap


def test_a_task_that_pays_nothing_is_steered_by_no_bonus_under_the_cap():
  """The unpaid task's bonus is 0 and the paying task keeps one; where no task pays, a run
  with the cap is the run with alpha2 = 0 exactly, where the paper's constant alpha2 steers
  the heads by the bonus alone."""
  _, logs = run(trainer(bonus_cap=True), 2)
  assert all(float(m["b/bonus_scale"]) == 0.0 and float(m["b/bonus"]) == 0.0 for m in logs)
  assert all(0.0 < float(m["a/bonus_scale"]) <= 1.0 and float(m["a/bonus"]) != 0.0 for m in logs)
  unpaid = lambda **c: Trainer(TrainConfig(**{**SMALL, **c}),
                               envs=[Unpaid(TARGET), Unpaid(-TARGET, obs_size=5)])
  capped, _ = run(unpaid(bonus_cap=True), 2)
  no_bonus, _ = run(unpaid(alpha2=0.0), 2)
  assert_same_tree(capped.params, no_bonus.params)
  paper, _ = run(unpaid(), 2)
  heads = lambda state: jax.device_get(state.params["params"]["heads_0"])
  assert not np.allclose(heads(paper)["MLP_0"]["Dense_2"]["kernel"],
                         heads(capped)["MLP_0"]["Dense_2"]["kernel"])
  assert Method.of(TrainConfig(bonus_cap=True)).name.endswith("-bonuscap")
  with pytest.raises(ValueError, match="bonus_cap"):
    TrainConfig(bonus_cap=True, decoder="identity", alpha2=0.0, alpha3=0.0).validate()
