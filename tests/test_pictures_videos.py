"""Synergy pictures and policy videos, rendered offscreen for real (EGL; .ci/run installs it)."""

import imageio.v3 as iio
import numpy as np
import pytest
from PIL import Image

from discosyn_jax import assemble, tasks
from discosyn import cli
from discosyn_jax import config as config_lib
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import hands
from discosyn_jax.run import checkpoints, layout
from discosyn_jax.training.trainer import Trainer
from discosyn_jax.viz import synergy_pictures, videos

# imageio reads a video back through an ffmpeg subprocess; JAX warns about any fork, here
# harmlessly (exec follows). videos.write_video silences it for its own writer.
pytestmark = pytest.mark.filterwarnings("ignore:os.fork:RuntimeWarning")

TINY = TrainConfig(squash_z=False, decoder_init="random", tasks=("valve1",), n_synergies=2, policy_hidden=(16,), value_hidden=(16,),
                   discriminator_hidden=(16,), decoder_hidden=(16,), num_envs=2, unroll_length=4,
                   num_minibatches=2, update_epochs=1, eval_envs=2, backend="native")


def saved_run(run_dir, config, envs=None):
  """A run directory holding the initial state as its final checkpoint: the pictures and
  videos read a run the same way whether it trained for a minute or not at all."""
  run_dir.mkdir(parents=True, exist_ok=True)
  config_lib.save(config, run_dir / layout.CONFIG_FILE)
  trainer = Trainer(config, envs) if envs is not None else assemble.trainer(config)
  state = trainer.init()
  checkpoints.save(run_dir, state, config.keep_checkpoints, final=True)
  return trainer, state


def assert_not_blank(image):
  image = np.asarray(image, dtype=float)
  assert image.std() > 10, "one flat colour"
  assert len(np.unique(image.reshape(-1, image.shape[-1]), axis=0)) > 50, "a handful of colours"


@pytest.fixture(scope="module")
def linear_run(tmp_path_factory):
  run_dir = tmp_path_factory.mktemp("runs") / "linear"
  # the trainer returned has 20-step episodes (short videos); the CLI reloads the run as saved
  short = tasks.make("valve1", backend="native", episode_length=20)
  return (run_dir, *saved_run(run_dir, TINY, [short]))


def test_settle_holds_the_commanded_posture_of_the_bare_hand():
  model = synergy_pictures.hand_model()
  assert model.nq == 24  # the hand alone: no object joints
  assert hands.actuator_names(model) == hands.actuators("shadow20")
  action = np.random.default_rng(0).uniform(-0.8, 0.8, model.nu)
  data = synergy_pictures.settle(model, action)
  assert np.abs(data.qvel).max() < 1e-3
  lo, hi = model.actuator_ctrlrange.T
  target = (hi + lo) / 2 + action * (hi - lo) / 2
  joints = [model.jnt_qposadr[model.actuator_trnid[i, 0]] for i in range(model.nu)]
  np.testing.assert_allclose(data.qpos[joints], target, atol=0.1)


def test_synergies_command_draws_postures_and_the_linear_matrix(linear_run, tmp_path, capsys):
  run_dir, trainer, state = linear_run
  out = tmp_path / "pictures"
  assert cli.main(["synergies", str(run_dir), "--out", str(out), "--k", "1.5"]) == 0
  assert capsys.readouterr().out.split() == [str(out / "postures.png"), str(out / "matrix.png")]
  postures = Image.open(out / "postures.png").convert("RGB")
  assert postures.width > 400 and postures.height > 300  # 2 rows x 3 columns of views
  assert_not_blank(postures)
  matrix = np.asarray(Image.open(out / "matrix.png").convert("RGB"), dtype=int)
  red = (matrix[..., 0] - matrix[..., 2] > 80).mean()
  blue = (matrix[..., 2] - matrix[..., 0] > 80).mean()
  assert red > 0.01 and blue > 0.01  # a random W has weights of both signs

  # the pictures themselves: z = -k and +k decode to different postures, 0 to the bias
  actions = synergy_pictures.decoded_actions(trainer, state.params, 1.5)
  bias = np.asarray(state.params["params"]["synergy_decoder"]["synergies"]["bias"])
  np.testing.assert_allclose(actions[:, 1], np.broadcast_to(np.clip(bias, -1, 1), (2, 20)), atol=1e-6)
  images = synergy_pictures.posture_images(actions, 48, 64)
  assert images.shape == (2, 3, 48, 64, 3)
  for row in images:
    assert_not_blank(row[0])
    assert np.abs(row[0].astype(int) - row[2].astype(int)).mean() > 1

  # pictures already there are kept unless --force
  before = (out / "postures.png").read_bytes()
  assert cli.main(["synergies", str(run_dir), "--out", str(out)]) == 2
  assert "already exists" in capsys.readouterr().err
  assert (out / "postures.png").read_bytes() == before


def test_mlp_decoder_gets_postures_only(tmp_path):
  config = TINY.replace(decoder="mlp")
  trainer = assemble.trainer(config)
  paths = synergy_pictures.write(trainer, trainer.init().params, tmp_path, height=48, width=64)
  assert [p.name for p in paths] == ["postures.png"]
  assert sorted(p.name for p in tmp_path.iterdir()) == ["postures.png"]


def test_identity_decoder_has_no_synergies_to_picture(tmp_path, capsys):
  run_dir = tmp_path / "ppo"
  saved_run(run_dir, TINY.replace(decoder="identity", n_synergies=20, alpha2=0.0, alpha3=0.0))
  assert cli.main(["synergies", str(run_dir)]) == 2
  err = capsys.readouterr().err.strip().splitlines()
  assert len(err) == 1 and err[0].startswith("discosyn: error:") and "identity" in err[0]
  assert not (run_dir / "synergies").exists()


def test_policy_video_shows_one_frame_per_control_step(linear_run, tmp_path):
  run_dir, trainer, state = linear_run
  out = tmp_path / "valve1.mp4"
  written = videos.render_policy(trainer, state, "valve1", out, episodes=1, height=48, width=64,
                                 cameras=("front",))
  assert written["steps"] == [20] and written["frames"] == 20
  frames = iio.imread(out)
  assert frames.shape == (20, 48, 64, 3)
  for frame in frames[::5]:
    assert_not_blank(frame)
  assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).mean() > 1  # the hand moved
  assert iio.immeta(out)["fps"] == pytest.approx(25)  # real time: one frame per 0.04 s


def test_video_writer_writes_mp4_and_gif(tmp_path):
  frames = [np.full((32, 48, 3), 10 * t, np.uint8) for t in range(6)]
  for name in ("a.mp4", "a.gif"):
    assert videos.write_video(iter(frames), tmp_path / name, fps=25) == 6
    back = iio.imread(tmp_path / name)
    assert back.shape[0] == 6 and back.shape[1:3] == (32, 48)
    assert abs(float(back[-1].mean()) - 50) < 3


def test_render_command_frame_and_bad_input(linear_run, tmp_path, capsys):
  run_dir, _, _ = linear_run
  # a checkpoint's pictures go beside the run's own, named by its step
  assert cli.main(["render", str(run_dir / "final"), "--task", "valve1", "--frame", "30"]) == 0
  png = run_dir / "videos" / "valve1-step0-frame30.png"
  assert capsys.readouterr().out.splitlines()[-1] == f"{png} (1 frames)"
  image = Image.open(png)
  assert image.size == (960, 360)  # two cameras side by side
  assert_not_blank(image.convert("RGB"))
  capsys.readouterr()
  for argv, message in (
      (["--task", "valve3"], "not one of this run's tasks: valve1"),
      (["--task", "valve1", "--frame", "30", "--out", str(png)], "already exists"),
      (["--task", "valve1", "--out", str(tmp_path / "v.avi")], "must end in .mp4 or .gif"),
  ):
    assert cli.main(["render", str(run_dir), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
  assert cli.main(["render", str(tmp_path), "--task", "valve1"]) == 2
  assert "not a run directory" in capsys.readouterr().err
  assert [p.name for p in (run_dir / "videos").iterdir()] == [png.name]


def test_a_run_without_scenes_is_refused_in_one_line(tmp_path, capsys):
  config = TINY.replace(tasks=("planted0",), n_synergies=3)
  run = tmp_path / "run"
  saved_run(run, config)
  assert cli.main(["synergies", str(run)]) == 2
  assert cli.main(["render", str(run), "--task", "planted0"]) == 2
  err = capsys.readouterr().err.splitlines()
  assert err[-2:] == [f"discosyn: error: {run}: planted0 has no scene to {what} (a pure-JAX task, "
                      "as the planted test bed's)" for what in ("picture", "film")]
  assert sorted(p.name for p in run.iterdir()) == ["config.json", "final"]  # nothing written
