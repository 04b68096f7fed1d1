"""A row of the tables is a composed config with a label (experiments/rows.py): every row the
paper's tables name is composed from its name and named back by it, the composition is the
named presets', and a row added in one module (this test) trains through the command line."""

import json

import pytest

from discosyn import cli
from discosyn_jax.checks import BadInput
from discosyn_jax.experiments import paper, presets, rows
from discosyn_jax.experiments.method import Method
from discosyn_jax.run import layout

FROM_A_FILE = ("PCA", "AE")  # fitted spaces: the planner gives them their file


@pytest.mark.parametrize("task_set", sorted(paper.PAPER_ROWS))
def test_every_row_of_the_tables_is_named_back_by_its_config(task_set):
  composed = [m for m in paper.PAPER_ROWS[task_set] if m.family not in FROM_A_FILE]
  assert len(composed) >= 8
  for method in composed:
    assert Method.of(rows.config_for(method, task_set)) == method, method


@pytest.mark.parametrize("name, row", [
    ("set1-disco3-linear-reward", "DiscoSyn3-L-reward"), ("set1-disco4-mlp", "DiscoSyn4-NL"),
    ("set2-disco6-linear-paper", "DiscoSyn6-L"), ("set1-disco3-linear-objects", "DiscoSyn3-L-objects"),
    ("set1-disco3-linear-residual", "DiscoSyn3-L-reward-res0.3r1000"), ("set2-ppo", "PPO"),
    ("set1-disco3-linear-decay", "DiscoSyn3-L-wd8a200")])
def test_a_named_preset_is_the_composition_of_its_row(name, row):
  task_set = name.split("-")[0]
  assert rows.config_for(row, task_set) == presets.preset(name)


def test_a_row_composes_its_parts_and_refuses_what_it_cannot():
  config = rows.config_for("Random3-L-zfree", "set1", steps=300)
  assert (config.freeze_decoder, config.squash_z, config.decoder_init) == (True, False, "random")
  config = rows.config_for("DiscoSyn6+3-L-reward-tasknoise-bonuscap-res0.3r400s200", "set2", steps=1200)
  assert (config.own_synergies, config.task_noise, config.bonus_cap) == (3, True, True)
  assert (config.residual, config.residual_ramp, config.residual_start) == (0.3, 1 / 3, 1 / 6)
  for name, problem in (("PCA4", "read from a file"), ("Random3-L-matched", "read from a file"),
                        ("DiscoSyn3-L-reward frozen", "read from a file"),
                        ("Random3-L-reward", "Prior at a prior's start"),
                        ("DiscoSyn3-L-alpha3=0.1", "names no config field")):
    with pytest.raises(BadInput, match=problem):
      rows.config_for(name, "set1")
  with pytest.raises(BadInput, match="unknown task set 'set9'"):
    rows.config_for("PPO", "set9")


def test_a_row_added_to_a_table_in_one_module_trains_through_the_command_line(tmp_path, monkeypatch):
  row = Method.parse("DiscoSyn3-L-reward-tasknoise")
  monkeypatch.setitem(paper.PAPER_ROWS, "set1", paper.PAPER_ROWS["set1"] + (row,))
  out = tmp_path / "out"
  assert cli.main(["experiment", "table1", "--scale", "ci", "--methods", row.name,
                   "--out", str(out)]) == 0
  [run] = [p for p in out.iterdir() if p.is_dir()]
  assert run.name == "discosyn3-l-reward-tasknoise-set1-seed0"
  assert json.loads((run / layout.EXPERIMENT_FILE).read_text())["method"] == row.name
  assert json.loads((run / layout.CONFIG_FILE).read_text())["task_noise"] is True
  assert (run / layout.FINAL).is_dir()
