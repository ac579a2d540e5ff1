"""The GPU path of ensembles and sweeps under numba's CUDA simulator
(``NUMBA_ENABLE_CUDASIM=1``, in a fresh interpreter: numba.cuda is the simulator there
and nowhere else). The simulator runs the device twin as Python on numpy floats, so its
results are the CPU's bit for bit: the same sweep file, byte for byte, and the same
ensemble measurements. Without a GPU, ``--device gpu`` is a one-line error."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import pytest

import billiard
from billiard.cli import main
from billiard.engine import gpu

needs_numba_cuda = pytest.mark.skipif(
    importlib.util.find_spec("numba_cuda") is None, reason="numba-cuda is not installed"
)

SWEEP = [
    "sweep", "wedge-6.6hz", "--vary", "initial.q1=-0.01:0.01:2", "--vary", "initial.q2=0.07,0.09",
    "--impacts", "12", "--transient", "6", "--keep", "4", "--no-plot", "--workers", "1",
]  # fmt: skip

_ENSEMBLE = """
import sys
import numpy as np
import billiard
from billiard.engine import gpu
assert gpu.simulated() and gpu.available() is None
gpu.BATCH = 2  # three trajectories in two launch batches
q1, q2 = np.array([-0.01, 0.0, 0.012]), np.array([0.06, 0.08, 0.1])
kw = dict(q1=q1, q2=q2, impacts=15, transient=10, keep=15)
g = billiard.run_ensemble("wedge-6.6hz", device="gpu", **kw)
c = billiard.run_ensemble("wedge-6.6hz", **kw)
for name in c.columns:
    assert np.array_equal(g.columns[name], c.columns[name]), name
assert np.array_equal(g.last_height, c.last_height) and np.array_equal(g.last_tof, c.last_tof)
assert all(np.array_equal(g.final[k], c.final[k]) for k in c.final)
print("same", g.device, c.device)
"""


def _simulated(args: list[str], cwd) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}
    return subprocess.run(
        [sys.executable, *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=600
    )


@needs_numba_cuda
def test_a_gpu_ensemble_under_the_simulator_is_the_cpu_ensemble(tmp_path):
    done = _simulated(["-c", _ENSEMBLE], tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["same", "gpu", "cpu"]


@needs_numba_cuda
def test_a_gpu_sweep_under_the_simulator_writes_the_cpu_sweeps_bytes(tmp_path, capsys):
    gpu_out, cpu_out = tmp_path / "gpu", tmp_path / "cpu"
    done = _simulated(
        ["-m", "billiard.cli", *SWEEP, "--device", "gpu", "--out", str(gpu_out)], tmp_path
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "trajectories on the GPU" in (gpu_out / "sweep.log").read_text()
    assert main([*SWEEP, "--out", str(cpu_out)]) == 0
    assert (gpu_out / "sweep.nc").read_bytes() == (cpu_out / "sweep.nc").read_bytes()


#: a parameter map: every trajectory of a chunk with its own drive and restitution
MAP = [
    "sweep", "wedge-6.6hz", "--vary", "drive.frequency=6.2:6.8:3", "--vary",
    "drive.amplitude=0.02,0.03", "--vary", "contact.restitution=0.35,0.45", "--impacts", "12",
    "--transient", "6", "--keep", "4", "--no-plot", "--workers", "1",
]  # fmt: skip


@needs_numba_cuda
def test_a_gpu_parameter_map_under_the_simulator_writes_the_cpu_maps_bytes(tmp_path):
    gpu_out, cpu_out = tmp_path / "gpu", tmp_path / "cpu"
    done = _simulated(
        ["-m", "billiard.cli", *MAP, "--device", "gpu", "--out", str(gpu_out)], tmp_path
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert main([*MAP, "--out", str(cpu_out)]) == 0
    assert (gpu_out / "sweep.nc").read_bytes() == (cpu_out / "sweep.nc").read_bytes()


def test_device_gpu_without_a_gpu_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(gpu, "available", lambda: "no CUDA GPU: numba-cuda found no CUDA GPU")
    code = main([*SWEEP, "--device", "gpu", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err == "billiard: error: --device gpu: no CUDA GPU: numba-cuda found no CUDA GPU\n"
    assert not (tmp_path / "out").exists()


PHASES = [
    "sweep", "wedge-6.6hz", "--set", "contact.model=phases", "--vary", "initial.q1=-0.01,0.01",
    "--impacts", "6", "--no-plot", "--workers", "1",
]  # fmt: skip


def test_contact_phases_with_device_gpu_run_on_the_cpu_and_say_so(tmp_path, monkeypatch):
    """The GPU kernels have the impacts model only: a sweep's contact-phases points run on
    the CPU, and its log says so and why; an ensemble refuses, naming the reason and the
    device that runs it."""
    monkeypatch.setattr(gpu, "available", lambda: None)  # no GPU is touched
    out = tmp_path / "out"
    assert main([*PHASES, "--device", "gpu", "--out", str(out)]) == 0
    log = (out / "sweep.log").read_text()
    assert (
        "(trajectories on the GPU; contact phases on the CPU: the GPU kernels have the "
        "impacts model only)" in log
    )
    scene = billiard.load_scene("wedge-6.6hz")
    phases = billiard.with_values(scene, {"contact.model": "phases"})
    with pytest.raises(ValueError) as refused:
        billiard.run_ensemble(phases, q1=[0.0], q2=[0.06], impacts=2, device="gpu")
    assert str(refused.value) == (
        "contact.model = 'phases' runs on the CPU only: the GPU kernels have the impacts "
        "model, not the contact state machine (use device 'cpu')"
    )
