"""The Python blocks of the pages a user follows run as written, from a folder laid out as
the checkout (their paths point there), the runs they train shrunk to seconds by a
substitution that must find its text (a page that changes the call fails here, not silently):
a documented call that raises is a defect. Every other block is run by
tests/test_doc_commands.py or says on the line above why not."""

import os
import sys

import pytest

from tests import helpers

RUN_HERE = ("python",)
RUN_AS_COMMANDS = ("bash",)
# (page, text in a block, what it becomes in the test): the documented call at the `ci` size
SHRINK = (
    ("README.md", 'ds.preset("quickstart").replace(seed=1)',
     'ds.preset("quickstart").replace(seed=1, **TINY)'),
    ("docs/TAKE_HOME.md", "num_timesteps=1_000_000,", "num_timesteps=40, unroll_length=5,"),
    ("docs/TAKE_HOME.md", "episode_length=100, num_envs=64, batch_size=256)",
     "episode_length=10, num_envs=4, batch_size=4, num_minibatches=2, "
     "num_updates_per_batch=1, num_evals=2, num_eval_envs=2)"),
)


def shrunk(page: str, code: str) -> str:
  for where, text, small in SHRINK:
    if where == page and text in code:
      code = code.replace(text, small)
  return code


@pytest.mark.parametrize("page", helpers.USER_PAGES)
def test_every_block_is_run_or_says_why(page):
  for line, language, code, why in helpers.doc_blocks(page):
    assert language in RUN_HERE + RUN_AS_COMMANDS or why, (
        f"{page}:{line}: a ```{language} block that no test runs and no "
        "'<!-- not run: why -->' line above explains")


def test_every_shrink_finds_its_text():
  codes = {page: "".join(code for _, _, code, _ in helpers.doc_blocks(page))
           for page in helpers.USER_PAGES}
  missing = [(page, text) for page, text, _ in SHRINK if text not in codes[page]]
  assert not missing, f"documented calls changed; update SHRINK: {missing}"


@pytest.mark.parametrize("page", [p for p in helpers.USER_PAGES if any(
    lang in RUN_HERE and not why for _, lang, _, why in helpers.doc_blocks(p))])
def test_every_python_block_runs(page, tmp_path, monkeypatch):
  monkeypatch.chdir(helpers.doc_folder(tmp_path))
  monkeypatch.setattr(sys, "argv", ["snippet"])
  for line, language, code, why in helpers.doc_blocks(page):
    if language in RUN_HERE and not why:
      exec(compile(shrunk(page, code), f"{page}:{line}", "exec"),
           {"__name__": "__snippet__", "TINY": helpers.TINY})
  assert os.getcwd() == str(tmp_path)
