"""The GPU rows of ``billiard bench --only ensemble`` (bench/ensemble.py) under numba's
CUDA simulator (in a fresh interpreter: numba.cuda is the simulator there and nowhere
else): they time the path a sweep takes, on which each trajectory brings back its stats
and its kept impacts alone, and the kernel on the same ensemble."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys

import pytest

from billiard.kernels.ensemble import NSTAT
from tests.copies import COUNT_COPIES

_RATE = (
    COUNT_COPIES
    + """
import json
from bench import ensemble
from billiard.engine import gpu
assert gpu.simulated()
rate = ensemble.gpu_rate(4, 5, 1)
print(json.dumps(rate | {"copied": sum(copied)}))
"""
)


@pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None, reason="no numba-cuda")
def test_the_gpu_rate_times_the_reduced_copy_and_its_kernel(tmp_path):
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=root)
    done = subprocess.run(
        [sys.executable, "-c", _RATE], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr[-3000:]
    rate = json.loads(done.stdout.splitlines()[-1])
    starts = rate["starts"]
    assert starts > 0 and rate["impacts"] == starts * 5
    assert rate["whole_to_kernel"] == rate["impacts_per_s"] / rate["kernel_impacts_per_s"]
    # the compiling call, the whole call and the kernel's: each trajectory brings back
    # no more than a sweep stores of it
    per_run = rate["copied"] / (3 * starts)
    assert NSTAT * 8 <= per_run <= 100 + 16 * rate["keep"] + NSTAT * 8
