import collections
import os
import shutil
import tempfile
import time
from importlib import metadata

# Nothing the tests do is left behind: the JAX compile cache, matplotlib's font cache,
# Jupyter's kernel files (the notebook test) and anything else written under the home
# folder go to a temporary one, removed when the session ends; MuJoCo's MUJOCO_LOG.TXT
# (written to the working directory on a simulation warning) goes to a temporary working
# directory (`_temporary_working_directory` below). Set before anything imports jax or
# matplotlib.
_SCRATCH = tempfile.mkdtemp(prefix="discosyn-tests-")
os.environ["HOME"] = os.path.join(_SCRATCH, "home")
os.environ["DISCOSYN_JAX_CACHE"] = os.path.join(_SCRATCH, "jax-cache")
# Keep the native backend to one thread per test process on the 2-core CI machine.
os.environ.setdefault("DISCOSYN_NATIVE_THREADS", "2")
# One OpenMP thread: with its threads waiting on each other on 2 busy cores, scikit-learn's
# t-SNE of a few hundred points made the experiments' report take 50 s instead of 10.
os.environ.setdefault("OMP_NUM_THREADS", "1")
# XLA compiles for speed of compiling, not of running: LLVM's optimisations off, and where
# jaxlib still has them (before 0.11) the classic fusion emitters. CPU seconds per compile,
# measured on jaxlib 0.10.2: a train step of the toy tasks 23 -> 11 -> 5, MJX's step on
# valve0 58 -> 38 -> 19; the compiled code runs 1.6x (toy) and 2.5x (MJX) slower.
# Compiling is most of what the tests do; they run few steps. The MuJoCo C physics is
# unaffected. (An XLA flag that jaxlib does not know aborts the process.)
_FAST_COMPILE = ["--xla_backend_optimization_level=0"]
if tuple(int(part) for part in metadata.version("jaxlib").split(".")[:2]) < (0, 11):
  _FAST_COMPILE.append("--xla_cpu_use_fusion_emitters=false")
os.environ["XLA_FLAGS"] = " ".join([os.environ.get("XLA_FLAGS", ""), *_FAST_COMPILE]).strip()

import pytest  # noqa: E402

import discosyn_jax  # noqa: E402  (sets XLA flags before anything imports jax)
from discosyn_jax.run import jax_setup  # noqa: E402

jax_setup.setup_jax()


class _FileProgress:
  """Under xdist pytest prints a dot per test and no file names: on the controller, this
  prints a line as each test file finishes (files run whole on one worker: --dist loadfile)."""

  def __init__(self, reporter):
    self.reporter = reporter
    self.total: collections.Counter | None = None
    self.done: collections.Counter = collections.Counter()
    self.outcomes: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    self.started: dict[str, float] = {}

  def pytest_xdist_node_collection_finished(self, node, ids):
    if self.total is None:  # every worker collects the same tests
      self.total = collections.Counter(nodeid.split("::")[0] for nodeid in ids)

  def pytest_runtest_logstart(self, nodeid, location):
    self.started.setdefault(nodeid.split("::")[0], time.monotonic())

  def pytest_runtest_logreport(self, report):
    path = report.nodeid.split("::")[0]
    if report.when == "call" or report.outcome != "passed":
      self.outcomes[path][report.outcome] += 1
    if report.when == "teardown" and self.total:
      self.done[path] += 1
      if self.done[path] == self.total[path]:
        if getattr(self.reporter._tw, "width_of_current_line", 0):  # after xdist's dots
          self.reporter.write("\n")
        counts = ", ".join(f"{n} {outcome}" for outcome, n in sorted(self.outcomes[path].items()))
        self.reporter.write_line(
            f"{path}: {counts} in {time.monotonic() - self.started[path]:.0f} s")


@pytest.hookimpl(trylast=True)  # after the terminal reporter is registered
def pytest_configure(config):
  if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
      config.pluginmanager.register(_FileProgress(reporter), "discosyn-file-progress")


def pytest_unconfigure(config):
  # at the session's end, not at exit: with an atexit handler the folder was sometimes left
  # behind (JAX's exit handler can end the process with os._exit before it runs)
  shutil.rmtree(_SCRATCH, ignore_errors=True)


@pytest.fixture(autouse=True, scope="session")
def _temporary_working_directory(tmp_path_factory):
  cwd = os.getcwd()
  os.chdir(tmp_path_factory.mktemp("cwd"))
  yield
  os.chdir(cwd)


@pytest.fixture(scope="session")
def valve3_on_both_backends():
  """50 control steps (2 s) of a grasp-and-sweep that turns valve3, reset and stepped on each
  backend: {backend: (env, states stacked over time)}. The one MJX reset of the suite; the
  MJX compile dominates, so the tests of valve3's MJX path share it."""
  import jax
  import jax.numpy as jnp

  from discosyn_jax.env import scripted
  from tests import helpers

  actions = jnp.asarray(scripted.grasp_and_sweep(50, 0.04))
  out = {}
  for backend in ("native", "mjx"):
    env = helpers.env("valve3", backend)

    def roll(key, env=env):
      state = env.reset(key)
      return jax.lax.scan(lambda s, a: (env.step(s, a),) * 2, state, actions)[1]

    out[backend] = (env, jax.jit(roll)(jax.random.PRNGKey(3)))
  return out


@pytest.fixture(autouse=True)
def _a_cheap_physics_prior(monkeypatch):
  """Runs that start from a prior (the quickstart's default) make it from 4
  states per task here instead of 640 (test_priors.py tests the prior itself; a
  training in a subprocess makes the whole one)."""
  from discosyn_jax.synergies import priors

  monkeypatch.setattr(priors, "ENVS", 2)
  monkeypatch.setattr(priors, "EVERY", 50)
