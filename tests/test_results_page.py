"""The tables of docs/RESULTS.md and README.md are the ones their committed records give
(discosyn_jax/experiments/results_page.py writes them between marker lines), the command
touches nothing outside the markers and names a table edited by hand, and the two pages
stay short: a reader's length, no table cell of a paragraph; the committed records stay a
small part of a clone."""

import os
import re

import numpy as np
import pytest

from discosyn_jax.experiments import results_page
from tests import helpers

PAGES = ("docs/RESULTS.md", "README.md")
LIMITS = {"README.md": 160, "docs/RESULTS.md": 260}  # lines
MAX_WORDS = 40  # in one table cell
RECORDS_LIMIT = 30_000_000  # bytes under docs/results: what the claims read, not every log


@pytest.fixture(scope="module")
def tables():
  return results_page.tables()


@pytest.mark.parametrize("page", PAGES)
def test_the_pages_tables_are_their_records(page, tables):
  path = os.path.join(helpers.ROOT, page)
  names = [name for name, _, _ in results_page.blocks(open(path, encoding="utf-8").read())]
  assert names, f"{page} has no generated table"
  assert results_page.check(path, tables) == [], (
      f"{page} differs from its records: run "
      f"`python -m discosyn_jax.experiments.results_page {page}`")


def test_every_table_is_on_a_page(tables):
  shown = {name for page in PAGES
           for name, _, _ in results_page.blocks(open(os.path.join(helpers.ROOT, page)).read())}
  assert shown == set(tables)


def test_write_replaces_only_between_the_markers(tmp_path, tables):
  page = tmp_path / "page.md"
  before = "# A page\n\nSome prose | with a pipe.\n\n"
  middle = "\nMore prose.\n\n"
  after = "\nThe end.\n"
  page.write_text(before + "<!-- table:claims -->\nold text\n<!-- /table:claims -->\n" + middle
                  + "<!-- table:sparse -->\n<!-- /table:sparse -->\n" + after)
  assert results_page.check(page, tables) == ["claims", "sparse"]
  assert results_page.write(page, tables) == ["claims", "sparse"]
  text = page.read_text()
  assert text == (before + "<!-- table:claims -->\n" + tables["claims"] + "\n<!-- /table:claims -->\n"
                  + middle + "<!-- table:sparse -->\n" + tables["sparse"]
                  + "\n<!-- /table:sparse -->\n" + after)
  assert results_page.check(page, tables) == []
  assert results_page.write(page, tables) == []  # a second write changes nothing
  assert page.read_text() == text

  # a cell edited by hand is named, the other table is not
  row = tables["sparse"].splitlines()[2]
  cells = row.split("|")
  cells[2] = " 0.01 " if cells[2].strip() != "0.01" else " 0.02 "
  page.write_text(text.replace(row, "|".join(cells)))
  assert results_page.check(page, tables) == ["sparse"]
  results_page.write(page, tables)
  assert page.read_text() == text


def test_a_page_with_a_wrong_marker_is_refused(tmp_path, tables):
  page = tmp_path / "page.md"
  page.write_text("<!-- table:nonesuch -->\n<!-- /table:nonesuch -->\n")
  assert results_page.check(page, tables) == ["nonesuch (no such table)"]
  with pytest.raises(ValueError, match="no table 'nonesuch'"):
    results_page.write(page, tables)
  page.write_text("<!-- table:claims -->\nno end\n")
  with pytest.raises(ValueError, match="never closed"):
    results_page.check(page, tables)


def test_the_command(tmp_path, tables, capsys, monkeypatch):
  monkeypatch.setattr(results_page, "tables", lambda root=None: tables)
  page = tmp_path / "page.md"
  page.write_text("<!-- table:sparse -->\n<!-- /table:sparse -->\n")
  assert results_page.main(["--check", str(page)]) == 1
  assert "sparse" in capsys.readouterr().out
  assert results_page.main([str(page)]) == 0
  assert results_page.main(["--check", str(page)]) == 0
  # where docs/results is absent (an installed package): one line, exit 2
  monkeypatch.setattr(results_page, "ROOT", tmp_path)
  assert results_page.main(["--check"]) == 2
  assert len(capsys.readouterr().err.strip().splitlines()) == 1


def table_cells(text: str):
  """(line number, cell) of every cell of every Markdown table outside code blocks."""
  fenced = False
  for number, line in enumerate(text.splitlines(), 1):
    if line.lstrip().startswith("```"):
      fenced = not fenced
      continue
    if not fenced and line.startswith("|"):
      for cell in re.sub(r"`[^`]*`", "code", line).strip().strip("|").split("|"):
        yield number, cell.strip()


@pytest.mark.parametrize("page", PAGES)
def test_the_pages_are_short(page):
  text = open(os.path.join(helpers.ROOT, page), encoding="utf-8").read()
  lines = text.count("\n")
  assert lines <= LIMITS[page], f"{page}: {lines} lines, at most {LIMITS[page]}"
  long = [f"{page}:{n}: {len(cell.split())} words" for n, cell in table_cells(text)
          if len(cell.split()) > MAX_WORDS]
  assert not long, f"table cells over {MAX_WORDS} words:\n" + "\n".join(long)


def test_the_records_stay_light():
  """docs/results holds what a claim reads (a record's metrics thinned, run/logs.py
  `kept`); the rest is regenerated by its command."""
  root = os.path.join(helpers.ROOT, "docs", "results")
  size = sum(os.path.getsize(os.path.join(folder, name))
             for folder, _, names in os.walk(root) for name in names)
  assert size <= RECORDS_LIMIT, f"docs/results holds {size / 1e6:.1f} MB, at most {RECORDS_LIMIT / 1e6:.0f}"


def test_a_verdict_another_bootstrap_seed_changes_says_so():
  assert results_page.stable(["below"] * 5) == "below"
  assert (results_page.stable(["below", "not separated", "below", "below", "not separated"])
          == "below at 3 of 5 bootstrap seeds")
  # the seeds are the bootstrap's: another seed moves an interval, and the default comes back
  from discosyn_jax.experiments import intervals
  rng = np.random.default_rng(3)
  x, y = {"s": rng.uniform(size=(4, 2))}, {"s": rng.uniform(size=(4, 2))}
  first = intervals.mean_difference(x, y)["s"]
  with intervals.bootstrap_seed(7):
    other = intervals.mean_difference(x, y)["s"]
  assert other.value == first.value and (other.low, other.high) != (first.low, first.high)
  assert intervals.mean_difference(x, y)["s"] == first
