"""The priors (discosyn_jax/synergies/priors.py): the action directions that move the
objects most, or that change what each task rewards, the same for every seed; each seed's
decoder starts in that subspace with its own scale and bias."""

import json
import pathlib

import numpy as np
import pytest

from discosyn_jax import assemble, tasks
from discosyn_jax import config as config_lib
from discosyn_jax.agent import networks
from discosyn_jax.synergies import diagnostics, fitting, priors, start
from discosyn_jax.experiments import presets
from discosyn_jax.experiments.method import Method

ROOT = pathlib.Path(__file__).resolve().parents[1]
TINY = dict(num_envs=2, unroll_length=4, num_minibatches=2, update_epochs=1, steps=1,
            eval_every=0, eval_envs=2, checkpoint_every=0, backend="native")


@pytest.fixture(autouse=True)
def few_states(monkeypatch):
  """4 random episodes per task, every 25th step: 16 states (the product uses 640)."""
  monkeypatch.setattr(priors, "ENVS", 4)
  monkeypatch.setattr(priors, "EVERY", 25)


@pytest.fixture(scope="module")
def valve3():
  return tasks.make("valve3", backend="native")


def test_the_prior_is_the_directions_that_move_the_object_most(valve3):
  jac = priors.jacobians(valve3, "objects")
  assert jac.shape == (16, 1, 20) and np.isfinite(jac).all()
  assert np.abs(jac).max() > 0  # some push moved the valve
  basis = priors.basis([valve3], 3)
  assert basis.shape == (20, 3)
  np.testing.assert_allclose(basis.T @ basis, np.eye(3), atol=1e-6)
  np.testing.assert_allclose(priors.basis([valve3], 3), basis)  # no seed in it
  # the object moves more along each prior direction than along any direction outside it
  motion = lambda u: float(np.mean(np.sum((jac @ u) ** 2, axis=1)))
  outside = np.linalg.qr(np.eye(20) - basis @ basis.T)[0][:, :17]
  assert min(motion(u) for u in basis.T) >= max(motion(u) for u in outside.T) - 1e-9


def test_a_start_keeps_the_seeds_own_scale_and_bias_in_the_prior_subspace(valve3):
  basis = priors.basis([valve3], 3)
  config = presets.preset("set1-disco3-linear")
  for seed in (0, 1):
    own = networks.random_decoder(config.replace(seed=seed), 20)
    start = priors.start(own, basis)
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
    trainer = assemble.trainer(config)
    starts.append(fitting.basis(fitting.architecture(config.to_dict()),
                                  start.starting_decoder(trainer)))
    random_start = fitting.basis(fitting.architecture(config.to_dict()),
                                   networks.random_decoder(config, 20))
  assert diagnostics.overlap(*starts) == pytest.approx(1.0, abs=1e-5)
  assert diagnostics.overlap(starts[1], random_start) < 0.9  # not the seed's own subspace


def test_the_prior_is_refused_where_it_cannot_start_the_decoder():
  config = presets.preset("set1-disco3-linear-objects")
  assert Method.of(config).name == "DiscoSyn3-L-objects"
  assert Method.of(config.replace(freeze_decoder=True)).name == "Prior3-L-objects"
  default = presets.preset("set1-disco3-linear")  # the reward prior, every linear preset's start
  assert {presets.preset(f"set{n}-disco{b}-linear").decoder_init
          for n, b in ((1, 3), (1, 4), (2, 4), (2, 6))} == {"reward"}
  assert Method.of(default).name == "DiscoSyn3-L-reward"
  # its start is the default's (auto): frozen, the decoder starts at random unless named
  assert Method.of(default.replace(freeze_decoder=True)).name == "Random3-L"
  assert Method.of(default.replace(freeze_decoder=True, decoder_init="reward")).name == "Prior3-L-reward"
  for bad in (dict(decoder="mlp"), dict(decoder_from="x.npz"), dict(decoder_init="pca")):
    with pytest.raises(ValueError):
      config.replace(**bad).validate()
  assert config_lib.ADDED["decoder_init"] == "random"  # what runs of older releases ran
  # TrainConfig's own default is the recommended start, resolved when the config is made
  # (auto: the reward prior for a linear decoder learned from scratch, else random)
  assert config_lib.TrainConfig().decoder_init == "reward"
  assert config_lib.TrainConfig().squash_z
  for other in (dict(decoder="mlp"), dict(decoder="identity", n_synergies=20, alpha2=0.0,
                                          alpha3=0.0), dict(freeze_decoder=True),
                dict(decoder_from="x.npz")):
    assert config_lib.TrainConfig(**other).decoder_init == "random", other
  assert config_lib.TrainConfig(decoder_init="objects").decoder_init == "objects"
  saved = config_lib.TrainConfig().to_dict()  # a config file names the start it ran
  assert saved["decoder_init"] == "reward" and config_lib.TrainConfig.from_dict(saved).validate()
  with pytest.raises(ValueError, match="needs hand tasks"):
    priors.basis([tasks.make("planted0")], 3)


def test_the_prior_of_an_mjx_env_is_measured_on_mujoco_c(valve3):
  """Whatever backend a run trains on, its prior is the reference physics' (and on the CPU):
  an MJX env gives its native twin's directions."""
  mjx_valve3 = tasks.make("valve3", backend="mjx")
  assert priors.reference(mjx_valve3).backend == "native"
  assert priors.reference(valve3) is valve3
  np.testing.assert_array_equal(priors.basis([mjx_valve3], 3),
                                priors.basis([valve3], 3))


def test_chunking_the_pushes_changes_nothing(valve3, monkeypatch):
  """The pushes go through lax.map in chunks (MJX memory): chunking changes nothing."""
  whole = priors.jacobians(valve3, "objects")
  monkeypatch.setattr(priors, "CHUNK", 3)
  np.testing.assert_allclose(priors.jacobians(valve3, "objects"), whole, atol=1e-6)


_PLANTED = """<mujoco><worldbody>
  <body name="hand/finger"><joint name="hand/a0" type="slide"/><joint name="hand/a1" type="slide"
    axis="0 1 0"/><geom size="0.01"/></body>
  <body name="rewarded"><joint name="rewarded" type="slide"/><geom size="0.01"/></body>
  <body name="flung"><joint name="flung" type="slide"/><geom size="0.01"/></body>
</worldbody></mujoco>"""


class PlantedResponse:
  """A hand of two actions and two objects, stepped in pure JAX: action 0 moves the object the
  task rewards (gain 1), action 1 flings the other, unrewarded, three times as hard. The
  pooled object motion favours action 1; the task asks for action 0."""

  action_size, episode_length = 2, 10

  def __init__(self):
    import jax.numpy as jnp
    import mujoco
    from brax.envs.base import State

    from discosyn_jax.env.physics import PhysicsView

    self.mj_model = mujoco.MjModel.from_xml_string(_PLANTED)
    self._jnp, self._state, self._view = jnp, State, PhysicsView
    self.physics = self

  def view(self, qvel):
    return self._view(qpos=qvel, qvel=qvel, sensordata=self._jnp.zeros(0))

  def reset(self, key):
    zero = self._jnp.zeros(())
    return self._state(pipeline_state=self._jnp.zeros(4), obs=self._jnp.zeros(1), reward=zero,
                       done=zero, metrics={})

  def step(self, state, action):
    qvel = self._jnp.stack([action[0], action[1], action[0], 3.0 * action[1]])
    return state.replace(pipeline_state=qvel, reward=qvel[2])


def test_the_task_aware_prior_keeps_the_rewarded_direction_the_object_motion_prior_loses():
  env = PlantedResponse()
  objects, reward = (priors.basis([env], 1, response) for response in ("objects", "reward"))
  assert abs(objects[1, 0]) == pytest.approx(1.0, abs=1e-5)  # the flung object's action
  assert abs(reward[0, 0]) == pytest.approx(1.0, abs=1e-5)  # the task's own
  assert priors.captured(reward, priors.metric(env, "reward")) == pytest.approx(1.0)
  assert priors.captured(objects, priors.metric(env, "reward")) == pytest.approx(
      0.0, abs=1e-6)
  with pytest.raises(ValueError, match="response must be one of objects, reward"):
    priors.basis([env], 1, "velocity")


def test_sharing_gives_each_task_its_direction_where_the_pooled_sum_does_not():
  """Task 0 spreads its response over actions 0-2, tasks 1 and 2 concentrate theirs on
  actions 3 and 4: the sum's top two are those, and task 0 gets nothing; in turns, task 0
  gets one of its directions, and the directions stay orthonormal."""
  m0 = np.diag([1 / 3, 1 / 3, 1 / 3, 0.0, 0.0])
  m1 = np.diag([0.0, 0.0, 0.0, 0.6, 0.4])
  m2 = np.diag([0.0, 0.0, 0.0, 0.4, 0.6])
  pooled = priors.pool([m0, m1, m2], 2, "trace")
  shared = priors.pool([m0, m1, m2], 2, "share")
  assert priors.captured(pooled, m0) == pytest.approx(0.0, abs=1e-9)
  assert priors.captured(shared, m0) == pytest.approx(1 / 3)
  assert priors.captured(shared, m1) == pytest.approx(0.6)
  np.testing.assert_allclose(shared.T @ shared, np.eye(2), atol=1e-9)
  with pytest.raises(ValueError, match="pooling must be one of trace, share"):
    priors.pool([m0], 1, "max")


class PlantedGate(PlantedResponse):
  """One step pays action 1 until action 1, held up for 6 steps, has opened a gate; past it,
  the step pays twice action 0. A uniform random policy seldom opens the gate."""

  episode_length = 20

  def step(self, state, action):
    opened = state.obs[0] + 0.1 * action[1]
    reward = self._jnp.where(opened > 0.5, 2.0 * action[0], action[1])
    return state.replace(obs=opened[None], reward=reward)


def test_the_prior_read_at_a_policys_states_sees_what_only_that_policy_reaches(monkeypatch):
  monkeypatch.setattr(priors, "EVERY", 10)  # states at steps 0 and 10
  env = PlantedGate()
  import jax.numpy as jnp
  opener = lambda obs, key: jnp.broadcast_to(jnp.array([0.0, 1.0]), (obs.shape[0], 2))
  random_states = priors.basis([env], 1, "reward")
  policy_states = priors.basis([env], 1, "reward", acts=[opener])
  assert abs(random_states[1, 0]) == pytest.approx(1.0, abs=1e-5)  # before the gate: action 1
  assert abs(policy_states[0, 0]) == pytest.approx(1.0, abs=1e-5)  # past it: action 0


def test_a_transfer_runs_config_file_says_its_decoder_starts_at_its_decoder_from(tmp_path, capsys):
  """In memory a decoder read from decoder_from has no start of its own ("random": what every
  comparison of configs reads); config.json names where it starts instead."""
  from discosyn import cli, commands

  args = cli.build_parser().parse_args(["train", "--tasks", "valve_cylinder",
                                        "--decoder-from", "shadow20-set1"])
  config = commands.train_config(args)
  assert config.decoder_init == "random" and config.decoder_from == "shadow20-set1"
  path = tmp_path / "config.json"
  config_lib.save(config, path)
  saved = json.loads(path.read_text())
  assert saved["decoder_init"] == config_lib.GIVEN_START == "decoder_from"
  assert config_lib.load(path) == config
  assert Method.of(saved) == Method.of(config)
  # a committed record's config, written before: "random", the same config as written now
  record = config_lib.load(ROOT / "docs/results/paper/transfer-synergies-set1-seed0/config.json")
  config_lib.save(record, tmp_path / "again.json")
  assert config_lib.load(tmp_path / "again.json") == record
  assert config_lib.same_run(config_lib.load(tmp_path / "again.json"), record)
  # a start at decoder_from with none given: refused in one line naming the file
  path.write_text(json.dumps({**saved, "decoder_from": ""}))
  with pytest.raises(ValueError, match=r"config file .*config.json: decoder_init is decoder_from, "
                                       r"but no decoder_from is given"):
    config_lib.load(path)
  assert cli.main(["eval", str(tmp_path)]) == 2
  assert "decoder_init is decoder_from, but no decoder_from is given" in capsys.readouterr().err
