"""A run's logs: JSONL read back, TensorBoard event files, training-curve PNGs."""

import json

import numpy as np
import pytest
from PIL import Image

from discosyn_jax.config import TrainConfig
from discosyn_jax.run import layout, logs, progress
from discosyn_jax.training import loop
from discosyn_jax.training.trainer import Trainer
from discosyn_jax.viz import plots
from tests.helpers import tensorboard_scalars
from tests.toy_env import ReachAction

TOY = TrainConfig(squash_z=False, decoder_init="random", tasks=("reach_a", "reach_b"), n_synergies=2, policy_hidden=(8,), value_hidden=(8,),
                  discriminator_hidden=(8,), num_envs=4, unroll_length=5, num_minibatches=2,
                  update_epochs=1, steps=4, eval_every=2, eval_envs=2, checkpoint_every=0)


@pytest.fixture(scope="module")
def toy_run(tmp_path_factory):
  """Four train steps on two toy tasks (episodes of 5 steps end in every rollout)."""
  run_dir = tmp_path_factory.mktemp("runs") / "toy"
  trainer = Trainer(TOY, envs=[ReachAction(0.3, episode_length=5), ReachAction(-0.3, episode_length=5)])
  loop.train(trainer, run_dir, progress=False, log=lambda *_: None,  # the assembler's hook
             on_end=lambda: plots.run_curves(run_dir, run_dir / layout.PLOTS_DIR))
  return run_dir


def test_read_jsonl_keeps_rows_and_drops_only_a_cut_last_line(tmp_path):
  path = tmp_path / "m.jsonl"
  path.write_text('{"step": 1, "loss": 0.5}\n{"step": 2, "loss": 0.25}\n{"step": 3, "lo')
  assert logs.read_jsonl(path) == [{"step": 1, "loss": 0.5}, {"step": 2, "loss": 0.25}]
  path.write_text('{"step": 1}\nnot json\n{"step": 3}\n')
  with pytest.raises(ValueError, match="line 2"):
    logs.read_jsonl(path)
  path.write_text('[1, 2]\n')
  with pytest.raises(ValueError, match="not a JSON object"):
    logs.read_jsonl(path)
  with pytest.raises(ValueError, match="does not exist"):
    logs.read_jsonl(tmp_path / "missing.jsonl")


def test_an_archived_log_reads_as_the_log_itself(toy_run, tmp_path):
  """docs/results keeps metrics.jsonl compressed (`xz -9`): readers get the same rows, and a
  log that is neither plain nor archived has none."""
  import lzma

  plain = toy_run / layout.METRICS_FILE
  rows = logs.read_log(plain)
  assert rows and rows == logs.read_jsonl(plain)
  kept = tmp_path / layout.METRICS_FILE
  (tmp_path / (layout.METRICS_FILE + logs.ARCHIVED)).write_bytes(lzma.compress(plain.read_bytes()))
  assert not kept.exists() and logs.read_log(kept) == rows
  assert logs.read_log(tmp_path / layout.EVAL_FILE) == []
  # a record's archive (`archive`): the rows a record keeps (all four here: the last ones),
  # without the loss diagnostics, fractions to 5 significant digits, counts and steps exact;
  # the log itself stays
  archived = logs.read_jsonl(logs.archive(plain, TOY.unroll_length))
  assert plain.is_file() and len(archived) == len(rows)
  for row, kept_row in zip(rows, archived):
    assert "loss" in row and set(kept_row) == set(row) - {"loss", "env_steps_per_s"} - {
        k for k in row if k.endswith(("/approx_kl", "/clip_fraction", "/policy_loss", "/value_loss"))}
    for key, value in kept_row.items():
      value = row[key]
      exact = not isinstance(value, float) or value.is_integer()
      assert kept_row[key] == (value if exact else pytest.approx(value, rel=1e-4, abs=0))
      if not exact:
        # at most 5 significant digits: printing it with 5 gives it back (13482.0 included)
        assert float(f"{kept_row[key]:.5g}") == kept_row[key]
  # read at the archive's precision, the log's kept rows and its archive are the same (the
  # report of a run and of its record agree to the digit)
  assert logs.kept(logs.read_log(plain, as_archived=True), TOY.unroll_length) == archived
  assert logs.read_log(kept.with_name("none.jsonl"), as_archived=True) == []
  # thinning the archive again changes nothing
  assert logs.read_jsonl(logs.archive(plain.with_name(plain.name + logs.ARCHIVED),
                                      TOY.unroll_length)) == archived


def test_a_record_keeps_an_even_sample_the_last_steps_and_each_first_reward():
  unroll = 20
  rows = [{"step": s, "env_steps": 40 * s, "a/reward": s / 7, "a/policy_loss": 0.5, "loss": 1.5,
           "a/first_reward_t": 9 if s == 37 else (3 if s > 37 else unroll),
           "b/first_reward_t": 0 if s == 1 else unroll, "grad_norm/heads": 0.25}
          for s in range(1, 201)]
  kept = logs.kept(rows, unroll)
  steps = [r["step"] for r in kept]  # b paid in the first step, a in the 37th
  assert steps == sorted(set(range(4, 185, logs.RECORD_EVERY)) | {1, 37} | set(range(185, 201)))
  assert all(set(r) == {"step", "env_steps", "a/reward", "a/first_reward_t", "b/first_reward_t",
                        "grad_norm/heads"} for r in kept)
  assert logs.kept(kept, unroll) == kept and logs.kept([], unroll) == []
  # an even sample: a mean over a window moves by less than a step's change
  window = [r["a/reward"] for r in rows if r["step"] <= 100]
  assert abs(np.mean([r["a/reward"] for r in kept if r["step"] <= 100]) - np.mean(window)) < 2 / 7


def test_tensorboard_holds_the_jsonl_numbers_over_env_steps(toy_run):
  metrics = logs.read_jsonl(toy_run / layout.METRICS_FILE)
  evals = logs.read_jsonl(toy_run / layout.EVAL_FILE)
  assert [r["step"] for r in metrics] == [1, 2, 3, 4] and [r["step"] for r in evals] == [2, 4]
  scalars = tensorboard_scalars(toy_run / layout.TENSORBOARD_DIR)
  per_step = 2 * 4 * 5  # tasks x envs x unroll
  assert scalars["train/loss"] == [(r["env_steps"], pytest.approx(r["loss"])) for r in metrics]
  assert [s for s, _ in scalars["train/loss"]] == [per_step * k for k in (1, 2, 3, 4)]
  assert scalars["reach_b/return"] == [(r["env_steps"], pytest.approx(r["reach_b/return"]))
                                       for r in metrics]
  assert scalars["eval/reach_a/success"] == [(r["env_steps"], pytest.approx(r["reach_a/success"]))
                                             for r in evals]
  assert "train/step" not in scalars and "train/wall_s" not in scalars


def test_the_run_ends_with_curve_pngs_and_run_curves_redraws_them(toy_run, tmp_path):
  drawn = sorted(p.name for p in (toy_run / layout.PLOTS_DIR).iterdir())
  assert drawn == ["losses.png", "return.png", "success.png"]
  paths = plots.run_curves(toy_run, tmp_path / "out")
  assert [p.name for p in paths] == ["success.png", "return.png", "losses.png"]
  for path in paths:
    image = np.asarray(Image.open(path).convert("RGB"), dtype=float)
    assert image.shape[0] > 200 and image.shape[1] > 400
    # drawn lines: colours other than the white background and black text
    coloured = (image.max(axis=-1) - image.min(axis=-1)) > 60
    assert coloured.mean() > 0.001, path


def test_curves_of_a_folder_without_a_run_or_without_steps_fail(tmp_path):
  with pytest.raises(ValueError, match="holds no run"):
    plots.run_curves(tmp_path, tmp_path / "out")
  (tmp_path / "config.json").write_text(json.dumps(TOY.to_dict()))
  with pytest.raises(ValueError, match="no training steps"):
    plots.run_curves(tmp_path, tmp_path / "out")
  assert not (tmp_path / "out").exists()


def test_progress_off_a_terminal_is_a_line_every_tenth_of_the_run(capsys):
  bar = progress.bar(True, 5, 40)  # resumed at step 5; pytest's stderr is not a terminal
  for step in range(6, 41):
    bar.set_postfix_str(f"valve1:{step}%", refresh=False)
    bar.update(1)
  bar.close()
  err = capsys.readouterr().err
  assert "\r" not in err
  lines = err.splitlines()
  assert [line.split(",")[0] for line in lines] == [f"step {n}/40" for n in range(8, 41, 4)]
  assert lines[-1].endswith("steps/s valve1:40%")
  assert progress.bar(False, 0, 40) is None
