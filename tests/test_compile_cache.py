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


def test_an_env_changes_nothing_global_and_a_run_turns_the_cache_on(monkeypatch, tmp_path):
  from discosyn_jax import assemble, tasks
  from discosyn_jax.config import TrainConfig
  from discosyn_jax.run import jax_setup

  monkeypatch.setenv(compile_cache.ENV_VAR, str(tmp_path / "jax"))
  monkeypatch.setattr(jax_setup, "_ready", False)  # as in a new process
  before = jax.config.jax_compilation_cache_dir
  try:
    tasks.make("planted0")
    assert jax.config.jax_compilation_cache_dir == before
    assemble.trainer(TrainConfig(tasks=("planted0",), decoder_init="random", num_envs=2,
                                 unroll_length=2, num_minibatches=1))
    assert jax.config.jax_compilation_cache_dir == str(tmp_path / "jax")
  finally:
    jax.config.update("jax_compilation_cache_dir", before)
