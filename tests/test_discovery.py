"""The measure of discovery (overlaps of synergy subspaces), the planted-synergy test bed,
and the random-decoder controls of `discosyn experiment`."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from discosyn_jax import tasks
from discosyn_jax.agent import networks, ppo
from discosyn_jax.config import TrainConfig
from discosyn_jax.run import checkpoints
from discosyn_jax.synergies import diagnostics, discovery, fitting
from discosyn_jax.training.trainer import Trainer
from discosyn_jax import assemble
from discosyn_jax.experiments import paper, presets, report
from discosyn_jax.experiments.method import Method
from discosyn_jax.tasks import planted, registry
from tests import toy_env

TARGET = np.linspace(-0.8, 0.8, 20)
toy_env.register()  # tasks a, b
DECODER = "params.params.synergy_decoder."




# -- the overlap -------------------------------------------------------------------
def test_overlap_is_1_for_a_subspace_itself_0_for_orthogonal_ones_whatever_the_basis():
  rng = np.random.default_rng(0)
  q = np.linalg.qr(rng.normal(size=(20, 6)))[0]
  a, b = q[:, :3], q[:, 3:]
  mix = rng.normal(size=(3, 3))  # any invertible change of basis (scale, shear, rotation)
  assert float(diagnostics.overlap(a, a)) == pytest.approx(1.0, abs=1e-5)
  assert float(diagnostics.overlap(a, 5.0 * a @ mix)) == pytest.approx(1.0, abs=1e-5)
  assert float(diagnostics.overlap(a, b)) == pytest.approx(0.0, abs=1e-6)
  assert float(diagnostics.overlap(a @ mix, b @ mix.T)) == pytest.approx(0.0, abs=1e-6)
  # half of a 2-D subspace inside the other: one cosine 1, one 0
  assert float(diagnostics.overlap(q[:, :2], q[:, 1:3])) == pytest.approx(0.5, abs=1e-5)
  # a 3-D subspace inside a 6-D one: the smaller dimension normalises
  assert float(diagnostics.overlap(a, q)) == pytest.approx(1.0, abs=1e-5)
  # chance: two random 3-D subspaces of R^20
  draws = [float(diagnostics.overlap(rng.normal(size=(20, 3)), rng.normal(size=(20, 3))))
           for _ in range(300)]
  assert np.mean(draws) == pytest.approx(diagnostics.chance_overlap(3, 3, 20), abs=0.02)
  assert diagnostics.chance_overlap(3, 3) == 0.15
  # the union of planted planes is the span they lie in
  assert diagnostics.union_span([a[:, :2], a[:, 1:], 2 * a[:, :1]]).shape == (20, 3)


# -- the planted test bed ----------------------------------------------------------
def test_planted_tasks_are_registered_with_one_span_and_a_plane_each():
  assert tasks.TASK_SETS["planted"] == tuple(f"planted{n}" for n in range(4))
  assert presets.PRESETS["planted_slack-disco3-linear"].tasks == tasks.TASK_SETS["planted_slack"]
  envs = [tasks.make(name) for name in tasks.expand(["planted", "planted_slack"])]
  u = planted.span()
  np.testing.assert_allclose(u.T @ u, np.eye(3), atol=1e-6)
  planes = []
  for env in envs:
    assert (env.action_size, env.observation_size, env.episode_length) == (20, 2, 10)
    np.testing.assert_array_equal(env.planted_span, u)  # the fixed seed: one span for all
    plane = planted.task_plane(env.config)
    np.testing.assert_allclose(u @ u.T @ plane, plane, atol=1e-6)  # inside the span
    planes.append(plane)
  # no task's plane is the span, the four together are
  assert all(float(diagnostics.overlap(p, u)) == pytest.approx(1.0, abs=1e-5) for p in planes)
  assert diagnostics.union_span(planes[:4]).shape == (20, 3)
  with pytest.raises(ValueError, match="has no setting"):
    tasks.make("planted0", frictionloss=0.1)


def test_planted_reward_and_success_count_the_error_in_the_span_only_with_slack():
  strict, slack = tasks.make("planted1"), tasks.make("planted_slack1")
  key = jax.random.PRNGKey(3)
  state = strict.reset(key)
  target = state.pipeline_state["target"]
  assert float(jnp.abs(target).max()) <= planted.MAX_TARGET + 1e-6
  np.testing.assert_allclose(planted.span() @ planted.span().T @ target, target, atol=1e-6)
  hit = strict.step(state, target)
  assert float(hit.reward) == pytest.approx(1.0) and float(hit.metrics["success"]) == 1.0
  # a step out of the span: costs reward without slack, nothing with it
  u = planted.span()
  out = np.linalg.qr(np.concatenate([u, np.eye(20)[:, :1]], axis=1))[0][:, 3]
  step = (1 - float(jnp.abs(target).max())) / np.abs(out).max()  # no action clipped
  assert step > 0.1
  off = target + step * jnp.asarray(out)
  assert float(strict.step(state, off).reward) == pytest.approx(
      1 - step ** 2 / strict._target_power, abs=1e-5)
  assert float(strict.step(state, target + 3 * step * jnp.asarray(out)).metrics["success"]) == 0.0
  loose = slack.step(slack.reset(key), off)
  assert float(loose.reward) == pytest.approx(1.0, abs=1e-5) and float(loose.metrics["success"]) == 1.0
  # targets change per episode
  other = strict.reset(jax.random.PRNGKey(4)).pipeline_state["target"]
  assert float(jnp.abs(other - target).max()) > 0.01


def test_the_found_task_pays_nothing_until_an_action_lands_near_its_target():
  """planted_found3: the dense reward inside paid_within of a typical target, 0 outside;
  success as for the dense task. Its set: three dense tasks and it."""
  assert tasks.TASK_SETS["planted_found"][-1] == "planted_found3"
  found, dense = tasks.make("planted_found3"), tasks.make("planted3")
  assert found.config.paid_within == planted.PAID_WITHIN > 0
  state = found.reset(jax.random.PRNGKey(5))
  target = state.pipeline_state["target"]
  np.testing.assert_array_equal(target, dense.reset(jax.random.PRNGKey(5)).pipeline_state["target"])
  radius = planted.PAID_WITHIN * np.sqrt(found._target_power)  # the error where pay starts
  direction = target / jnp.linalg.norm(target)
  for error, paid in ((0.9 * radius, True), (1.1 * radius, False)):
    action = target - error * direction
    hit, dense_hit = found.step(state, action), dense.step(state, action)
    assert float(hit.reward) == (pytest.approx(float(dense_hit.reward)) if paid else 0.0)
    assert float(hit.metrics["success"]) == float(dense_hit.metrics["success"])
  assert float(found.step(state, jnp.zeros(20)).reward) == 0.0  # where the dense one pays ~0
  with pytest.raises(ValueError, match="paid_within"):
    tasks.make("planted0", paid_within=1.5)


@pytest.mark.parametrize("task_set,reach", [("planted_reach", planted.REACH),
                                            ("planted_far", planted.REACH_FAR)])
def test_the_reach_task_pays_only_for_an_excursion_along_its_direction(task_set, reach):
  """planted_reach3 / planted_far3: nothing short of their reach along the first axis of the
  plane (a posture at its own target is paid nothing), then a reward rising to 1 over
  EXCURSION_WIDTH; success from the reach on. Motion across the direction changes nothing."""
  env = tasks.make(tasks.TASK_SETS[task_set][-1])
  assert env.config.excursion == reach > 0
  direction = planted.task_plane(env.config)[:, 0]
  across = planted.task_plane(env.config)[:, 1]  # orthogonal to it, inside the plane
  state = env.reset(jax.random.PRNGKey(5))
  for reach, reward, success in ((0.9 * reach, 0.0, 0.0), (reach + 0.01, 0.02, 1.0),
                                 (reach + 0.25, 0.25 / planted.EXCURSION_WIDTH, 1.0),
                                 (reach + 2 * planted.EXCURSION_WIDTH, 1.0, 1.0)):
    for side in (0.0, 0.3):
      out = env.step(state, jnp.asarray(reach * direction + side * across))
      assert float(out.reward) == pytest.approx(reward, abs=1e-5)
      assert float(out.metrics["success"]) == success
  assert float(env.step(state, state.pipeline_state["target"]).reward) == 0.0
  with pytest.raises(ValueError, match="excursion"):
    tasks.make("planted0", excursion=1.0, paid_within=0.5)
  with pytest.raises(ValueError, match="excursion"):
    tasks.make("planted0", excursion=-1.0)


def test_a_decoder_trained_on_planted_tasks_finds_the_span():
  """The paper's update on one planted task that needs the whole span: the decoder's
  overlap with it climbs from chance to near 1 (96 k env steps, a few seconds after the
  compile; measured 2026-12-02: 0.11 at the start, 0.94 at the end)."""
  config = TrainConfig(decoder_init="random", tasks=("planted0",), n_synergies=3, squash_z=True, num_envs=32,
                       unroll_length=10, num_minibatches=2, update_epochs=4, learning_rate=1e-3,
                       policy_hidden=(32, 32), value_hidden=(32, 32),
                       discriminator_hidden=(32, 32), steps=300)
  trainer = Trainer(config, envs=[tasks.make("planted0", task_rank=3)])
  state = trainer.init()
  start = jax.tree.map(lambda x: x.copy(), state.params)
  before = float(trainer.decoder_drift(start, start)["decoder/overlap_planted"])
  for _ in range(config.steps):
    state, _ = trainer.train_step(state)
  after = trainer.decoder_drift(start, state.params)
  assert before < 0.2
  assert float(after["decoder/overlap_planted"]) > 0.8
  assert float(after["decoder/overlap_start"]) < 0.5  # it left its own start to get there


def test_the_decoder_weight_decay_shrinks_the_decoder_weights_only():
  config = TrainConfig(squash_z=False, decoder_init="random", tasks=("a",), n_synergies=3)
  params = assemble.trainer(config).initial_params()
  zero = jax.tree.map(jnp.zeros_like, params)
  plain = ppo.optimizer(config)
  decayed = ppo.optimizer(config.replace(decoder_weight_decay=2.0))
  updates, _ = decayed.update(zero, decayed.init(params), params)
  kernel = lambda tree: tree["params"]["synergy_decoder"]["synergies"]["kernel"]
  np.testing.assert_allclose(kernel(updates), -config.learning_rate * 2.0 * kernel(params),
                             rtol=1e-5)
  moved = [jax.tree_util.keystr(k) for k, v in jax.tree_util.tree_flatten_with_path(updates)[0]
           if np.abs(np.asarray(v)).max() > 0]
  assert moved == ["['params']['synergy_decoder']['synergies']['kernel']"]
  assert Method.of(config.replace(decoder_weight_decay=3.0)).name == "DiscoSyn3-L-wd3"
  # a frozen decoder is not decayed: the optimiser state of a frozen run without decay
  frozen = config.replace(freeze_decoder=True)
  assert jax.tree.structure(ppo.optimizer(frozen).init(params)) == jax.tree.structure(
      ppo.optimizer(frozen.replace(decoder_weight_decay=2.0)).init(params))
  # without decay: Adam's state as every earlier run has it (their checkpoints restore)
  assert jax.tree.structure(plain.init(params)) == jax.tree.structure(optax.multi_transform(
      {k: optax.chain(optax.clip_by_global_norm(1.0), optax.adam(1e-3))
       for k in ("policy", "discriminator")} | {"frozen": optax.set_to_zero()},
      lambda p: {"params": {n: jax.tree.map(lambda _: "discriminator" if n == "discriminator"
                                            else "policy", sub) for n, sub in p["params"].items()}}
  ).init(params))


# -- the initial decoder, rebuilt -------------------------------------------------------
@pytest.mark.parametrize("decoder", ["linear", "mlp"])
def test_the_initial_decoder_is_rebuilt_from_the_config_alone(decoder):
  config = TrainConfig(squash_z=False, decoder_init="random", tasks=("a", "b"), n_synergies=3, decoder=decoder, seed=7,
                       decoder_hidden=(16, 16))
  from_trainer = assemble.trainer(config).initial_params()["params"]["synergy_decoder"]
  rebuilt = networks.random_decoder(config, 20)
  jax.tree.map(np.testing.assert_array_equal, rebuilt, from_trainer)
  basis = discovery.initial_basis(config, 20)
  expected = diagnostics.synergy_basis(assemble.trainer(config).model,
                                       assemble.trainer(config).initial_params())
  np.testing.assert_allclose(basis, expected, atol=1e-6)


def test_the_matched_decoder_has_the_learned_scale_in_the_initial_subspace():
  rng = np.random.default_rng(1)
  learned = {"synergies": {"kernel": rng.normal(size=(3, 20)).astype(np.float32),
                           "bias": rng.normal(size=20).astype(np.float32)},
             "log_std": np.full(20, -1.0, np.float32)}
  start = {"synergies": {"kernel": rng.normal(size=(3, 20)).astype(np.float32),
                         "bias": np.zeros(20, np.float32)}, "log_std": np.zeros(20, np.float32)}
  matched = fitting.in_subspace_of(learned, start)
  w, w0, wm = (d["synergies"]["kernel"].T for d in (learned, start, matched))
  assert float(diagnostics.overlap(wm, w0)) == pytest.approx(1.0, abs=1e-5)
  np.testing.assert_allclose(np.linalg.svd(wm, compute_uv=False),
                             np.linalg.svd(w, compute_uv=False), rtol=1e-5)
  np.testing.assert_array_equal(matched["synergies"]["bias"], learned["synergies"]["bias"])
  np.testing.assert_array_equal(matched["log_std"], learned["log_std"])


# -- the controls, end to end at the ci scale ----------------------------------------------
def test_the_controls_build_run_and_show_in_the_report(tmp_path):
  sets = {"set1": ("a",)}
  plan = {s.meta["method"]: s for s in paper.Planner(tmp_path, "ci", 0, sets).plan("discosyn-set1")}
  random = plan["Random3-L"].config
  assert random.squash_z and random.freeze_decoder and not random.decoder_from
  assert plan["Random3-L-zfree"].config == random.replace(squash_z=False)
  assert plan["Random3-L-matched"].config.replace(decoder_from="") == random
  assert "Random3-NL-zfree" in plan and "Random3-NL-matched" not in plan  # linear only
  methods = ["DiscoSyn3-L", "Random3-L-zfree", "Random3-L-matched"]
  paper.run("discosyn-set1", tmp_path, "ci", task_sets=sets,
            methods=methods[1:], log=lambda *a: None)
  folder = lambda m: tmp_path / f"{m.lower()}-set1-seed0"
  for m in methods:
    assert json.loads((folder(m) / "experiment.json").read_text())["method"] == m
  # the matched control ran the learned decoder's scale and bias in the random start's subspace
  read = lambda m: checkpoints.read_arrays(folder(m) / "final", DECODER)
  learned, used = read("DiscoSyn3-L"), read("Random3-L-matched")
  start = networks.random_decoder(random, 20)["synergies"]["kernel"]
  np.testing.assert_allclose(used["synergies.bias"], learned["synergies.bias"], atol=1e-6)
  assert float(diagnostics.overlap(used["synergies.kernel"].T, start.T)) == pytest.approx(1, abs=1e-5)
  np.testing.assert_allclose(np.linalg.svd(used["synergies.kernel"], compute_uv=False),
                             np.linalg.svd(learned["synergies.kernel"], compute_uv=False),
                             rtol=1e-4)
  text = report.write([tmp_path], tmp_path / "report", with_tsne=False).read_text()
  table = text.split("## Is the synergy space discovered?")[1].split("\n## ")[0]
  rows = {m: next(line for line in table.splitlines() if line.startswith(f"| {m} | set1 |"))
          for m in methods}
  assert all(row.endswith("| 0.15 |") for row in rows.values())
  # a frozen control stays at its start; one seed has no pairs
  assert rows["Random3-L-zfree"] == "| Random3-L-zfree | set1 | – | – | 1.00 [1] | – | 0.15 |"


def test_an_annealed_decay_falls_linearly_to_nothing_over_its_train_steps():
  config = TrainConfig(squash_z=False, decoder_init="random", tasks=("a",), n_synergies=3, num_minibatches=2, update_epochs=2,
                       decoder_weight_decay=2.0, decoder_weight_decay_steps=3)
  params = assemble.trainer(config).initial_params()
  zero = jax.tree.map(jnp.zeros_like, params)
  kernel = lambda tree: tree["params"]["synergy_decoder"]["synergies"]["kernel"]
  optimizer = ppo.optimizer(config)
  state = optimizer.init(params)
  shrink = []  # the decay applied at each optimiser update, 4 per train step
  for _ in range(14):
    updates, state = optimizer.update(zero, state, params)
    shrink.append(float(np.mean(kernel(updates) / kernel(params))) / -config.learning_rate)
  np.testing.assert_allclose(shrink[:12], 2.0 * (1 - np.arange(12) / 12), atol=1e-5)
  assert shrink[12:] == [0.0, 0.0]  # off after its 3 train steps
  assert Method.of(config).name == "DiscoSyn3-L-wd2a3"


def test_the_decayed_variant_is_planned_beside_the_papers_update_with_its_own_matched_control(tmp_path):
  steps = paper.Planner(tmp_path, "ci", 0, {"planted_slack": ("a",)}).plan("discosyn-planted_slack")
  plan = {s.meta["method"]: s for s in steps}
  decayed = plan["DiscoSyn3-L-wd8a200"].config
  assert (decayed.decoder_weight_decay, decayed.decoder_weight_decay_steps) == (8.0, 200)
  assert decayed.replace(decoder_weight_decay=0.0, decoder_weight_decay_steps=0) == \
      plan["DiscoSyn3-L"].config  # the paper's update otherwise
  # one Random3-L for both (a frozen decoder is never decayed), a matched control for each
  assert [s.meta["method"] for s in steps].count("Random3-L") == 1
  assert plan["Random3-L-matched-wd8a200"].needs == (
      "random3-l-matched-wd8a200-decoder-planted_slack-seed0",)
  assert "DiscoSyn3-NL-wd8a200" not in plan  # the decay is measured on linear decoders only
  hand = paper.Planner(tmp_path, "ci", 0).plan("discosyn-set1")  # not a row of the hand's tables
  assert not any("wd" in s.meta["method"] for s in hand)
  with pytest.raises(ValueError, match="a frozen decoder is not decayed"):
    decayed.replace(freeze_decoder=True).validate()
  with pytest.raises(ValueError, match="anneals a decoder_weight_decay"):
    decayed.replace(decoder_weight_decay=0.0).validate()


def test_the_gpu_check_trains_a_tables_rows_as_the_experiment_does():
  from benchmarks.gpu import gpu_check

  got = gpu_check.configs(["DiscoSyn3-L-reward", "Random3-L-zfree"], "set1", "gpu", 0, "mjx")
  default, control = got["DiscoSyn3-L-reward"], got["Random3-L-zfree"]
  assert default.backend == control.backend == "mjx"
  assert default.num_envs == control.num_envs == paper.SCALES["gpu"].train["num_envs"]
  assert default.decoder_init == "reward" and not default.freeze_decoder
  assert control.freeze_decoder and not control.squash_z and control.decoder_init == "random"
  assert default.replace(backend="auto") == presets.preset("set1-disco3-linear").replace(
      tasks=default.tasks, seed=0, **paper.SCALES["gpu"].train_for("set1"))
  with pytest.raises(ValueError, match="not rows of table2: DiscoSyn3-L-reward"):
    gpu_check.configs(["DiscoSyn3-L-reward"], "set2", "gpu", 0, "mjx")
