"""`discosyn report` on a committed folder of records regenerates its committed REPORT.md:
the fixture tests/fixtures/report-ci (tests/report_fixture.py made it), wherever it lies."""

import shutil

from discosyn import cli
from tests.report_fixture import FIXTURE


def test_the_committed_report_regenerates_from_the_records_alone(tmp_path):
  committed = (FIXTURE / "report" / "REPORT.md").read_text()
  # elsewhere than where it was made, and without a checkpoint: the text is the same
  folder = tmp_path / "elsewhere" / "report-ci"
  shutil.copytree(FIXTURE, folder)
  assert not list(folder.rglob("final")) and not list(folder.rglob("checkpoints"))
  assert cli.main(["report", str(folder), "--out", str(folder / "report"), "--force"]) == 0
  regenerated = (folder / "report" / "REPORT.md").read_text()
  assert regenerated.splitlines() == committed.splitlines()
  assert (folder / "report" / "tsne-set1.png").is_file()  # drawn from the records' z.npz
  assert "`..`" in committed and str(tmp_path) not in regenerated


def test_logs_without_z_or_checkpoints_report_without_a_t_sne_and_a_failure_leaves_nothing(
    tmp_path, monkeypatch):
  """Logs alone (no z.npz, no checkpoint: runs kept before records) still report, the t-SNE
  drawn from the runs that can give it or left out; a report that fails leaves no folder."""
  from discosyn_jax.experiments import report_figures

  folder = tmp_path / "logs"
  shutil.copytree(FIXTURE, folder)
  for z in folder.rglob("z.npz"):
    z.unlink()
  out = folder / "again"
  assert cli.main(["report", str(folder), "--out", str(out)]) == 0
  assert "t-SNE" not in (out / "REPORT.md").read_text()

  shutil.copytree(FIXTURE, tmp_path / "with-z")
  def broken(*args, **kwargs):
    raise RuntimeError("no display")
  monkeypatch.setattr(report_figures, "tsne", broken)
  assert cli.main(["report", str(tmp_path / "with-z"), "--out", str(tmp_path / "failed")]) == 1
  assert not (tmp_path / "failed").exists()
