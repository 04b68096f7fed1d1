"""Many devices, one run: the train step split over 2 CPU devices equals the 1-device step."""

import json
import os
import subprocess
import sys

import jax
import pytest

from discosyn_jax.training import devices
from tests.helpers import ROOT


def test_two_cpu_devices_give_the_one_device_results(tmp_path):
  # the device count is read when XLA starts: a process of its own (this one keeps 1 device)
  env = dict(os.environ, PYTHONPATH=ROOT,
             XLA_FLAGS=os.environ["XLA_FLAGS"] + " --xla_force_host_platform_device_count=2")
  run = subprocess.run([sys.executable, "-m", "tests.two_devices"], capture_output=True,
                       text=True, env=env, cwd=tmp_path)
  assert run.returncode == 0, run.stderr[-3000:]
  out = json.loads(run.stdout.strip().splitlines()[-1])
  assert out["toy_max_param_diff"] < 1e-4, out
  assert out["toy_losses"][0] == pytest.approx(out["toy_losses"][1], rel=1e-5)
  assert out["native_max_param_diff"] < 1e-4, out
  one, two = out["native_eval"]  # evaluated after that step: every figure finite, alike
  assert one.keys() == two.keys() == {"valve1"}
  for key, value in one["valve1"].items():
    assert two["valve1"][key] == pytest.approx(value, abs=0.05), out
  # the native backend's host callback stepped the 4 training envs in one call on one
  # device, 2 per call on two; the 3 evaluation envs are not split
  assert out["native_callback_batches"] == [[3, 4], [2, 3]]
  assert out["odd_batch_error"] == "num_envs = 5 does not split over 2 devices"


def test_this_process_has_one_device_and_bad_counts_are_refused():
  assert jax.device_count() == 1
  assert devices.make_mesh().size == 1
  with pytest.raises(ValueError, match="between 1 and 1"):
    devices.make_mesh(2)



def test_train_refuses_more_devices_than_there_are_before_making_the_run(tmp_path, capsys):
  from discosyn import cli

  out = tmp_path / "run"
  assert cli.main(["train", "--devices", "2", "--out", str(out), "--no-progress"]) == 2
  assert "--devices must be between 1 and 1" in capsys.readouterr().err
  assert not out.exists()
