"""Synergies you can take home (synergies/artefact.py, synergies/action_space.py): a synergy
file that says what it is, the shipped files by name, the synergies as another library's
action space, and Brax's own PPO from a user's script that patches nothing."""

import json
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import discosyn_jax as ds
from discosyn import cli
from discosyn_jax.env import hands
from discosyn_jax.synergies import artefact, fitting
from tests import helpers

RECORD = os.path.join(helpers.ROOT, "docs/results/paper/discosyn3-l-reward-set1-seed0")


def test_export_then_load_gives_back_the_runs_decoder_and_says_what_it_is(tmp_path):
  path = artefact.export(RECORD, tmp_path / "mine.npz", date="2026-12-06")
  syn = ds.Synergies.load(path)
  _, params = fitting.read(RECORD)
  jax.tree.map(np.testing.assert_array_equal, syn.params, params)
  assert syn.meta["format"] == artefact.FORMAT and syn.meta["date"] == "2026-12-06"
  assert (syn.hand, syn.b, syn.actuators) == ("shadow20", 3, tuple(hands.actuators("shadow20")))
  assert syn.meta["hand"]["ctrlrange"][0][0] < syn.meta["hand"]["ctrlrange"][0][1]
  assert syn.learned_on == {"tasks": ["valve0", "valve1", "valve2", "valve3"],
                            "env_steps": 1_536_000, "seed": 0, "method": "DiscoSyn3-L-reward",
                            "set": "set1"}
  evals = [json.loads(line) for line in open(os.path.join(RECORD, "eval.jsonl"))]
  assert syn.success["valve1"] == pytest.approx(np.mean([e["valve1/success"] for e in evals[-3:]]),
                                                abs=1e-4)
  # the decoder's mean: W tanh(z) + c for a linear decoder of bounded z
  z = np.array([[0.3, -1.2, 2.0]], np.float32)
  kernel, bias = params["synergies"]["kernel"], params["synergies"]["bias"]
  np.testing.assert_allclose(syn.decode(z), np.tanh(z) @ kernel + bias, rtol=1e-5, atol=1e-6)
  np.testing.assert_allclose(syn.matrix, kernel.T, rtol=1e-6)
  # from the command line, the same file
  assert cli.main(["synergies", RECORD, "--export", str(tmp_path / "cli.npz")]) == 0
  again = ds.Synergies.load(tmp_path / "cli.npz")
  jax.tree.map(np.testing.assert_array_equal, again.params, params)


def test_an_older_synergy_file_still_loads_with_its_hand_unknown(tmp_path):
  meta, params = fitting.read(RECORD)
  fitting.save(tmp_path / "old.npz", params, meta)  # no format, no hand
  old = ds.Synergies.load(tmp_path / "old.npz")
  assert old.hand is None and old.actuators is None and old.b == 3
  old.check_hand(hands.actuators("shadow20"))  # 20 actuators: the size is all it can check
  with pytest.raises(artefact.SynergyFileError, match="drives 20 actuators, .* has 16"):
    old.check_hand(hands.actuators("leap16"))


def test_the_shipped_files_load_by_name_everywhere_a_path_does():
  shipped = ds.shipped_synergies()
  assert {"shadow20-set1", "shadow20-set2", "leap16-set1"} <= set(shipped)
  for name in shipped:
    syn = ds.Synergies.load(name)
    assert syn.source == fitting.SHIPPED / f"{name}.npz"
    assert syn.hand == name.split("-")[0] and syn.learned_on["method"].startswith("DiscoSyn")
    assert os.path.getsize(syn.source) < 20_000  # KBs
    assert os.path.isfile(os.path.join(helpers.ROOT, "docs/synergies/shipped", f"{name}.png"))
  # the shipped set #1 file is that run's decoder
  jax.tree.map(np.testing.assert_array_equal, ds.Synergies.load("shadow20-set1").params,
               fitting.read(RECORD)[1])
  # --decoder-from NAME: the config keeps the name, the run starts from the shipped decoder
  from discosyn import commands

  args = cli.build_parser().parse_args(["train", "--tasks", "valve_cylinder",
                                        "--decoder-from", "shadow20-set1"])
  config = commands.train_config(args)
  assert config.decoder_from == "shadow20-set1" and config.freeze_decoder
  jax.tree.map(np.testing.assert_array_equal, fitting.load_decoder("shadow20-set1", config),
               fitting.read(RECORD)[1])


def test_the_wrapped_envs_action_is_the_decoders_output():
  syn = ds.Synergies.load("shadow20-set1")
  env = helpers.env("valve1")
  wrapped = ds.synergy_env(env, syn)
  assert wrapped.action_size == 3 and wrapped.observation_size == env.observation_size
  u = jnp.array([0.5, -0.25, 0.9])
  # u is what the decoder read in training: tanh(z), so D(u) = decode(arctanh(u))
  np.testing.assert_allclose(wrapped.action(u), syn.decode(np.arctanh(np.asarray(u))[None])[0],
                             rtol=1e-5, atol=1e-6)
  state = wrapped.reset(jax.random.PRNGKey(0))
  stepped = wrapped.step(state, u)
  direct = env.step(state, wrapped.action(u))
  np.testing.assert_array_equal(np.asarray(stepped.obs), np.asarray(direct.obs))
  np.testing.assert_array_equal(np.asarray(stepped.pipeline_state.qpos),
                                np.asarray(direct.pipeline_state.qpos))
  # jitted and batched, as an RL library runs it
  batch = jax.jit(jax.vmap(wrapped.step))(jax.vmap(wrapped.reset)(jax.random.split(jax.random.PRNGKey(1), 2)),
                                          jnp.zeros((2, 3)))
  assert batch.obs.shape == (2, env.observation_size)


def test_another_hands_file_a_missing_name_and_a_damaged_file_are_refused_in_one_line(tmp_path, capsys):
  leap = helpers.env("valve1", hand="leap16")
  with pytest.raises(artefact.SynergyFileError,
                     match=r"shadow20-set1.npz drives the shadow20 hand \(20 actuators\), not the "
                           r"env's hand \(leap16\) \(16 actuators\)"):
    ds.synergy_env(leap, "shadow20-set1")
  with pytest.raises(artefact.SynergyFileError, match="no shipped synergies have that name .*shadow20-set1"):
    ds.Synergies.load("shadow99-set9")
  (tmp_path / "bad.npz").write_bytes(b"not a zip at all")
  with pytest.raises(artefact.SynergyFileError, match="bad.npz is not a synergy file"):
    ds.Synergies.load(tmp_path / "bad.npz")
  # from the command line: one line, exit 2, no run folder made
  for source, line in (("leap16-set1", "leap16-set1 drives the leap16 hand (16 actuators), "
                        "not shadow20 (20 actuators)"),
                       ("shadow99-set9", "no shipped synergies have that name"),
                       (str(tmp_path / "bad.npz"), "bad.npz is not a synergy file")):
    out = tmp_path / "run"
    code = cli.main(["train", "--tasks", "valve_cylinder", "--decoder-from", source, "--steps", "1",
                     "--out", str(out), "--no-progress"])
    err = [l for l in capsys.readouterr().err.splitlines() if l]
    assert code == 2 and len(err) == 1 and line in err[0], err
    assert not out.exists()


SCRIPT = """
import jax, numpy as np
import discosyn_jax as ds
from brax.training.agents.ppo import train as ppo

for env in (ds.make_env("valve1"), ds.synergy_env(ds.make_env("valve1"), "shadow20-set1")):
  _, params, metrics = ppo.train(environment=env, num_timesteps=40, episode_length=10, num_envs=4,
                                 batch_size=4, unroll_length=5, num_minibatches=2,
                                 num_updates_per_batch=1, num_evals=2, num_eval_envs=2, seed=0)
  print("RESULT", env.action_size, bool(np.isfinite(metrics["eval/episode_reward"])),
        all(np.isfinite(x).all() for x in jax.tree.leaves(params)))
"""


def test_brax_own_ppo_runs_from_a_users_script_on_the_plain_and_the_synergy_env(tmp_path):
  """As README tells a user: nothing patched in the script; the JAX that Brax 0.14.2 still
  calls is given back by the package (run/jax_setup.py)."""
  (tmp_path / "script.py").write_text(SCRIPT)
  out = subprocess.run([sys.executable, str(tmp_path / "script.py")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=900)
  assert out.returncode == 0, out.stderr[-3000:]
  results = [l.split()[1:] for l in out.stdout.splitlines() if l.startswith("RESULT")]
  assert results == [["20", "True", "True"], ["3", "True", "True"]]
