"""The discosyn command: listing, the demo, bad input."""

import subprocess
import sys

from discosyn_jax import cli


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


def test_bad_input_is_one_line_and_exit_2():
  for argv in (["demo", "valve7"], ["demo", "valve1", "--batch", "0"]):
    out = subprocess.run([sys.executable, "-m", "discosyn_jax.cli", *argv], capture_output=True, text=True)
    assert out.returncode == 2
    errors = [l for l in out.stderr.splitlines() if l.startswith("discosyn: error:")]
    assert len(errors) == 1, out.stderr


def test_a_finished_run_ends_with_the_next_commands_filled_in(tmp_path):
  from discosyn_jax.config import TrainConfig

  config = TrainConfig(tasks=("valve0", "valve3"), steps=40)
  results = {"valve0": {"success": 0.9, "return": 1.0}, "valve3": {"success": 0.2, "return": 0.0}}
  text = cli.next_commands(tmp_path / "my run", 40, config, results)
  run = f"'{tmp_path / 'my run'}'"  # quoted: a folder name with a space still pastes
  assert f"discosyn synergies {run}" in text
  assert f"discosyn render {run} --task valve0" in text  # the best-solved task
  assert f"discosyn train --out {run} --resume --steps 80" in text
  ppo = cli.next_commands(tmp_path, 40, config.replace(decoder="identity"), results)
  assert "synergies" not in ppo
