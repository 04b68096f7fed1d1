"""The committed fixture tests/fixtures/report-ci: the records of tiny experiment runs (ci
scale, toy tasks, two seeds) and the REPORT.md `discosyn report` made of them, which
tests/test_report_fixture.py regenerates from those records alone.

  .venv/bin/python -m tests.report_fixture          # make it again: the runs, the report
  .venv/bin/python -m tests.report_fixture report   # the report alone, from the records

Rewrite the report when its text changes on purpose, and commit REPORT.md with the change.
"""

import pathlib
import shutil
import tempfile

import numpy as np
import pytest

from discosyn_jax.experiments import paper, presets, record, report
from tests import toy_env

FIXTURE = pathlib.Path(__file__).resolve().parent / "fixtures" / "report-ci"
toy_env.register()  # tasks a, b, c, g
SETS = {"set1": ("a", "b"), "set2": ("b", "c"), "sparse": ("g",), "unseen-set1": ("c",),
        "unseen-set2": ("a",)}
# the steps kept: every section of the report, few runs
PLANS = {"discosyn-set1": ("DiscoSyn3-L", "Random3-L-zfree", "Random3-L-matched"),
         "baselines-set1": ("PCA4",), "sparse": None, "transfer": None}


def make(dest: pathlib.Path = FIXTURE) -> pathlib.Path:
  """Run the plans at the ci scale for seeds 0 and 1, keep their records in `dest`, report."""
  # toy tasks have no physics to make a prior of: the paper's random start; small decoders
  small = {name: config.replace(decoder_hidden=(16, 16),
                                **({"decoder_init": "random"} if config.decoder == "linear" else {}))
           for name, config in presets.PRESETS.items()}
  with pytest.MonkeyPatch.context() as patch, tempfile.TemporaryDirectory() as runs:
    patch.setattr(presets, "PRESETS", small)
    for name, methods in PLANS.items():
      paper.run(name, pathlib.Path(runs), "ci", (0, 1), task_sets=SETS,
                methods=methods, log=lambda *a: None)
    shutil.rmtree(dest, ignore_errors=True)
    record.keep(pathlib.Path(runs), dest)
  return write_report(dest)


def write_report(dest: pathlib.Path = FIXTURE) -> pathlib.Path:
  """The report of the records in `dest`, its text alone (the test compares the text)."""
  written = report.write([dest], dest / "report", force=True)
  for figure in written.parent.glob("*.png"):
    figure.unlink()
  return written


if __name__ == "__main__":
  import sys

  print(write_report() if sys.argv[1:] == ["report"] else make())
