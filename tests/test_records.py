"""A run's files as a user hands them to `discosyn report` and `ds.read_run`: a damaged
eval.jsonl, experiment.json or closing.json is refused in one line naming the file and the
field (RecordError, exit 2), never read as numbers for a table or a verdict."""

import json
import pathlib
import random
import shutil

import pytest

from discosyn import cli
from discosyn_jax.experiments import report_runs
from discosyn_jax.run import folder, layout
from discosyn_jax.run.record_files import RecordError

ROOT = pathlib.Path(__file__).resolve().parents[1]
# a small committed record: four tasks, 16 evaluations, a closing evaluation
RECORD = ROOT / "docs" / "results" / "planted-lag-floor-success" / "discosyn3-l-zfloor0.7-planted_reach-seed1"
FILES = (layout.CONFIG_FILE, layout.EVAL_FILE, layout.EXPERIMENT_FILE, layout.CLOSING_FILE)


@pytest.fixture
def run(tmp_path):
  """A copy of the record's config and the three files read here (no metrics: none needed)."""
  run_dir = tmp_path / "run"
  run_dir.mkdir()
  for name in FILES:
    shutil.copyfile(RECORD / name, run_dir / name)
  return run_dir


def rows(run_dir):
  return [json.loads(line) for line in (run_dir / layout.EVAL_FILE).read_text().splitlines()]


def write_rows(run_dir, found):
  (run_dir / layout.EVAL_FILE).write_text("".join(json.dumps(row) + "\n" for row in found))


def refused(run_dir, capsys, *words):
  """The Python reader and the report both refuse `run_dir` in one line holding `words`;
  the report leaves no folder."""
  with pytest.raises(RecordError) as err:
    folder.read(run_dir)
  line = str(err.value)
  assert "\n" not in line and all(word in line for word in words), line
  capsys.readouterr()
  out = run_dir.parent / "report"
  assert cli.main(["report", str(run_dir), "--out", str(out), "--no-tsne"]) == 2
  stderr = capsys.readouterr().err
  assert stderr.count("\n") == 1 and stderr.startswith("discosyn: error: ") and line in stderr
  assert "Traceback" not in stderr and not out.exists()
  return line


def damaged_row(run_dir, change, at=2):
  found = rows(run_dir)
  change(found[at])
  write_rows(run_dir, found)


@pytest.mark.parametrize("change, words", [
    (lambda row: row.pop("step"), ("line 3", "no step")),
    (lambda row: row.update(step="50"), ("line 3", "step is '50'", "whole number")),
    (lambda row: row.update(step=1.5), ("line 3", "step is 1.5")),
    (lambda row: row.update(step=10), ("line 3", "step 10 after step 50", "order")),
    (lambda row: row.update({"planted1/success": float("nan")}), ("planted1/success is nan", "[0, 1]")),
    (lambda row: row.update({"planted1/success": 7.5}), ("planted1/success is 7.5", "[0, 1]")),
    (lambda row: row.update({"planted1/success": "0.5"}), ("planted1/success is '0.5'",)),
    (lambda row: row.update({"planted1/success": True}), ("planted1/success is True",)),
    (lambda row: row.update({"planted1/return": float("inf")}), ("planted1/return is inf", "finite")),
    (lambda row: row.update(env_steps=-1), ("env_steps is -1",)),
    (lambda row: row.update(stepz=3), ("unknown field 'stepz'",)),
], ids=["no-step", "string-step", "fractional-step", "step-out-of-order", "nan-success",
        "success-7.5", "string-success", "bool-success", "inf-return", "negative-env-steps",
        "unknown-field"])
def test_a_damaged_evaluation_is_refused_naming_the_file_line_and_field(run, capsys, change, words):
  damaged_row(run, change)
  line = refused(run, capsys, str(run / layout.EVAL_FILE), *words)
  assert "line 3" in line


def test_a_line_of_eval_jsonl_that_is_not_json_or_not_text_is_refused(run, capsys):
  text = (run / layout.EVAL_FILE).read_bytes().split(b"\n")
  (run / layout.EVAL_FILE).write_bytes(b"\n".join([text[0], b"[1, 2]", *text[1:]]))
  refused(run, capsys, str(run / layout.EVAL_FILE), "line 2", "not a JSON object")
  (run / layout.EVAL_FILE).write_bytes(b"\n".join([text[0], b"\xff\xfe", *text[1:]]))
  refused(run, capsys, str(run / layout.EVAL_FILE), "not UTF-8")


def test_an_emptied_eval_jsonl_of_a_run_that_ended_is_refused_not_counted_unfinished(run, capsys):
  (run / layout.EVAL_FILE).write_text("")
  refused(run, capsys, str(run / layout.EVAL_FILE), "no evaluation", "the run ended")
  (run / layout.EVAL_FILE).unlink()  # gone altogether: the same
  refused(run, capsys, str(run / layout.EVAL_FILE), "no evaluation")


def test_a_last_evaluation_cut_short_is_refused_where_the_run_ended(run, capsys):
  text = (run / layout.EVAL_FILE).read_text()
  (run / layout.EVAL_FILE).write_text(text[:-40])
  refused(run, capsys, str(run / layout.EVAL_FILE), "last line is cut short", "the run ended")


def test_a_run_still_going_may_have_no_evaluation_yet(run):
  (run / layout.EVAL_FILE).write_text("")
  for name in (layout.EXPERIMENT_FILE, layout.CLOSING_FILE):
    (run / name).unlink()
  found = folder.read(run)
  assert found.evaluations == [] and not found.finished
  # nor a last line whole: a run killed while writing it
  text = (RECORD / layout.EVAL_FILE).read_text()
  (run / layout.EVAL_FILE).write_text(text[:-40])
  assert folder.read(run).evaluations == rows(RECORD)[:-1]


@pytest.mark.parametrize("text, words", [
    ("[1, 2]", ("a JSON list, not the object expected",)),
    ("", ("empty", "expected a JSON object")),
    ("{\"experiment\": ", ("not JSON",)),
    (json.dumps({"experiment": "x", "method": 3}), ("method is 3, not a string",)),
    (json.dumps({"experiment": "x", "seed": "1"}), ("seed is '1', not a whole number",)),
    (json.dumps({"experiment": "x", "scale": 2}), ("scale is 2, not a string",)),
], ids=["list", "empty", "cut", "numeric-method", "string-seed", "numeric-scale"])
def test_a_damaged_experiment_json_is_refused_naming_the_file_and_field(run, capsys, text, words):
  (run / layout.EXPERIMENT_FILE).write_text(text)
  refused(run, capsys, str(run / layout.EXPERIMENT_FILE), *words)


def test_a_method_that_is_no_methods_name_is_refused_by_the_report(run, capsys):
  labels = json.loads((run / layout.EXPERIMENT_FILE).read_text())
  (run / layout.EXPERIMENT_FILE).write_text(json.dumps({**labels, "method": "Disco Syn"}))
  assert folder.read(run).labels["method"] == "Disco Syn"  # a label as such: the report names methods
  with pytest.raises(RecordError, match=r"experiment.json: method: 'Disco Syn' is not a method's name"):
    report_runs.read(run)
  assert cli.main(["report", str(run), "--out", str(run.parent / "report")]) == 2
  assert "experiment.json: method:" in capsys.readouterr().err
  assert not (run.parent / "report").exists()


@pytest.mark.parametrize("text, words", [
    ("not json", ("not JSON",)),
    ("", ("empty",)),
    ("[0.5]", ("a JSON list, not the object expected",)),
    (json.dumps({"step": 400, "planted1/success": float("nan")}), ("planted1/success is nan", "[0, 1]")),
    (json.dumps({"planted1/success": 0.5}), ("no step",)),
], ids=["not-json", "empty", "list", "nan-success", "no-step"])
def test_a_damaged_closing_json_is_refused_naming_the_file_and_field(run, capsys, text, words):
  (run / layout.CLOSING_FILE).write_text(text)
  refused(run, capsys, str(run / layout.CLOSING_FILE), *words)


def test_the_committed_record_reads_whole(run):
  found = folder.read(run)
  assert found.finished and len(found.evaluations) == 16 and found.closing["step"] == 400
  assert found.labels["method"] == "DiscoSyn3-L-zfloor0.7"


def _damage(data: bytes, rng: random.Random) -> bytes:
  """`data` cut short, or with one to three bytes changed."""
  if rng.random() < 0.4:
    return data[:rng.randrange(len(data))]
  data = bytearray(data)
  for _ in range(rng.randint(1, 3)):
    data[rng.randrange(len(data))] = rng.choice([rng.randrange(256), *b'{}[]",:\n0-.'])
  return bytes(data)


def _valid(run: folder.Run) -> None:
  """What every read run holds: steps in order, successes rates, figures finite."""
  steps = [row["step"] for row in run.evaluations]
  assert all(isinstance(s, int) for s in steps) and steps == sorted(set(steps))
  for row in [*run.evaluations, *([run.closing] if run.closing else [])]:
    for key, value in row.items():
      assert isinstance(value, (int, float)) and value == value
      if key.endswith("/success"):
        assert 0 <= value <= 1


@pytest.mark.parametrize("case", range(40))
def test_a_record_damaged_at_random_is_read_or_refused_in_one_line(run, case):
  """A byte changed or the file cut, at a seeded random place of eval.jsonl,
  experiment.json or closing.json: the run reads (the same content where the damage left
  the JSON the same, and a valid run whatever it read) or is refused with RecordError in
  one line naming the file; never another exception."""
  rng = random.Random(case)
  whole = report_runs.read(run)
  name = (layout.EVAL_FILE, layout.EXPERIMENT_FILE, layout.CLOSING_FILE)[case % 3]
  original = (run / name).read_bytes()
  damaged = _damage(original, rng)
  (run / name).write_bytes(damaged)
  try:
    found = report_runs.read(run)
  except RecordError as err:
    assert str(run / name) in str(err) and "\n" not in str(err)
    return
  _valid(found)
  try:
    same = _parsed(damaged, name) == _parsed(original, name)
  except ValueError:  # a last eval line cut short, read as a run killed while writing it
    same = False
  if same:
    assert (found.evaluations, found.closing, found.labels, found.method) == \
        (whole.evaluations, whole.closing, whole.labels, whole.method)
  elif name == layout.EVAL_FILE and original.startswith(damaged):  # cut: the rows before it
    assert found.evaluations == whole.evaluations[:len(found.evaluations)]


def _parsed(data: bytes, name: str):
  text = data.decode()
  if name == layout.EVAL_FILE:
    return [json.loads(line) for line in text.splitlines() if line.strip()]
  return json.loads(text)
