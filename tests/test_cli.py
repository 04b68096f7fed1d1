"""The discosyn command: its help, listing, the demo, bad input."""

import argparse
import subprocess
import sys

import pytest

from discosyn import cli, commands
from discosyn_jax import config as config_lib
from discosyn_jax.checks import BadInput
from discosyn_jax.experiments import presets
from tests.helpers import ROOT


def subcommands(parser):
  (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
  return sub.choices


def test_every_flag_says_what_it_is_and_its_default():
  for name, parser in subcommands(cli.build_parser()).items():
    for action in parser._actions:
      if isinstance(action, argparse._HelpAction):
        continue
      assert action.help, f"{name} {action.dest} has no help"
      takes_value = action.nargs != 0 and not action.required
      if takes_value:  # flags that take a value, and optional positionals
        assert "default" in action.help, f"{name} {action.dest}: {action.help}"
  train = subcommands(cli.build_parser())["train"]
  (preset,) = [a for a in train._actions if a.dest == "preset"]
  assert all(name in preset.help for name in presets.PRESETS)


def test_help_lists_every_command_and_imports_no_jax():
  code = ("import sys; from discosyn import cli; print(cli.build_parser().format_help()); "
          "print('HEAVY', sorted({'jax', 'mujoco', 'brax', 'flax', 'matplotlib'} & set(sys.modules)))")
  out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
  assert out.returncode == 0, out.stderr
  assert out.stdout.splitlines()[-1] == "HEAVY []"
  listed = [line.split()[0] for line in out.stdout.splitlines()  # "    name   what it does"
            if line.startswith("    ") and line[4] != " "]
  assert set(listed) == set(subcommands(cli.build_parser())) >= {"train", "report", "bench"}


def test_tasks_lists_every_task_with_sizes(capsys):
  assert cli.main(["tasks"]) == 0
  out = capsys.readouterr().out
  for name in ("valve0", "valve1", "valve2"):
    (line,) = [l for l in out.splitlines() if l.startswith(name + " ")]
    assert line.split()[1:4] == ["27", "20", "set1"]
  expected = {"valve3": ["27", "20", "set1,set2"], "dice": ["45", "20", "set2"],
              "weight_pull": ["32", "20", "set2"], "screw": ["28", "20", "set2"],
              "valve_cylinder": ["27", "20", "unseen"], "valve_cw": ["27", "20", "unseen"],
              "screw_topdown": ["28", "20", "unseen"], "valve_goal": ["30", "20", "sparse"],
              "valve_goal_dense": ["30", "20", "-"]}
  for name, fields in expected.items():
    (line,) = [l for l in out.splitlines() if l.startswith(name + " ")]
    assert line.split()[1:4] == fields


def test_demo_prints_a_row_per_task(capsys):
  assert cli.main(["demo", "valve1", "--batch", "2"]) == 0
  rows = [l for l in capsys.readouterr().out.splitlines() if l.startswith("valve1")]
  assert len(rows) == 1 and rows[0].split()[1] == "native"
  assert rows[0].split()[-1] == "0.0%"  # the neutral action leaves a valve where it is


def test_bad_input_is_one_line_and_exit_2():
  for argv in (["demo", "valve7"], ["demo", "valve1", "--batch", "0"]):
    out = subprocess.run([sys.executable, "-m", "discosyn", *argv], capture_output=True,
                         text=True, cwd=ROOT)
    assert out.returncode == 2
    errors = [l for l in out.stderr.splitlines() if l.startswith("discosyn: error:")]
    assert len(errors) == 1, out.stderr
    assert "Failed to import" not in out.stdout  # MJX's lines about the absent Warp


def test_a_finished_run_ends_with_the_next_commands_filled_in(tmp_path):
  from discosyn_jax.config import TrainConfig

  config = TrainConfig(squash_z=False, decoder_init="random", tasks=("valve0", "valve3"), steps=40)
  results = {"valve0": {"success": 0.9, "return": 1.0}, "valve3": {"success": 0.2, "return": 0.0}}
  text = commands.next_commands(tmp_path / "my run", 40, config, results)
  run = f"'{tmp_path / 'my run'}'"  # quoted: a folder name with a space still pastes
  assert f"discosyn synergies {run}" in text
  assert f"discosyn render {run} --task valve0" in text  # the best-solved task
  assert f"discosyn train --out {run} --resume --steps 80" in text
  ppo = commands.next_commands(tmp_path, 40, config.replace(decoder="identity"), results)
  assert "synergies" not in ppo


def test_decoder_from_help_names_the_shipped_synergy_files():
  from discosyn_jax.synergies import fitting

  shipped = sorted(path.stem for path in fitting.SHIPPED.glob("*.npz"))
  assert "shadow20-set1" in shipped
  for command in ("train", "experiment"):
    (flag,) = [a for a in subcommands(cli.build_parser())[command]._actions if a.dest == "decoder_from"]
    assert ", ".join(shipped) in flag.help, flag.help


def test_the_train_flags_help_is_their_fields_own_documentation():
  docs = config_lib.field_docs()
  assert docs["alpha2"].startswith("weight of the discriminator reward log q(z|a)")
  assert docs["tasks"].startswith("tasks or task sets")  # a "# --" group heading is not a doc
  assert docs["decoder"] == "linear (a b x 20 matrix) | mlp | identity (full-action PPO)"
  helps = {a.dest: a.help for a in subcommands(cli.build_parser())["train"]._actions}
  for flag, field in commands.TRAIN_FLAGS.items():
    assert docs[field] and helps[flag].startswith(docs[field] + "; default: the preset's"), flag


def test_the_strongest_control_is_two_flags_away():
  """A frozen random decoder with z free (the strongest control on the hand's sets) from the
  command line, for a task set of one's own as for ours."""
  args = cli.build_parser().parse_args(["train", "--preset", "set1-disco3-linear", "--freeze-decoder",
                                        "yes", "--squash-z", "no", "--decoder-init", "random"])
  config = commands.train_config(args)
  assert (config.freeze_decoder, config.squash_z, config.decoder_init) == (True, False, "random")
  args = cli.build_parser().parse_args(["train", "--preset", "set1-disco3-linear"])
  assert (commands.train_config(args).freeze_decoder, commands.train_config(args).squash_z) == (False, True)
  # without --decoder-init the start follows the decoder asked for: a frozen decoder or
  # full-action PPO from a preset that starts in the reward prior starts at random
  args = cli.build_parser().parse_args(["train", "--preset", "set1-disco3-linear", "--freeze-decoder",
                                        "yes", "--squash-z", "no"])
  assert commands.train_config(args).decoder_init == "random"
  args = cli.build_parser().parse_args(["train", "--tasks", "valve3", "--decoder", "identity",
                                        "--synergies", "20", "--alpha2", "0", "--alpha3", "0"])
  assert (commands.train_config(args).decoder, commands.train_config(args).decoder_init) == (
      "identity", "random")
  args = cli.build_parser().parse_args(["train", "--decoder-init", "objects"])
  assert commands.train_config(args).decoder_init == "objects"


def test_a_task_posture_without_a_decoder_is_one_line_and_nothing_made(tmp_path, capsys):
  out = tmp_path / "run"
  assert cli.main(["train", "--preset", "set1-ppo", "--task-posture", "yes", "--out", str(out)]) == 2
  (err,) = capsys.readouterr().err.splitlines()
  assert err.startswith("discosyn: error: the identity decoder (full-action PPO) has no room "
                        "for a task posture"), err
  assert not out.exists()


@pytest.mark.parametrize("argv, line", [
    (["train", "--decoder-init", "bogus"], "discosyn train: error: argument --decoder-init: "
     "invalid choice: 'bogus' (choose from 'auto', 'random', 'objects', 'reward')"),
    (["train", "--discriminator-target", "a"], "discosyn train: error: argument "
     "--discriminator-target: invalid choice: 'a' (choose from 'z', 'activation')"),
    (["train", "--steps", "x"], "discosyn train: error: argument --steps: invalid int value: 'x'"),
    (["train", "--squash-z", "False"], "discosyn train: error: argument --squash-z: yes or no, "
     "not 'False'"),
    (["bogus"], "discosyn: error: argument command: invalid choice: 'bogus'"),
])
def test_a_bad_flag_is_one_line_and_exit_status_2(argv, line, capsys):
  with pytest.raises(SystemExit) as ended:
    cli.main(argv)
  assert ended.value.code == 2
  (err,) = capsys.readouterr().err.splitlines()
  assert err.startswith(line), err


def test_a_bug_shows_its_traceback_and_says_it_is_a_bug(monkeypatch, capsys):
  """A ValueError that is not BadInput is an internal check that failed, not the user's
  mistake: not the one line of bad input."""
  def broken(args):
    raise ValueError("an invariant of ours broke")
  monkeypatch.setattr(commands, "cmd_tasks", broken)
  assert cli.main(["tasks"]) == 1
  err = capsys.readouterr().err.splitlines()
  assert err[0] == "Traceback (most recent call last):", err
  assert "ValueError: an invariant of ours broke" in err
  assert err[-1] == ("discosyn: this is a bug in discosyn, not in what it was given: please "
                     "report it with the command and the traceback above")
  assert not any(line.startswith("discosyn: error:") for line in err)


def test_bad_input_raised_in_a_command_is_one_line_and_exit_status_2(monkeypatch, capsys):
  def refused(args):
    raise BadInput("that input cannot be used")
  monkeypatch.setattr(commands, "cmd_tasks", refused)
  assert cli.main(["tasks"]) == 2
  assert capsys.readouterr().err.splitlines() == ["discosyn: error: that input cannot be used"]
