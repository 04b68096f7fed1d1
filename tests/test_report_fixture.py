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
