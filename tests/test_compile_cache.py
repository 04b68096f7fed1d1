"""The persistent compilation cache: on by default, its folder from DISCOSYN_JAX_CACHE."""

import pathlib

import jax

from discosyn_jax.run import compile_cache


def test_the_cache_folder_follows_the_environment(monkeypatch, tmp_path):
  monkeypatch.delenv(compile_cache.ENV_VAR, raising=False)
  assert compile_cache.folder() == pathlib.Path("~/.cache/discosyn/jax").expanduser()
  monkeypatch.setenv(compile_cache.ENV_VAR, "off")
  assert compile_cache.folder() is None and compile_cache.enable() is None
  monkeypatch.setenv(compile_cache.ENV_VAR, str(tmp_path / "jax"))
  before = jax.config.jax_compilation_cache_dir
  try:
    assert compile_cache.enable() == tmp_path / "jax" and (tmp_path / "jax").is_dir()
    assert jax.config.jax_compilation_cache_dir == str(tmp_path / "jax")
  finally:
    jax.config.update("jax_compilation_cache_dir", before)


def test_setting_up_jax_turned_it_on():
  from discosyn_jax import tasks  # noqa: F401  (sets JAX up, as the CLI does before a command)

  if compile_cache.folder() is not None:  # unless this run says off
    assert jax.config.jax_compilation_cache_dir == str(compile_cache.folder())
