"""Any MJCF hand (discosyn_jax/env/hands.py): the shipped hands run the valves on both backends,
every hand's palm lands where ours does, our hand's scenes are the very models of before,
a hand file of one's own (meshes beside it) works from its own folder, and a file that is
no hand is refused in one line."""

import pathlib

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from discosyn_jax import tasks
from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.env import assets, hands, scene
from discosyn_jax.run import layout
from tests import helpers
from tests.helpers import run_episode

SET1 = ("valve0", "valve1", "valve2", "valve3")
SIZES = {"shadow20": (24, 20), "leap16": (16, 16)}  # hand joints, actuators
TINY = ["--num-envs", "2", "--unroll-length", "4", "--minibatches", "2", "--epochs", "1",
        "--steps", "1", "--eval-envs", "2", "--eval-every", "0", "--checkpoint-every", "0",
        "--backend", "native", "--no-progress"]


@pytest.mark.parametrize("hand", hands.SHIPPED)
@pytest.mark.parametrize("name", SET1)
def test_each_valve_runs_on_each_shipped_hand(hand, name):
  env = helpers.env(name, hand=hand)
  joints, actuators = SIZES[hand]
  assert (env.observation_size, env.action_size) == (joints + 3, actuators)
  uniform = lambda t, key, batch: jax.random.uniform(key, (batch, actuators), minval=-1, maxval=1)
  _, states = run_episode(env, jax.random.split(jax.random.PRNGKey(0), 2), uniform, steps=3)
  assert states.obs.shape == (3, 2, joints + 3)
  for leaf in jax.tree.leaves((states.obs, states.reward, states.metrics)):
    assert np.isfinite(np.asarray(leaf)).all()


@pytest.mark.parametrize("name", SET1[:3])
def test_leap16_steps_on_mjx(name):
  """Three random steps of two envs on MJX from the native reset (valve3: below)."""
  native, mjx = helpers.env(name, hand="leap16"), helpers.env(name, "mjx", hand="leap16")
  start = helpers.on_mjx(native, mjx, jax.jit(jax.vmap(native.reset))(
      jax.random.split(jax.random.PRNGKey(0), 2)))
  actions = jax.random.uniform(jax.random.PRNGKey(1), (3, 2, 16), minval=-1, maxval=1)
  step = jax.vmap(mjx.step)
  states = jax.jit(lambda s, a: jax.lax.scan(lambda s, a: (step(s, a),) * 2, s, a)[1])(start, actions)
  assert states.obs.shape == (3, 2, 19)
  assert np.isfinite(np.asarray(states.obs)).all()
  assert not np.asarray(states.metrics["diverged"]).any()


def test_leap16_sweep_turns_valve3_alike_on_both_backends():
  """leap16's scripted sweep (no wrist: the fingers dip and sweep sideways) turns valve3, on
  MJX as on MuJoCo C: hand joints within 0.02 rad, the valve within 0.05 rad over 50 steps
  (measured 0.007 and 0.006; the tolerances of valve3 on our hand, test_backends.py)."""
  native, mjx = helpers.env("valve3", hand="leap16"), helpers.env("valve3", "mjx", hand="leap16")
  start = jax.jit(native.reset)(jax.random.PRNGKey(5))
  actions = jnp.asarray(native.task.motion.actions(50, native.dt, "leap16"))
  out = {}
  for env, state in ((native, start), (mjx, helpers.on_mjx(native, mjx, start))):
    step = lambda s, a, env=env: (env.step(s, a),) * 2
    states = jax.jit(lambda s, a: jax.lax.scan(step, s, a)[1])(state, actions)
    out[env.backend] = np.asarray(jax.vmap(env.physics.view)(states.pipeline_state).qpos)
  hand_q, valve_q = hands.qpos_indices(native.mj_model), native.task.valve_qpos
  assert out["native"][-1, valve_q] - out["native"][0, valve_q] > 0.5  # turned counter-clockwise
  np.testing.assert_allclose(out["mjx"][:, hand_q], out["native"][:, hand_q], atol=0.02)
  np.testing.assert_allclose(out["mjx"][:, valve_q], out["native"][:, valve_q], atol=0.05)


@pytest.mark.parametrize("hand", hands.SHIPPED)
@pytest.mark.parametrize("mount", ["down", "up"])
def test_every_palm_lands_where_ours_does(hand, mount):
  moved = {"down": hands.PALM_DOWN, "up": hands.PALM_UP}[mount]
  model = scene.load_spec("hand", hand, moved).compile()
  data = mujoco.MjData(model)
  mujoco.mj_kinematics(model, data)
  site = data.site(hands.PREFIX + hands.PALM_SITE_NAME)
  pos, rot = hands.PALM_SITE
  move_pos, move_rot = moved
  np.testing.assert_allclose(site.xpos, move_rot @ pos + move_pos, atol=1e-9)
  np.testing.assert_allclose(site.xmat.reshape(3, 3), move_rot @ rot, atol=1e-9)
  assert model.nu == SIZES[hand][1] and len(hands.joint_ids(model)) == SIZES[hand][0]


def test_our_hand_composes_the_same_model_as_one_mjcf_file():
  """The composed scene (arena, hand attached under its prefix, object) is the model the
  three files make when included into one, array for array: runs on our hand are those of
  before hands.py, and its placement is the identity."""
  assert hands.placement(hands.load("shadow20")) == ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
  parts = ["arena.xml", "hands/shadow20.xml", "objects/valve3.xml"]
  includes = "".join(f'<include file="{assets.xml_path(p)}"/>' for p in parts)
  one = mujoco.MjSpec.from_string(f"<mujoco>{includes}</mujoco>").compile()
  composed = scene.load_spec("valve3").compile()
  for name in dir(one):
    value = getattr(one, name)
    if isinstance(value, np.ndarray) and not name.startswith(("name", "_")):  # names aside
      np.testing.assert_array_equal(getattr(composed, name), value, err_msg=name)


def _hand_file(folder: pathlib.Path, body: str = "", actuator: str = "",
               name: str = "myhand.xml") -> pathlib.Path:
  """A two-finger hand with a mesh palm, its mesh in an assets/ folder beside the file."""
  (folder / "assets").mkdir(exist_ok=True)
  (folder / "assets" / "palm.obj").write_text(
      "v -0.03 -0.01 0\nv 0.03 -0.01 0\nv 0 0.01 0\nv 0 0 0.08\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n")
  path = folder / name
  path.write_text(f"""<mujoco model="myhand">
  <compiler meshdir="assets/"/>
  <asset><mesh name="palm" file="palm.obj"/></asset>
  <worldbody>
    <body name="palm">
      <geom type="mesh" mesh="palm" conaffinity="1"/>
      <site name="palm_center" pos="0 -0.01 0.04"/>
      {body or '''<body name="f1" pos="0.02 0 0.08"><joint name="f1" axis="1 0 0" range="0 1.5"/>
        <geom type="capsule" size="0.01 0.03" pos="0 0 0.03" conaffinity="1"/></body>
      <body name="f2" pos="-0.02 0 0.08"><joint name="f2" axis="1 0 0" range="0 1.5"/>
        <geom type="capsule" size="0.01 0.03" pos="0 0 0.03" conaffinity="1"/></body>'''}
    </body>
  </worldbody>
  <actuator>{actuator or '''<position joint="f1" kp="1" ctrlrange="0 1.5"/>
    <position joint="f2" kp="1" ctrlrange="0 1.5"/>'''}</actuator>
</mujoco>""")
  return path


def test_a_hand_of_ones_own_trains_from_its_file_and_is_read_again(tmp_path, monkeypatch):
  folder = tmp_path / "hands"
  folder.mkdir()
  _hand_file(folder)
  monkeypatch.chdir(tmp_path)  # a relative path, made absolute in the run's config
  run = tmp_path / "run"
  assert cli.main(["train", "--hand", "hands/myhand.xml", "--tasks", "valve3", *TINY,
                   "--out", str(run)]) == 0
  config = config_lib.load(run / layout.CONFIG_FILE)
  assert config.hand == str(folder / "myhand.xml")
  env = tasks.make("valve3", hand=config.hand)
  assert (env.observation_size, env.action_size) == (2 + 3, 2)
  # the file's geoms touched everything; in the scene they touch objects only, as ours
  hand_geoms = [g for g in range(env.mj_model.ngeom)
                if env.mj_model.body(env.mj_model.geom_bodyid[g]).name.startswith(hands.PREFIX)]
  assert len(hand_geoms) == 3
  assert all((env.mj_model.geom_contype[g], env.mj_model.geom_conaffinity[g]) == (1, 0)
             for g in hand_geoms)
  monkeypatch.chdir(folder / "assets")  # read again from elsewhere
  assert cli.main(["eval", str(run), "--episodes", "2"]) == 0


NOT_A_HAND = {
    "noact": (dict(actuator="<!-- none -->"), "the MJCF has no actuators"),
    "ball": (dict(body='<body name="f1"><joint name="f1" axis="1 0 0" range="0 1"/><geom size="0.01"/>'
                       '<body><joint name="loose" type="ball"/><geom size="0.01"/></body></body>',
                  actuator='<position joint="f1" ctrlrange="0 1"/>'),
             "joint loose is free or a ball"),
    "unbounded": (dict(actuator='<motor name="m1" joint="f1"/>'), "actuator m1 has no ctrlrange"),
    "broken": (dict(body="<body"), "hand "),
}


@pytest.mark.parametrize("case", NOT_A_HAND)
def test_a_file_that_is_no_hand_is_one_line_and_exit_2(tmp_path, capsys, case):
  changes, message = NOT_A_HAND[case]
  path = _hand_file(tmp_path, **changes)
  run = tmp_path / "run"
  assert cli.main(["train", "--hand", str(path), *TINY, "--out", str(run)]) == 2
  err = capsys.readouterr().err.strip()
  assert message in err and len(err.splitlines()) == 1
  assert not run.exists()


@pytest.mark.parametrize("spec, message", [
    ("leap17", "a hand is one of shadow20, leap16 or an MJCF file"),
    ("missing.xml", "no hand MJCF file missing.xml"),
    ("HAND:nosite", "no site named 'nosite' marks the palm"),
])
def test_a_wrong_hand_name_or_palm_site_is_refused(tmp_path, spec, message):
  spec = spec.replace("HAND", str(_hand_file(tmp_path)))
  with pytest.raises(ValueError, match=message):
    hands.load(spec)


def test_the_run_config_keeps_the_hand_and_old_configs_had_ours():
  assert config_lib.ADDED["hand"] == "shadow20" == config_lib.TrainConfig().hand
  with pytest.raises(ValueError, match="no hand given"):
    config_lib.TrainConfig(squash_z=False, decoder_init="random", hand="").validate()


def test_an_experiment_on_another_hand_names_its_folders_and_configs_after_it(tmp_path):
  from discosyn_jax.experiments import paper, report_runs

  steps = paper.Planner(tmp_path, "cpu", 0, hand="leap16").plan("discosyn-set1")
  assert "discosyn3-l-objects-set1-leap16-seed0" in {s.name for s in steps}
  assert all(s.name.endswith("-leap16-seed0") for s in steps)
  assert {s.config.hand for s in steps if hasattr(s, "config")} == {"leap16"}
  ours = paper.Planner(tmp_path, "cpu", 0).plan("discosyn-set1")
  assert "discosyn3-l-objects-set1-seed0" in {s.name for s in ours}
  assert {s.config.hand for s in ours if hasattr(s, "config")} == {"shadow20"}
  # the report's chance level and initial decoders use the run's own action size
  assert report_runs.action_size("valve3", "leap16") == 16
  assert report_runs.action_size("planted0", "leap16") == 20  # a pure-JAX task's own
