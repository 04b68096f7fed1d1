"""`discosyn bench`: one row per backend and batch; bad input is exit 2."""

from discosyn import cli


def test_bench_prints_a_physics_row_per_batch_and_profile(capsys):
  argv = ["bench", "--tasks", "valve1", "--batches", "2", "4", "--physics", "reference", "fast",
          "--no-train", "--repeats", "1"]
  assert cli.main(argv) == 0
  rows = [l.split("|") for l in capsys.readouterr().out.splitlines() if l.startswith("| native")]
  assert [(r[2].strip(), r[3].strip()) for r in rows] == [
      ("2", "reference"), ("2", "fast"), ("4", "reference"), ("4", "fast")]
  for r in rows:
    assert float(r[4].replace(",", "")) > 0 and float(r[5].replace(",", "")) > 0  # env/s
    assert r[7].strip() == "-"  # no training asked


def test_bench_refuses_zero_repeats(capsys):
  assert cli.main(["bench", "--repeats", "0", "--no-train"]) == 2
  assert "--repeats must be at least 1" in capsys.readouterr().err
