"""Every relative link of the repository's Markdown files ([text](path) and ![alt](path)) names
a file or folder that exists, relative to the Markdown file's folder. Links to the web
(http(s)://, mailto: and the like) and pure #anchors are not checked; a trailing #anchor is
dropped. Links inside code (fenced blocks, `code spans`) are not links."""

import os
import re
import urllib.parse

from tests import helpers

# folders no Markdown file of the repository lives in: environments, run folders, caches
SKIP_DIRS = {".git", "runs", "node_modules", "__pycache__", ".pytest_cache", "build", "dist"}
# test data, not documentation: the report fixture's REPORT.md names figures that are not
# committed, and must stay what `discosyn report` writes (tests/test_report_fixture.py)
SKIP_PATHS = {os.path.join("tests", "fixtures")}

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
CODE_SPAN = re.compile(r"(`+).+?\1")
# [text](target) and ![alt](target): the text may hold one level of brackets ([`x`] etc.);
# the target is a <bracketed> path or runs to the first space or closing parenthesis that
# balances (a title after a space is ignored)
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|(?:[^()\s]|\([^()\s]*\))*)[^)]*\)")
EXTERNAL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")  # http:, https:, mailto:, ...


def markdown_files():
  for folder, dirs, files in os.walk(helpers.ROOT):
    dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith(".venv")
                     and not d.endswith(".egg-info")
                     and os.path.relpath(os.path.join(folder, d), helpers.ROOT) not in SKIP_PATHS)
    for name in sorted(files):
      if name.lower().endswith(".md"):
        yield os.path.join(folder, name)


def links(path):
  """(line number, target) of every link outside code in the Markdown file at `path`."""
  fence = None
  with open(path, encoding="utf-8") as f:
    for number, line in enumerate(f, 1):
      opened = FENCE.match(line)
      if fence is not None:
        if opened and opened.group(1)[0] == fence[0] and len(opened.group(1)) >= len(fence):
          fence = None
        continue
      if opened:
        fence = opened.group(1)
        continue
      for match in LINK.finditer(CODE_SPAN.sub("", line)):
        yield number, match.group(1).strip("<>")


def broken(path):
  folder = os.path.dirname(path)
  for number, target in links(path):
    if not target or target.startswith("#") or EXTERNAL.match(target):
      continue
    local = urllib.parse.unquote(target.split("#", 1)[0])
    if local.startswith("/"):  # from the repository's root, as GitHub reads it
      resolved = os.path.join(helpers.ROOT, local.lstrip("/"))
    else:
      resolved = os.path.join(folder, local)
    if not os.path.exists(resolved):
      yield f"{os.path.relpath(path, helpers.ROOT)}:{number}: ({target})"


def test_the_markdown_files_are_found():
  found = {os.path.relpath(p, helpers.ROOT) for p in markdown_files()}
  assert {"README.md", os.path.join("docs", "notes", "README.md")} <= found
  assert not any(p.split(os.sep)[0] in ("runs", ".venv") for p in found)


def test_every_relative_link_resolves():
  bad = [line for path in markdown_files() for line in broken(path)]
  assert not bad, f"{len(bad)} broken link(s):\n" + "\n".join(bad)
