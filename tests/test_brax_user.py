"""What a user of Brax meets first: a script that imports the package and Brax in either
order prints no notice about the absent Warp, runs Brax's PPO before it makes any env of
ours, and reads Brax's `eval/episode_success` as a rate."""

import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.wrappers import training

from discosyn_jax.env import wrappers
from tests.toy_env import ReachAction

PPO = """
_, params, metrics = ppo.train(environment=env, num_timesteps=40, episode_length=10, num_envs=4,
                               batch_size=4, unroll_length=5, num_minibatches=2,
                               num_updates_per_batch=1, num_evals=2, num_eval_envs=2, seed=0)
"""
# Brax's own env first, then one of ours
SCRIPT = """
import numpy as np
{imports}
from brax import envs
env = envs.get_environment("fast")
{ppo}
print("RESULT fast", bool(np.isfinite(metrics["eval/episode_reward"])))
env = ds.make_env("valve1")
{ppo}
print("RESULT valve1", 0 <= float(metrics["eval/episode_success"]) <= 1)
"""
ORDERS = {"package first": "import discosyn_jax as ds\nfrom brax.training.agents.ppo import train as ppo",
          "brax first": "from brax.training.agents.ppo import train as ppo\nimport discosyn_jax as ds"}


def run_script(tmp_path, imports: str) -> subprocess.CompletedProcess:
  (tmp_path / "script.py").write_text(SCRIPT.format(imports=imports, ppo=PPO))
  out = subprocess.run([sys.executable, str(tmp_path / "script.py")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=900)
  assert out.returncode == 0, out.stderr[-3000:]
  assert [l for l in out.stdout.splitlines() if l.startswith("RESULT")] == \
      ["RESULT fast True", "RESULT valve1 True"]
  return out


def test_a_script_that_imports_the_package_first_is_quiet_and_runs_brax_ppo_before_any_env(tmp_path):
  out = run_script(tmp_path, ORDERS["package first"])
  assert "Failed to import" not in out.stdout + out.stderr  # MJX's notices about the absent Warp


def test_a_script_that_imports_brax_first_runs_its_ppo_too(tmp_path):
  run_script(tmp_path, ORDERS["brax first"])  # Brax's notices printed before the package was there


def test_importing_the_package_imports_no_jax_and_quiets_mjx_imported_later():
  code = ("import sys, discosyn_jax; print('RESULT', 'jax' in sys.modules, 'mujoco' in sys.modules);"
          "import mujoco.mjx")
  out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
  assert out.returncode == 0, out.stderr
  assert out.stdout.splitlines() == ["RESULT False False"]


def test_episode_success_sums_to_the_success_at_each_episodes_last_step():
  """Brax's EvalWrapper sums a metric over the episode: with EpisodeSuccess the sum is the
  success of the episode's last state, for the episode Brax evaluates and for those that
  follow its auto-reset; each state's own success stays in info["success"]."""
  length, batch, steps = 5, 6, 15
  target = 0.5
  env = training.EvalWrapper(training.wrap(wrappers.EpisodeSuccess(ReachAction(target)),
                                           episode_length=length))
  rng = np.random.default_rng(0)
  hits = rng.random((steps, batch)) < 0.5  # a success at this step or not, per env
  state = env.reset(jax.random.split(jax.random.PRNGKey(0), batch))
  assert np.asarray(state.metrics["success"]).tolist() == [0.0] * batch
  step = jax.jit(env.step)
  summed, sums, ends = np.zeros(batch), [], []
  for t in range(steps):
    action = jnp.where(jnp.asarray(hits[t])[:, None], target, -target) * jnp.ones((batch, 20))
    state = step(state, action)
    np.testing.assert_array_equal(np.asarray(state.info["success"]), hits[t])
    summed += np.asarray(state.metrics["success"])
    done = np.asarray(state.done) > 0
    sums.append(summed[done].copy())
    ends.append(hits[t][done].astype(float))
    summed[done] = 0.0
    if t == length - 1:  # Brax's own sum, of the first episode
      np.testing.assert_array_equal(
          np.asarray(state.info["eval_metrics"].episode_metrics["success"]), hits[t])
  assert len(np.concatenate(sums)) == batch * steps // length
  np.testing.assert_allclose(np.concatenate(sums), np.concatenate(ends))
