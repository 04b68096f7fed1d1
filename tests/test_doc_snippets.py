"""The Python blocks of the pages that read committed records run as written, from the
repository's root (where their paths point): a documented call that raises is a defect."""

import os
import re

import pytest

from tests import helpers

PAGES = ("docs/RESULTS.md",)  # blocks that read docs/results/ and train nothing


def blocks(page: str) -> list[str]:
  text = open(os.path.join(helpers.ROOT, page)).read()
  return re.findall(r"^```python\n(.*?)^```", text, re.M | re.S)


@pytest.mark.parametrize("page", PAGES)
def test_every_python_block_runs(page, monkeypatch):
  found = blocks(page)
  assert found, f"{page} has no Python block"
  monkeypatch.chdir(helpers.ROOT)
  for code in found:
    exec(compile(code, page, "exec"), {"__name__": "__snippet__"})
