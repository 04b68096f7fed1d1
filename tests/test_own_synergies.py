"""Each task's own synergies beside the shared ones (`own_synergies`): off, nothing changes;
on, task n's head picks b + k activations, the last k through directions only task n acts
through, started from what task n's reward prior holds outside the shared start; a task
whose target lies partly outside a frozen shared span reaches it with them and not without."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.agent import networks, policy
from discosyn_jax.config import TrainConfig
from discosyn_jax.experiments.method import Method
from discosyn_jax.synergies import priors, start
from discosyn_jax.training.trainer import Trainer
from tests.test_residual import SMALL, TARGET, assert_same_tree, run
from tests.toy_env import ReachAction


def trainer(**overrides):
  config = TrainConfig(**{**SMALL, **overrides})
  return Trainer(config, envs=[ReachAction(TARGET), ReachAction(-TARGET, obs_size=5)])


def test_off_it_adds_nothing_and_trains_as_a_config_that_never_named_it(tmp_path):
  old = {k: v for k, v in trainer().config.to_dict().items() if k != "own_synergies"}
  (tmp_path / "config.json").write_text(json.dumps(old))
  assert config_lib.upgrade(tmp_path / "config.json") == ["own_synergies"]
  upgraded = config_lib.load(tmp_path / "config.json")
  assert upgraded.own_synergies == 0
  plain = trainer()
  assert "own_synergies" not in plain.initial_params()["params"]
  state, logs = run(plain, 2)
  again, logs_again = run(Trainer(upgraded, envs=plain.envs), 2)
  assert_same_tree(state, again)
  assert_same_tree(logs, logs_again)


def test_a_tasks_own_direction_moves_only_its_tasks_actions():
  t = trainer(own_synergies=1)
  model, params = t.model, t.initial_params()
  inner = params["params"]
  assert inner["own_synergies"].shape == (2, 1, 20)  # tasks, k, actions
  assert inner["heads_0"]["MLP_0"]["Dense_2"]["kernel"].shape[-1] == 3  # b + k
  assert inner["discriminator"]["MLP_0"]["Dense_2"]["kernel"].shape[-1] == 3  # q reads all
  assert networks.role("own_synergies") == "heads"  # a task's own: learns beside a frozen decoder
  z = jnp.array([[0.3, -0.2, 0.0]])
  act = lambda p, task, z: model.apply(p, task, z, method=networks.DiscoSyn.act)[0]
  # its own activation moves task n along tanh-activated W_n, and nothing else
  moved = z.at[0, 2].set(0.5)
  for task in (0, 1):
    np.testing.assert_allclose(act(params, task, moved) - act(params, task, z),
                               np.tanh(0.5) * inner["own_synergies"][task, 0][None], atol=1e-6)
  # another task's own directions change nothing of this task's action
  other = jax.tree.map(lambda x: x, params)
  other["params"] = {**inner, "own_synergies": inner["own_synergies"].at[1].add(1.0)}
  np.testing.assert_array_equal(act(other, 0, moved), act(params, 0, moved))
  assert not np.allclose(act(other, 1, moved), act(params, 1, moved))
  # the shared decoder reads the first b activations alone
  shared = model.apply(params, z, method=networks.DiscoSyn.decode)[0]
  np.testing.assert_array_equal(shared, model.apply(params, moved, method=networks.DiscoSyn.decode)[0])
  # sampling draws b + k z's and scores them
  draws = policy.noise(jax.random.PRNGKey(0), 4, model.z_size, 20)
  z_s, a_s, logp = policy.sample(model, params, 0, jnp.ones((4, 3)), draws)
  assert z_s.shape == (4, 3) and a_s.shape == (4, 20) and np.isfinite(logp).all()


def test_own_directions_are_each_tasks_top_metric_directions_outside_the_shared_span():
  rng = np.random.default_rng(0)
  shared = np.linalg.qr(rng.normal(size=(20, 3)))[0]
  rest = np.eye(20) - shared @ shared.T
  wanted = [rest @ rng.normal(size=20) for _ in range(2)]
  wanted = [w / np.linalg.norm(w) for w in wanted]
  metrics = [0.01 * np.eye(20) + np.outer(w, w) + 5 * np.outer(shared[:, 0], shared[:, 0])
             for w in wanted]  # most of each metric lies in the shared span: not its own
  own = priors.own(metrics, shared, 2)
  assert own.shape == (2, 20, 2)
  for n, w in enumerate(wanted):
    np.testing.assert_allclose(own[n].T @ own[n], np.eye(2), atol=1e-9)
    np.testing.assert_allclose(shared.T @ own[n], 0, atol=1e-9)
    assert abs(own[n][:, 0] @ w) == pytest.approx(1, abs=1e-9)  # its top direction is w_n
  with pytest.raises(ValueError, match="do not fit beside"):
    priors.own(metrics, shared, 18)


def test_a_run_starts_them_from_its_tasks_reward_prior_outside_the_shared_start():
  t = trainer(own_synergies=1, freeze_decoder=True)
  own = start.starting_own(t)
  assert own.shape == (2, 1, 20)
  kernel = np.asarray(networks.random_decoder(t.config, 20)["synergies"]["kernel"], np.float64)
  q = np.linalg.qr(kernel.T)[0]
  for n, target in enumerate((TARGET, -TARGET)):
    direction = own[n, 0] / np.linalg.norm(own[n, 0])
    np.testing.assert_allclose(q.T @ direction, 0, atol=1e-5)
    missing = target - q @ (q.T @ target)  # what the shared span cannot reach of the target
    # chance about 0.24 in the 18 dimensions outside; the clipped pushes blur it from 1
    assert abs(direction @ missing) / np.linalg.norm(missing) > 0.7
  # as long as a shared direction on average
  assert np.linalg.norm(own[0, 0]) == pytest.approx(
      np.linalg.svd(kernel, compute_uv=False).mean(), rel=1e-5)
  params = t.initial_params(own=own)
  np.testing.assert_array_equal(params["params"]["own_synergies"], own)
  with pytest.raises(ValueError, match="own synergies do not fit"):
    t.initial_params(own=own[:, :, :10])


def test_a_target_outside_a_frozen_shared_span_is_reached_with_own_synergies_only():
  # the shared space: a frozen random 2-D decoder, which cannot reach TARGET; with one
  # direction of each task's own, started where its reward prior points, it can
  fields = dict(freeze_decoder=True, learning_rate=3e-3, alpha2=0.0, num_envs=16)
  errors = {}
  for own in (0, 1):
    t = trainer(own_synergies=own, **fields)
    state = t.init(own=start.starting_own(t))
    for _ in range(60):
      state, _ = t.train_step(state)
    a = t.act(state.params, 0, jnp.zeros((1, 3)))[1]  # the deterministic action of task 0
    errors[own] = float(np.mean((np.clip(np.asarray(a)[0], -1, 1) - TARGET) ** 2))
  # no action of the frozen shared span (its bias stays 0) comes nearer TARGET than this
  kernel = np.asarray(networks.random_decoder(t.config, 20)["synergies"]["kernel"], np.float64)
  q = np.linalg.qr(kernel.T)[0]
  best_shared = float(np.mean((TARGET - q @ (q.T @ TARGET)) ** 2))
  assert errors[1] < 0.5 * best_shared <= 0.5 * errors[0] + 1e-6, (errors, best_shared)


def test_it_is_refused_where_it_has_no_room_and_named_in_the_rows_name():
  with pytest.raises(ValueError, match="identity decoder"):
    TrainConfig(decoder="identity", n_synergies=20, alpha2=0.0, alpha3=0.0,
                own_synergies=2).validate()
  with pytest.raises(ValueError, match="at most 20"):
    TrainConfig(n_synergies=18, own_synergies=3).validate()
  with pytest.raises(ValueError, match="must not be negative"):
    TrainConfig(own_synergies=-1).validate()
  with pytest.raises(ValueError, match="more than the hand's 12 actions"):
    config = TrainConfig(**{**SMALL, "n_synergies": 10, "own_synergies": 3})
    Trainer(config, envs=[ReachAction(TARGET[:12], action_size=12),
                          ReachAction(TARGET[:12], action_size=12)])
  config = TrainConfig(n_synergies=6, own_synergies=3, task_noise=True, bonus_cap=True,
                       decoder_init="reward")
  name = Method.of(config).name
  assert name == "DiscoSyn6+3-L-reward-tasknoise-bonuscap"
  assert Method.parse(name) == Method.of(config)
  plain = config.replace(task_noise=False, bonus_cap=False)  # the report's row after its b's
  assert Method.of(plain).rank() > Method.of(plain.replace(own_synergies=0)).rank()


def test_the_command_line_trains_them_one_flag_away(tmp_path):
  out = tmp_path / "run"
  cli.main(["train", "--preset", "planted-disco3-linear", "--own-synergies", "1", "--steps", "2",
            "--num-envs", "8", "--unroll-length", "4", "--eval-every", "0", "--out", str(out),
            "--no-progress"])
  saved = config_lib.load(out / "config.json")
  assert saved.own_synergies == 1
  from discosyn_jax.run import checkpoints

  arrays = checkpoints.read_arrays(out / "final", "params.params.")
  assert arrays["own_synergies"].shape == (4, 1, 20)


def test_the_study_writes_a_plan_whose_comparators_are_the_committed_records(tmp_path):
  import sys

  from discosyn_jax.experiments import confirm
  from tests.helpers import ROOT

  sys.path.insert(0, str(ROOT))
  try:
    from studies import own_synergies
  finally:
    sys.path.remove(str(ROOT))
  out = tmp_path / "plan" / "plan.json"
  own_synergies.main(["plan", "--seeds", "16", "17", "--claim", "c", "--decision", "d",
                      "--out", str(out)])
  plan = confirm.load(out)  # every named record is its row's run at its seed
  assert plan.row("set2-own").config.own_synergies == 3
  assert [len(plan.row(r).records) for r in ("set2-ppo", "set2-default", "set2-tncap")] == [13, 13, 7]
  assert [s.name for s in confirm.steps(plan, tmp_path)] == ["set2-own-seed16", "set2-own-seed17"]
  assert all(h.statistic == "difference" for h in plan.hypotheses)
  with pytest.raises(SystemExit):  # a plan is never rewritten
    own_synergies.main(["plan", "--seeds", "18", "--claim", "c", "--decision", "d", "--out", str(out)])
