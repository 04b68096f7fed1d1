"""The shell blocks of the pages a user follows run as written, from a folder laid out as
the checkout: each `discosyn` line through the CLI's main with the flags that shrink it to
the `ci` size appended (its shape as documented), each `python -m studies.X` line through
that study's main; a page's later lines read what its earlier ones wrote. A block no test
runs says why on the line above (tests/test_doc_snippets.py holds the pages to that)."""

import importlib
import re
import shlex

import pytest

from discosyn import cli
from tests import helpers

TRAIN = ["--steps", "2", "--num-envs", "4", "--unroll-length", "5", "--minibatches", "2",
         "--epochs", "1", "--eval-every", "1", "--eval-envs", "2", "--closing-episodes", "4",
         "--checkpoint-every", "0", "--no-progress"]
# appended to a documented command of each kind: the `ci` size (helpers.TINY)
SHRINK = {"train": TRAIN, "experiment": ["--scale", "ci"], "demo": ["--batch", "2"],
          "eval": ["--episodes", "2"], "studies.task_calibration": ["--episodes", "4"]}
# what a page's commands read that the page has the user make elsewhere: made first
GIVEN = {"docs/TAKE_HOME.md": [["train", "--preset", "quickstart", "--out", "runs/mine"]]}


def commands(code: str) -> list[list[str]]:
  """The argv of each command of a shell block: continuations joined, comments and
  `NAME=value` lines read as the shell would (their names expanded in later lines)."""
  names, out = {}, []
  for line in code.replace("\\\n", " ").splitlines():
    words = shlex.split(line, comments=True)
    if len(words) == 1 and re.fullmatch(r"[A-Z_]+=\S+", words[0]):
      name, value = words[0].split("=", 1)
      names[name] = value
    elif words:
      out.append([re.sub(r"\$(\w+)", lambda m: names[m.group(1)], w) for w in words])
  return out


def run(argv: list[str]) -> None:
  if argv[0] == "discosyn":
    code = cli.main(argv[1:] + SHRINK.get(argv[1], []))
    assert code == 0, f"{shlex.join(argv)}: exit {code}"
  elif argv[:2] == ["python", "-m"] and argv[2].startswith("studies."):
    importlib.import_module(argv[2]).main(argv[3:] + SHRINK.get(argv[2], []))
  else:
    raise AssertionError(f"no way to run {shlex.join(argv)}: say why above its block")


def test_commands_read_as_the_shell_would():
  assert commands("F=a/b.py\ndiscosyn x $F:P \\\n  --y 1   # why\n# all\n") == [
      ["discosyn", "x", "a/b.py:P", "--y", "1"]]


@pytest.mark.parametrize("page", [p for p in helpers.USER_PAGES if any(
    lang == "bash" and not why for _, lang, _, why in helpers.doc_blocks(p))])
def test_every_shell_block_runs(page, tmp_path, monkeypatch, capsys):
  monkeypatch.chdir(helpers.doc_folder(tmp_path))
  for argv in GIVEN.get(page, []):
    run(["discosyn"] + argv)
  for line, language, code, why in helpers.doc_blocks(page):
    if language == "bash" and not why:
      for argv in commands(code):
        run(argv)
  capsys.readouterr()
