"""The residual beside the synergies (discosyn_jax/agent/residual.py): off, it is today's
computation; its weight follows its schedule; it reaches what a frozen synergy space cannot."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from discosyn import cli, commands
from discosyn_jax import config as config_lib
from discosyn_jax import tasks
from discosyn_jax.agent import networks, policy, residual
from discosyn_jax.config import TrainConfig
from discosyn_jax.tasks import planted
from discosyn_jax.training import evaluation
from discosyn_jax.training.trainer import Trainer
from tests.toy_env import ReachAction

TARGET = np.linspace(-0.8, 0.8, 20)
SMALL = dict(tasks=("a", "b"), n_synergies=2, policy_hidden=(16, 16), value_hidden=(16, 16),
             discriminator_hidden=(16, 16), num_envs=8, unroll_length=4, num_minibatches=2,
             update_epochs=2, eval_envs=4, squash_z=True, decoder_init="random")


def toy_trainer(**overrides):
  config = TrainConfig(**{**SMALL, **overrides})
  return Trainer(config, envs=[ReachAction(TARGET), ReachAction(-TARGET, obs_size=5)])


def run(trainer, steps):
  state, logs = trainer.init(), []
  for _ in range(steps):
    state, metrics = trainer.train_step(state)
    logs.append(jax.device_get(metrics))
  return jax.device_get(state), logs


def assert_same_tree(a, b):
  assert jax.tree.structure(a) == jax.tree.structure(b)
  jax.tree.map(np.testing.assert_array_equal, a, b)


# -- off: today's computation ------------------------------------------------------------
def test_no_residual_adds_nothing_and_trains_as_a_config_that_never_named_it(tmp_path):
  old = {k: v for k, v in toy_trainer().config.to_dict().items()
         if k not in ("residual", "residual_ramp", "residual_start", "init_residual_std",
                      "closing_episodes")}
  (tmp_path / "config.json").write_text(json.dumps(old))
  assert config_lib.upgrade(tmp_path / "config.json") == ["residual", "residual_ramp",
                                                           "residual_start",
                                                           "init_residual_std", "closing_episodes"]
  upgraded = config_lib.load(tmp_path / "config.json")
  assert (upgraded.residual, upgraded.residual_ramp, upgraded.residual_start) == (0, 0, 0)
  plain = toy_trainer()
  assert not plain.model.residual and plain.rho(0) is None
  assert not any(name.startswith("residuals") for name in plain.initial_params()["params"])
  assert len(plain._noise(jax.random.PRNGKey(0), 3)) == 2  # z's and a's draws only
  # exactly equal: every parameter, optimiser moment, rng and logged value
  state, logs = run(plain, 2)
  again, logs_again = run(Trainer(upgraded.replace(init_residual_std=0.5),
                                  envs=[ReachAction(TARGET), ReachAction(-TARGET, obs_size=5)]), 2)
  assert_same_tree(state, again)
  assert_same_tree(logs, logs_again)
  assert not any("residual" in k or "action_" in k for k in logs[0])


def test_a_residual_held_at_zero_leaves_the_rollout_and_its_own_parameters_alone():
  """Held at 0 the residual's draws come from a stream of their own: the first rollout is a
  plain run's, and its parameters get no gradient (they do not drift before the ramp)."""
  _, plain = run(toy_trainer(), 1)
  held = toy_trainer(residual=0.3, residual_start=0.02)  # 2 of its 100 train steps
  start = jax.device_get(held.init().params["params"]["residuals_0"])
  state, logs = run(held, 2)
  for key in ("a/reward", "a/return", "b/reward", "a/log_q"):
    assert logs[0][key] == plain[0][key], key
  assert_same_tree(start, state.params["params"]["residuals_0"])
  assert logs[1]["a/action_residual"] == 0.0 and logs[1]["a/action_synergy"] > 0


# -- the schedule ------------------------------------------------------------------------
def test_rho_rises_linearly_over_its_ramp_after_its_start_and_stays_at_its_cap():
  ramp = TrainConfig(residual=0.3, residual_ramp=0.5, steps=400)  # 200 train steps
  values = lambda config, steps: [float(residual.rho(config, s)) for s in steps]
  np.testing.assert_allclose(values(ramp, [0, 50, 100, 200, 201, 10_000]),
                             [0, 0.075, 0.15, 0.3, 0.3, 0.3], rtol=1e-6)
  late = ramp.replace(residual_start=0.25)  # 100 train steps
  np.testing.assert_allclose(values(late, [0, 99, 100, 200, 300, 400]),
                             [0, 0, 0, 0.15, 0.3, 0.3], rtol=1e-6)
  np.testing.assert_allclose(values(TrainConfig(residual=0.2), [0, 1, 500]), [0.2] * 3, rtol=1e-6)
  np.testing.assert_allclose(values(TrainConfig(residual=0.2, residual_start=0.03), [0, 2, 3]),
                             [0, 0, 0.2], rtol=1e-6)
  # jitted on the state's int32 step, as the train step computes it
  assert float(jax.jit(lambda s: residual.rho(ramp, s))(jnp.int32(50))) == pytest.approx(0.075)


def test_the_logged_rho_follows_the_schedule_and_the_action_shares_are_logged():
  trainer = toy_trainer(residual=0.4, residual_ramp=0.02, residual_start=0.01)
  _, logs = run(trainer, 4)
  np.testing.assert_allclose([m["residual/rho"] for m in logs], [0, 0, 0.2, 0.4], rtol=1e-6)
  for task in ("a", "b"):
    assert [m[f"{task}/action_residual"] > 0 for m in logs] == [False, False, True, True]
    assert all(m[f"{task}/action_synergy"] > 0 for m in logs)
  assert float(trainer.rho()) == pytest.approx(0.4)  # a finished run acts with the cap


def test_the_residual_moves_the_action_by_rho_times_its_bounded_mean():
  trainer = toy_trainer(residual=0.5)
  params = trainer.initial_params()
  obs = jnp.ones((3, 3))
  model = trainer.model
  big = jax.tree.map(lambda x: x * 1000.0, params["params"]["residuals_0"])
  params = {"params": {**params["params"], "residuals_0": big}}
  r_mean, _ = model.apply(params, 0, obs, method=networks.DiscoSyn.residual_policy)
  assert float(jnp.abs(r_mean).max()) <= 1.0  # bounded: the cap bounds what it carries
  z, a = policy.deterministic(model, params, 0, obs, jnp.float32(0.5))
  synergy = model.apply(params, 0, z, method=networks.DiscoSyn.act)[0]
  np.testing.assert_allclose(a, synergy + 0.5 * r_mean, rtol=1e-6, atol=1e-6)
  assert networks.role("residuals_0") == "heads"  # its task's, learned beside a frozen decoder


# -- what it is for ----------------------------------------------------------------------
def planted_span_decoder():
  """A frozen linear decoder spanning exactly the planted span, around the zero posture."""
  return {"synergies": {"kernel": jnp.asarray(planted.span().T), "bias": jnp.zeros(20)},
          "log_std": jnp.full(20, np.log(0.3), jnp.float32)}


@pytest.mark.parametrize("cap", [0.0, 0.5])
def test_a_ramped_residual_reaches_a_target_the_frozen_synergies_stop_short_of(cap):
  """A third of the target's power lies outside the planted span (outside = 1): a frozen
  decoder spanning the span alone reaches at best 10 x (1 - 1/3) = 6.7 of the 10 an episode
  pays (the eval mean over 256 goals: +-0.2); with the residual ramped in it passes 8.5
  (measured 2026-12-05, seeds 0-4, 150 train steps: 6.0-6.7 without, 9.0-9.3 with)."""
  config = TrainConfig(tasks=("planted0",), n_synergies=3, squash_z=False, decoder_init="random",
                       freeze_decoder=True, policy_hidden=(32, 32), value_hidden=(32, 32),
                       discriminator_hidden=(32, 32), num_envs=32, unroll_length=10,
                       num_minibatches=4, update_epochs=4, learning_rate=3e-3, eval_envs=256,
                       steps=150, residual=cap, residual_ramp=1 / 3 if cap else 0)
  trainer = Trainer(config, envs=[tasks.make("planted0", outside=1.0)])
  state = trainer.init(decoder_params=planted_span_decoder())
  start = jax.device_get(state.params["params"])
  for _ in range(150):
    state, metrics = trainer.train_step(state)
  ret = evaluation.evaluate(trainer, state)["planted0"]["return"]
  params = jax.device_get(state.params["params"])
  assert_same_tree(start["synergy_decoder"], params["synergy_decoder"])  # frozen
  if not cap:
    assert ret < 7.5, ret
    return
  assert ret > 8.5, ret
  assert float(metrics["residual/rho"]) == pytest.approx(cap)
  assert 0 < float(metrics["planted0/action_residual"]) <= cap
  moved = jax.tree.map(lambda x, y: bool(np.any(x != y)), start["residuals_0"],
                       params["residuals_0"])
  assert all(jax.tree.leaves(moved))  # the residual learned beside the frozen decoder


def test_a_planted_target_outside_the_span_has_the_share_it_is_given():
  inside = tasks.make("planted2")
  for outside in (0.5, 1.0):
    env = tasks.make("planted2", outside=outside)
    targets = np.asarray(env._targets)  # target = targets @ goal
    u = planted.span()
    off = targets - u @ (u.T @ targets)
    share = (off ** 2).sum() / (targets ** 2).sum()  # E over goals: the columns are orthogonal
    assert share == pytest.approx(outside ** 2 / (2 + outside ** 2), rel=1e-4)
    np.testing.assert_allclose(targets.T @ targets, np.diag(np.diag(targets.T @ targets)),
                               atol=1e-5)
    assert np.abs(targets).sum(axis=1).max() == pytest.approx(planted.MAX_TARGET, rel=1e-5)
  np.testing.assert_array_equal(np.asarray(tasks.make("planted2", outside=0.0)._targets),
                                np.asarray(inside._targets))
  with pytest.raises(ValueError, match="outside must not be negative"):
    tasks.make("planted0", outside=-0.1)
  with pytest.raises(ValueError, match="with slack"):
    tasks.make("planted_slack0", outside=0.5)


# -- the config and the command line -------------------------------------------------------
@pytest.mark.parametrize("changes, message", [
    (dict(residual=-0.1), "residual .* must be between 0 and 1, not -0.1"),
    (dict(residual=1.5), "must be between 0 and 1, not 1.5"),
    (dict(residual_ramp=0.5), "schedule a residual: set residual"),
    (dict(residual=0.3, residual_ramp=-0.1), "residual_ramp must not be negative"),
    (dict(residual=0.3, residual_start=-0.5), "residual_start must not be negative"),
    (dict(residual=0.3, residual_start=0.6, residual_ramp=0.5), "their sum must be at most 1"),
    (dict(residual=0.3, init_residual_std=0.0), "init_residual_std must be positive"),
    (dict(residual=0.3, decoder="identity", n_synergies=20, alpha2=0.0, alpha3=0.0),
     "identity decoder .* has no room for a residual"),
    (dict(residual=0.3, decoder_noise=False, alpha3=0.0), "noiseless decoder"),
])
def test_the_config_refuses_an_impossible_residual(changes, message):
  with pytest.raises(ValueError, match=message):
    TrainConfig(**changes).validate()
  TrainConfig(residual=0.3, residual_ramp=0.5, freeze_decoder=True).validate()


def test_the_residual_is_two_flags_away():
  args = cli.build_parser().parse_args(["train", "--preset", "planted-disco3-linear",
                                        "--residual", "0.3", "--residual-ramp", "0.5"])
  config = commands.train_config(args)
  assert (config.residual, config.residual_ramp, config.residual_start) == (0.3, 0.5, 0)
  assert config.residual_ramp_step_count == 200  # half of the preset's 400 train steps


@pytest.mark.parametrize("argv, line", [
    (["--residual", "-0.5"], "discosyn: error: residual (the cap of the residual's weight) must be "
     "between 0 and 1, not -0.5"),
    (["--preset", "set1-ppo", "--residual", "0.3"], "discosyn: error: the identity decoder "
     "(full-action PPO) has no room for a residual"),
    (["--residual-ramp", "0.1"], "discosyn: error: residual_ramp and "
     "residual_start schedule a residual"),
    (["--residual", "lots"], "discosyn train: error: argument --residual: invalid float value"),
    (["--residual-ramp", "half"], "discosyn train: error: argument --residual-ramp: "
     "invalid float value"),
])
def test_a_bad_residual_flag_is_one_line_exit_2_and_nothing_made(argv, line, tmp_path, capsys):
  out = tmp_path / "run"
  try:
    code = cli.main(["train", *argv, "--out", str(out)])
  except SystemExit as ended:  # argparse's own errors
    code = ended.code
  assert code == 2
  (err,) = capsys.readouterr().err.splitlines()
  assert err.startswith(line), err
  assert not out.exists()


# -- transfer and the sparse valve from the residual row's decoder ---------------------------


def test_transfer_and_sparse_freeze_the_residual_rows_decoder_and_act_with_its_residual(tmp_path):
  from discosyn_jax.experiments import paper, presets, report_runs

  planner = paper.Planner(tmp_path, "cpu", 0)
  steps = planner.plan("transfer") + planner.plan("sparse")
  by_method = {(s.meta["experiment"], s.meta["set"], s.meta["method"]): s for s in steps}
  half = paper.SCALES["cpu"].train_for("unseen-set1")["steps"] // 2
  for experiment, task_set, source in (("transfer", "unseen-set1", "discosyn3-l-reward-res0.3r150-set1-seed0"),
                                       ("transfer", "unseen-set2", "discosyn6-l-reward-res0.3r600-set2-seed0"),
                                       ("sparse", "sparse", "discosyn3-l-reward-res0.3r150-set1-seed0")):
    learned = source.split("-set")[0].replace("discosyn", "DiscoSyn").replace("-l-", "-L-")
    frozen = by_method[experiment, task_set, f"{learned} frozen-res0.3r{half}"]
    # the decoder of the residual row's own run (the same folder as discosyn-<set>'s)
    assert frozen.needs == (source,)
    assert frozen.config.decoder_from == str(tmp_path.resolve() / source / "decoder.npz")
    assert frozen.config.freeze_decoder and frozen.name.split("-")[:3] == [experiment, "synergies", "residual"]
    # the source's cap, ramped in over the first half of this run's own budget
    assert (frozen.config.residual, frozen.config.residual_ramp_step_count) == (presets.RESIDUAL_CAP, half)
    b = frozen.config.n_synergies
    for control in (f"Random{b}-L-res0.3r{half}", f"Random{b}-L-zfree-res0.3r{half}"):
      assert by_method[experiment, task_set, control].config.residual == presets.RESIDUAL_CAP
    # beside the paper's rows, which stay as they were; one full-action run for both
    paper_row = by_method[experiment, task_set, f"DiscoSyn{b}-L-reward frozen"]
    assert paper_row.config.residual == 0.0
    assert by_method[experiment, task_set, "PPO"].config.residual == 0.0
    # a run without its experiment.json is named from its config the same way
    assert report_runs.method_of(frozen.config).name == f"DiscoSyn{b}-L frozen-res0.3r{half}"
  names = [s.name for s in planner.plan("transfer")]
  assert len(names) == len(set(names))
  assert sum(n.startswith("transfer-ppo-set1") for n in names) == 1
  # `all` keeps the paper's rows: no residual among its transfer and sparse steps
  frozen_in_all = [s for s in planner.plan("all") if s.meta["experiment"] in ("transfer", "sparse")]
  assert frozen_in_all and not any(s.config.residual for s in frozen_in_all)


def test_the_report_shows_each_parts_share_of_the_action():
  """From committed records of set #1 with a residual: a row per method and task, the
  residual's share at the end as the logs hold it."""
  import pathlib

  from discosyn_jax.experiments import report, report_runs

  records = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "residual-set1"
  runs, _ = report_runs.find([records / f"{m}-set1-seed{s}" for m in
                              ("discosyn3-l-reward-res0.3r150", "random3-l-zfree-res0.3r150")
                              for s in (0, 1)])
  rows = [line.split(" | ") for line in report.residual_table(runs).splitlines()[2:]]
  assert [(r[0].strip("| "), r[2]) for r in rows] == [
      (m, t) for m in ("DiscoSyn3-L-reward-res0.3r150", "Random3-L-zfree-res0.3r150")
      for t in ("valve0", "valve1", "valve2", "valve3")]
  ends = [[row for row in r.metrics if "residual/rho" in row][-10:]
          for r in runs if r.method.family == "DiscoSyn"]
  share = [np.mean([row["valve2/action_residual"] for row in rows_]) for rows_ in ends]
  assert rows[2][5].startswith(f"{np.mean(share):.2f} ({min(share):.2f}–{max(share):.2f}) [2]")
  assert report.residual_table([r for r in runs if r.config.residual == 0]) == ""
