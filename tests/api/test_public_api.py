"""The documented Python API (README "Python API") is the same every time it is used:
``billiard.analysis.calibrate`` and ``from billiard import calibrate`` are the function, also
after the module that defines it has been imported (by the CLI, by ``reproduce``, or by
the user)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

EXPORTS = (
    "calibrate",
    "plot_run",
    "read_collisions",
    "load_curve",
    "camera_filter",
    "simulate",
    "open_run",
    "view",
)


def test_exports_are_the_functions_every_time():
    """In a fresh interpreter: each name twice through the package, then again after
    every module behind them has been imported, then used."""
    code = textwrap.dedent(
        f"""
        import importlib, types
        import billiard
        names = {EXPORTS!r}
        first = {{n: getattr(billiard, n) for n in names}}
        for n in names:
            assert getattr(billiard, n) is first[n], n
            assert callable(first[n]) and not isinstance(first[n], types.ModuleType), n
        for module in ("billiard.analysis.calibrate", "billiard.plot", "billiard.plot.interactive",
                       "billiard.runfile.record", "billiard.geometry.curves",
                       "billiard.analysis.camera", "billiard.run.simulate",
                       "billiard.reproduce.paper", "billiard.cli", "billiard.run.load"):
            importlib.import_module(module)
        import billiard.analysis.calibrate
        from billiard import plot_run, read_collisions, load_curve, camera_filter
        from billiard import calibrate, open_run
        again = dict(calibrate=calibrate, plot_run=plot_run, read_collisions=read_collisions,
                     load_curve=load_curve, camera_filter=camera_filter, open_run=open_run)
        for n, f in again.items():
            assert f is first[n], (n, f)
            assert getattr(billiard, n) is first[n], n
        scene = billiard.load_scene("parabola-5.4hz")
        for _ in range(2):
            try:
                billiard.calibrate(scene, "drive.amplitude", -1.0)
            except Exception as exc:
                assert type(exc).__name__ == "CalibrationError", exc
        print("ok")
        """
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "ok"
