"""Regenerate committed reports from their records, each as it was made: the folders its
REPORT.md names (its third line, relative to the report's own folder), with a t-SNE where it
has one, at its threshold.

  python docs/results/regenerate.py [--final-k K] [REPORT_DIR ...]

Without REPORT_DIRs: every docs/results/**/REPORT.md whose third line names its folders
(the older ones, made from checkpoints no longer kept, say so instead and are left alone).
`git diff docs/results` then shows what changed; with the same code and --final-k 1 (the
final as the last evaluation alone, the reports before 2026-12-06) nothing does.
"""

from __future__ import annotations

import argparse
import pathlib
import re

RESULTS = pathlib.Path(__file__).resolve().parent


def sources(report: pathlib.Path) -> list[pathlib.Path] | None:
  """The folders a REPORT.md was made from, or None where its line names no folders."""
  line = report.read_text().splitlines()[2]
  if " (relative to this report's folder)" not in line:
    return None
  return [(report.parent / name).resolve() for name in re.findall(r"`([^`]+)`", line)]


def settings(report: pathlib.Path) -> dict:
  text = report.read_text()
  threshold = re.search(r"at least (\d+)%", text)
  return {"with_tsne": "## t-SNE" in text,
          "threshold": int(threshold.group(1)) / 100 if threshold else 0.8}


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("reports", nargs="*", type=pathlib.Path)
  parser.add_argument("--final-k", type=int, default=3)
  args = parser.parse_args(argv)

  from discosyn_jax.experiments import report as report_lib

  folders = args.reports or sorted(p.parent for p in RESULTS.glob("**/REPORT.md"))
  for folder in folders:
    report = folder / "REPORT.md"
    found = sources(report)
    if found is None:
      print(f"{report}: made from checkpoints no longer kept; left as it is")
      continue
    report_lib.write(found, folder, force=True, final_k=args.final_k, **settings(report))
    print(report)


if __name__ == "__main__":
  main()
