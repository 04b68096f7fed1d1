"""studies/same_logs.py: two folders of runs compared value by value, clocks aside."""

import json

from studies import same_logs


def write(folder, rows):
  folder.mkdir(parents=True)
  (folder / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))


def test_only_the_clock_may_differ(tmp_path):
  write(tmp_path / "a" / "run", [{"step": 1, "loss": 0.5, "wall_s": 1.0, "env_steps_per_s": 9.0}])
  write(tmp_path / "b" / "run", [{"step": 1, "loss": 0.5, "wall_s": 2.0, "env_steps_per_s": 7.0}])
  write(tmp_path / "c" / "run", [{"step": 1, "loss": 0.25, "wall_s": 1.0, "env_steps_per_s": 9.0}])
  assert same_logs.compare(tmp_path / "a", tmp_path / "b") == []
  assert same_logs.compare(tmp_path / "a", tmp_path / "c") == [
      f"{tmp_path / 'c' / 'run' / 'metrics.jsonl'} row 0: loss = 0.25, 0.5 before"]
  assert same_logs.main([str(tmp_path / "a"), str(tmp_path / "c")]) == 1


def test_a_missing_log_or_row_is_a_difference(tmp_path):
  write(tmp_path / "a" / "run", [{"step": 1}, {"step": 2}])
  write(tmp_path / "b" / "run", [{"step": 1}])
  (tmp_path / "c").mkdir()
  assert same_logs.compare(tmp_path / "a", tmp_path / "b") == [
      f"{tmp_path / 'b' / 'run' / 'metrics.jsonl'}: 1 rows, 2 before"]
  assert same_logs.compare(tmp_path / "a", tmp_path / "c") == [
      f"{tmp_path / 'c' / 'run' / 'metrics.jsonl'}: missing"]
