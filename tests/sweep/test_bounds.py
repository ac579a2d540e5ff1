"""``billiard sweep`` on the inputs of issue 22: runs that must end, numbers checked up
front, sweeps under ``contact.model = "phases"``, a ``--dask`` address that is not a
scheduler, bounded memory and output, run folders and edited definitions.

Each sweep is a few points of a few hundred impacts; the Dask and size checks run no
point at all.
"""

from __future__ import annotations

import gc
import importlib
import io
import json
import socketserver
import subprocess
import sys
import threading
import time
import tracemalloc
from fractions import Fraction
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

import billiard
from billiard import load_scene
from billiard.cli import main
from billiard.status import Status
from billiard.sweep import (
    StopSweep,
    Sweep,
    SweepError,
    SweepInterrupted,
    parse_vary,
    read_result,
    run_sweep,
)
from billiard.sweep import execute as sweep_execute
from billiard.sweep.attractor import CLASSES, contact_class
from billiard.sweep.progress import SweepProgress

REPO = Path(__file__).resolve().parents[2]


def _quiet(sweep: Sweep) -> SweepProgress:
    return SweepProgress(sweep.size, stream=io.StringIO())


def _cli(capsys, *argv):
    code = main(["sweep", *argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _one_line_error(code: int, err: str) -> None:
    assert code == 2, err
    assert err.startswith("billiard: error: ") and err.count("\n") == 1, err


# --- the pre-check and the resting height never simulate open-ended ---------------------

#: A ball at rest in the parabola under the phases model, shaken gently: it rolls with
#: the boundary and never has an impact (a run that asks for one impact runs for ever
#: unless something bounds its simulated time).
ROLLING = ["contact.model=phases", "drive.amplitude=0.005"]


@pytest.fixture
def bounded_simulate(monkeypatch):
    """billiard.run.simulate.simulate, refusing any call without a finite duration (the durations
    asked for are recorded)."""
    module = importlib.import_module("billiard.run.simulate")
    real = module.simulate
    asked: list[float] = []

    def simulate(scene, **kwargs):
        duration = kwargs.get("duration")
        if duration is None:
            duration = scene.run.duration
        if duration is None:
            raise AssertionError("simulate() called without a duration: it may never end")
        asked.append(float(duration))
        return real(scene, **kwargs)

    monkeypatch.setattr(module, "simulate", simulate)
    return asked


def test_precheck_honours_the_sweep_duration_and_never_runs_open_ended(bounded_simulate):
    scene = load_scene("parabola-5.4hz", overrides=ROLLING)
    axes = (parse_vary("drive.frequency=5.0,5.4"),)
    sweep_execute.prepare(Sweep(scene, axes, duration=0.25))
    assert bounded_simulate == [0.25]
    bounded_simulate.clear()
    # without a duration the check still ends: one impact, or PRECHECK_SPAN of time
    sweep_execute.prepare(Sweep(scene, axes))
    assert bounded_simulate == [sweep_execute.PRECHECK_SPAN]


def test_resting_height_needs_no_open_ended_run(bounded_simulate):
    from billiard.sweep.measure import _rest_height

    scene = load_scene("parabola-5.4hz", overrides=ROLLING)
    # the parabola's bottom 0.0063 m plus the ball's radius 1.55 mm
    assert _rest_height(scene) == pytest.approx(0.0063 + 1.55e-3, abs=1e-12)


def test_phases_sweep_with_a_duration_ends_and_classifies_the_rolling_ball(tmp_path, capsys):
    out = tmp_path / "roll"
    code, stdout, err = _cli(
        capsys, "parabola-5.4hz", *(a for s in ROLLING for a in ("--set", s)),
        "--vary", "drive.frequency=5.0,5.4", "--duration", "1.5",
        "--impacts", "20", "--transient", "5", "--workers", "1", "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    assert "2 rolling" in stdout
    data = read_result(out / "sweep.nc")
    assert list(data["attractor"]) == ["rolling", "rolling"]
    assert list(data["status"]) == ["ok", "ok"]
    assert list(data["run_status"]) == ["time_limit", "time_limit"]
    assert list(data["final_mode"]) == ["roll", "roll"]
    assert list(data["impacts"]) == [0, 0]
    assert np.isnan(data["height_mean"]).all()
    assert data["rest_height"][0] == pytest.approx(0.0063 + 1.55e-3, abs=1e-12)


# --- classes under the phases model -------------------------------------------------------


def test_contact_classes_are_added_after_the_existing_codes():
    old = ("failed", "resting", "periodic", "quasi-periodic", "chaotic", "aperiodic", "invalid")
    assert CLASSES[: len(old)] == old
    assert CLASSES[len(old) :] == ("rolling", "sliding", "held")


@pytest.mark.parametrize(
    ("status", "mode", "measured", "expected"),
    [
        (Status.AT_REST, "roll", 0, "resting"),
        (Status.AT_REST, "held", 7, "resting"),
        (Status.IN_CONTACT, "roll", 0, "rolling"),
        (Status.IN_CONTACT, "slide", 0, "sliding"),
        (Status.IN_CONTACT, "held", 0, "held"),
        (Status.IN_CONTACT, "held", 12, "held"),  # impacts, then held for contact_span
        (Status.TIME_LIMIT, "roll", 0, "rolling"),
        (Status.TIME_LIMIT, "slide", 0, "sliding"),
        (Status.TIME_LIMIT, "held", 0, "held"),
        (Status.TIME_LIMIT, "roll", 40, None),  # impacts after the transient: an orbit
        (Status.TIME_LIMIT, "flight", 0, None),  # a long flight: no attractor to name
        (Status.COMPLETE, "roll", 100, None),
        (Status.COMPLETE, "flight", 100, None),
        (Status.ESCAPED, "flight", 0, None),
    ],
)
def test_contact_class_from_status_and_final_mode(status, mode, measured, expected):
    assert contact_class(status, mode, measured) == expected


def test_phases_ball_at_rest_is_resting_not_failed(tmp_path):
    # a static boundary: the ball lies at the bottom, the run ends AT_REST at once
    scene = load_scene("parabola-5.4hz", overrides=["contact.model=phases", "drive.amplitude=0"])
    sweep = Sweep(scene, (parse_vary("drive.frequency=5.0,5.4"),), impacts=30, transient=10)
    outcome = run_sweep(sweep, tmp_path / "rest", workers=1, progress=_quiet(sweep))
    data = read_result(outcome.result)
    assert list(data["attractor"]) == ["resting", "resting"]
    assert list(data["status"]) == ["ok", "ok"]
    assert list(data["run_status"]) == ["at_rest", "at_rest"]
    assert list(data["reason"]) == ["", ""]
    assert outcome.classes == {"resting": 2}


# --- numbers checked up front; a sweep of failures is not a success -----------------------

BAD_NUMBERS = {
    "duration 1e300": (
        ["--duration", "1e300"],
        "'duration' = 1e+300 s is out of range (0, 1e+09] s",
    ),
    "duration 0": (["--duration", "0"], "'duration' = 0.0 s is out of range (0, 1e+09] s"),
    "duration nan": (["--duration", "nan"], "'duration' must be a finite number (s)"),
    "impacts 10^10": (["--impacts", "10000000000"], "'impacts' = 10000000000 impacts is out"),
    "keep 0": (["--keep", "0"], "'keep' must be an integer >= 1"),
}


@pytest.mark.parametrize("case", BAD_NUMBERS)
def test_bad_sweep_numbers_are_refused_up_front(case, tmp_path, capsys):
    argv, message = BAD_NUMBERS[case]
    out = tmp_path / "out"
    code, _, err = _cli(capsys, "parabola-5.4hz", "--vary", "drive.frequency=5,5.4", *argv,
                        "--out", str(out))  # fmt: skip
    _one_line_error(code, err)
    assert message in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("setting", "value", "message"),
    [
        ("tolerance", 0.0, "'tolerance' = 0.0 m is out of range (0, 1] m"),
        ("tolerance", 5.0, "'tolerance' = 5.0 m is out of range (0, 1] m"),
        ("rest_band", -0.01, "'rest_band' = -0.01 m is out of range (0, 10] m"),
        ("max_period", 500, "'max_period' = 500 impacts is out of range [1, 128] impacts"),
        ("chaos_threshold", float("inf"), "'chaos_threshold' must be a finite number (1/impact)"),
    ],
)
def test_sweep_settings_are_checked_with_their_range_and_unit(setting, value, message):
    with pytest.raises(SweepError) as caught:
        Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=5"),), **{setting: value})
    assert message in str(caught.value)


def test_a_sweep_where_every_point_failed_exits_non_zero(tmp_path, capsys):
    from billiard import with_values
    from billiard.scene.scene import scene_to_toml

    open_top = with_values(load_scene("parabola-5.4hz"), {"boundary.ceiling": None})
    scene_file = tmp_path / "open.toml"
    scene_file.write_text(scene_to_toml(open_top))
    out = tmp_path / "esc"
    code, stdout, err = _cli(
        capsys, str(scene_file), "--vary", "boundary.escape_height=0.04,0.05",
        "--impacts", "20", "--transient", "20", "--workers", "1", "--out", str(out), "--no-plot",
    )  # fmt: skip
    assert code == 3
    assert "2 failed" in stdout
    assert "billiard: point 0 failed: ball escaped above escape_height = 0.04 m" in err
    last = err.strip().splitlines()[-1]
    assert last.startswith("billiard: error: no point of the sweep was measured (2 failed)")
    assert (out / "sweep.nc").exists()  # the reasons are kept


# --- --dask against a live address that is not a Dask scheduler ---------------------------


class _Garbage(socketserver.BaseRequestHandler):
    """Answers any connection with bytes that are no Dask frame, then waits."""

    def handle(self) -> None:
        try:
            self.request.sendall(bytes(range(256)) * 4 + b"HTTP/1.0 200 OK\r\n\r\n" * 8)
            self.request.settimeout(20)
            self.request.recv(65536)
        except OSError:
            pass


def _serve(server: socketserver.BaseServer):
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    return server


@pytest.fixture
def http_server():
    server = _serve(ThreadingHTTPServer(("127.0.0.1", 0), SimpleHTTPRequestHandler))
    server.daemon_threads = True
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def garbage_server():
    socketserver.ThreadingTCPServer.allow_reuse_address = True
    server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), _Garbage)
    server.daemon_threads = True
    _serve(server)
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


def _sweep_process(address: str, out: Path, timeout: float = 90.0):
    """`billiard sweep --dask ADDRESS` in a process of its own, with a 3 s protocol
    timeout: it must end by itself long before ``timeout``."""
    pytest.importorskip("distributed")
    code = (
        "import sys; import billiard.sweep.execute as e; e.DASK_TIMEOUT = 3.0; "
        "from billiard.cli import main; "
        f"sys.exit(main(['sweep', 'parabola-5.4hz', '--vary', 'drive.frequency=5,5.4', "
        f"'--dask', {address!r}, '--out', {str(out)!r}]))"
    )
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, cwd=REPO
    )
    return done, time.monotonic() - started


@pytest.mark.parametrize(
    "server", [pytest.param("http_server", marks=pytest.mark.slow), "garbage_server"]
)  # the HTTP server takes 4 s to refuse; the garbage server is the same check
def test_dask_address_that_is_not_a_scheduler_fails_in_one_line(server, request, tmp_path):
    address = request.getfixturevalue(server)
    out = tmp_path / "out"
    done, seconds = _sweep_process(address, out)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"billiard: error: cannot reach a Dask scheduler at {address}")
    assert done.stderr.count("\n") == 1, done.stderr
    assert "Traceback" not in done.stderr
    assert seconds < 60.0
    assert not out.exists()


def test_dask_probe_accepts_a_real_scheduler():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        sweep_execute.probe_scheduler(cluster.scheduler_address, 10.0)  # no error


# --- bounded resources ---------------------------------------------------------------------


def test_a_huge_axis_is_refused_before_anything_is_materialised(tmp_path):
    tracemalloc.start()
    try:
        axis = parse_vary("drive.frequency=4:7:2000000")
        sweep = Sweep(load_scene("parabola-5.4hz"), (axis,))
        with pytest.raises(SweepError) as caught:
            run_sweep(sweep, tmp_path / "big", workers=1, progress=_quiet(sweep))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2_000_000  # bytes: two million values would take 60 MB or more
    message = str(caught.value)
    assert "the sweep has 2,000,000 points (2,000,000) and would write about 6.98 GB" in message
    # 96 bytes per point and 16 per kept impact (keep = 100): 1,696 bytes a point
    assert "GB (points.npy 3.39 GB, sweep.nc 3." in message
    assert "--yes" in message
    assert not (tmp_path / "big").exists()
    # the values are those of the range, computed when asked for
    assert axis.values[0] == 4.0 and axis.values[-1] == 7.0 and len(axis.values) == 2_000_000
    assert axis.values[1] == 4.0 + 3.0 / 1_999_999


def test_cli_refuses_a_large_grid_without_yes(tmp_path, capsys):
    out = tmp_path / "grid"
    started = time.monotonic()
    code, _, err = _cli(
        capsys, "parabola-5.4hz", "--vary", "drive.frequency=4:7:1000",
        "--vary", "drive.amplitude=0.01:0.03:1000", "--out", str(out),
    )  # fmt: skip
    _one_line_error(code, err)
    assert "the sweep has 1,000,000 points (1,000 x 1,000)" in err
    assert "beyond 100,000 points or 1 GB a sweep runs only with --yes" in err
    assert time.monotonic() - started < 20.0
    assert not out.exists()
    # an axis too long for any sweep (a 10^12-point result file) is refused outright
    code, _, err = _cli(capsys, "parabola-5.4hz", "--vary", "drive.frequency=4:7:1000000000000")
    _one_line_error(code, err)
    assert "at most 1,000,000,000 can be swept" in err


@pytest.mark.parametrize("keep", [5, 150])
def test_size_estimate_is_close_to_the_files_written(tmp_path, keep):
    scene = load_scene("parabola-5.4hz")
    axes = (parse_vary("drive.frequency=5.3:5.5:3"), parse_vary("drive.amplitude=0.025,0.026"))
    sweep = Sweep(scene, axes, impacts=200, transient=20, keep=keep)
    estimate = sweep_execute.estimate_size(sweep)
    outcome = run_sweep(sweep, tmp_path / "s", workers=1, plots=False, progress=_quiet(sweep))
    for name, size in estimate.items():
        written = (outcome.directory / name).stat().st_size
        assert 0.8 * written < size < 1.25 * written, (name, size, written)


def test_range_values_are_the_grids_decimals():
    # value i is the float nearest START + i (STOP - START) / (N - 1) in decimals: what
    # the user asked for, so a result is selected by the value as typed
    for spec, texts in {
        "4:7:31": [f"{4 + i / 10:.1f}" for i in range(31)],
        "0.02:0.03:11": [f"0.0{20 + i}" for i in range(11)],
        "0.012:0.03:7": ["0.012", "0.015", "0.018", "0.021", "0.024", "0.027", "0.03"],
        "-0.003:0.03:12": [f"{-0.003 + 0.003 * i:.3f}" for i in range(12)],
        "0:1:4": ["0", "1/3", "2/3", "1"],
    }.items():
        axis = parse_vary(f"drive.frequency={spec}")
        expected = [float(Fraction(text)) for text in texts]
        assert list(axis.values) == expected, spec
        assert np.asarray(axis.values).tolist() == expected
        assert axis.values == tuple(expected)
    # 0.012 + 5 * 0.003 in floats is 0.026999999999999996: not the value asked for
    assert parse_vary("drive.amplitude=0.012:0.03:7").values[5] == 0.027
    assert parse_vary("drive.frequency=7:4:4").values == (7.0, 6.0, 5.0, 4.0)
    huge = parse_vary("drive.frequency=0:1:999999999").values  # never materialised
    assert huge[-1] == 1.0 and huge[333333333] == float(Fraction(333333333, 999999998))


def _growth(tmp_path: Path, name: str, points: int) -> int:
    """Traced memory of this process after the last point minus after the second (B),
    garbage collected first (cycles awaiting the collector are not kept memory)."""
    axes = (parse_vary(f"drive.frequency=5.35:5.45:{points}"),)
    scene = load_scene("parabola-5.4hz", overrides=["air.drag=none"])
    sweep = Sweep(scene, axes, impacts=300, transient=0, keep=300)
    seen: list[int] = []

    def measure(record) -> None:
        gc.collect()
        seen.append(tracemalloc.get_traced_memory()[0])

    run_sweep(
        sweep,
        tmp_path / name,
        workers=1,
        plots=False,
        progress=_quiet(sweep),
        on_point=measure,
    )
    return seen[-1] - seen[1]


@pytest.mark.slow  # 8 s: 200 finished points
def test_sweep_memory_does_not_grow_with_finished_points(tmp_path):
    tracemalloc.start()
    try:
        small = _growth(tmp_path, "small", 4)
        large = _growth(tmp_path, "large", 24)
    finally:
        tracemalloc.stop()
    # a record of 300 heights and times of flight is about 24 kB in memory: twenty more
    # points kept would add some 480 kB; the sweep's memory must not grow by more than
    # 2 kB per point (the pending tasks of a window, freed at the end, move it by ~25 kB)
    assert large - small < 20 * 2000, (small, large)


def test_sweep_file_that_is_not_a_regular_file_is_refused(tmp_path, capsys):
    code, _, err = _cli(capsys, "--file", "/dev/zero", "--out", str(tmp_path / "z"))
    _one_line_error(code, err)
    assert "sweep file '/dev/zero' is not a regular file" in err


# --- run folders and edited definitions ----------------------------------------------------


def test_sweep_refuses_a_folder_holding_a_run(tmp_path, capsys):
    run_dir = tmp_path / "run"
    billiard.simulate(load_scene("parabola-5.4hz"), collisions=5, out_dir=run_dir)
    capsys.readouterr()  # a first streamed run may print the kernels' compile notice
    scene_bytes = (run_dir / "scene.toml").read_bytes()
    before = sorted(p.name for p in run_dir.iterdir())
    code, _, err = _cli(capsys, "parabola-5.4hz", "--set", "drive.frequency=6",
                        "--vary", "drive.amplitude=0.02,0.03", "--out", str(run_dir))  # fmt: skip
    _one_line_error(code, err)
    assert f"{run_dir} holds a run of `billiard run` (collisions.csv)" in err
    assert (run_dir / "scene.toml").read_bytes() == scene_bytes
    assert sorted(p.name for p in run_dir.iterdir()) == before


def test_sweep_refuses_a_folder_with_a_scene_file_it_would_replace(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "scene.toml").write_text('name = "mine"\n')
    code, _, err = _cli(capsys, "parabola-5.4hz", "--vary", "drive.amplitude=0.02,0.03",
                        "--out", str(folder))  # fmt: skip
    _one_line_error(code, err)
    assert "already holds scene.toml, which the sweep would replace" in err
    assert (folder / "scene.toml").read_text() == 'name = "mine"\n'


def _interrupted(tmp_path: Path) -> Path:
    scene = load_scene("parabola-5.4hz")
    sweep = Sweep(scene, (parse_vary("drive.frequency=5.0,5.2,5.4"),), impacts=40, transient=60)
    directory = tmp_path / "cut"

    def stop(record):
        raise StopSweep

    with pytest.raises(SweepInterrupted, match="points kept"):
        run_sweep(sweep, directory, workers=1, on_point=stop, progress=_quiet(sweep))
    assert len(np.load(directory / "points.npy")) == 1
    return directory


@pytest.mark.parametrize(
    ("name", "old", "new"),
    [
        pytest.param("sweep.toml", "impacts = 40", "impacts = 41", marks=pytest.mark.slow),
        ("scene.toml", "0.393", "0.394"),
    ],
)
def test_resume_refuses_an_edited_definition(tmp_path, capsys, name, old, new):
    directory = _interrupted(tmp_path)
    path = directory / name
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    code, _, err = _cli(capsys, "--resume", str(directory))
    _one_line_error(code, err)
    assert f"cannot resume {directory}: {name} changed since the sweep started" in err
    assert len(np.load(directory / "points.npy")) == 1
    assert not (directory / "sweep.nc").exists()
    if name == "scene.toml":
        return
    # restored, the sweep resumes
    path.write_text(text)
    code, stdout, err = _cli(capsys, "--resume", str(directory), "--no-plot")
    assert code == 0, err
    assert "3 points (2 computed now" in stdout


def test_digest_file_checks_with_sha256sum_format(tmp_path):
    import hashlib

    directory = _interrupted(tmp_path)
    lines = (directory / "sweep.sha256").read_text().splitlines()
    for line in lines:
        digest, name = line.split("  ")
        assert hashlib.sha256((directory / name).read_bytes()).hexdigest() == digest
    assert [line.split("  ")[1] for line in lines] == ["sweep.toml", "scene.toml"]


def test_set_changes_are_kept_in_the_sweep_file_and_not_applied_twice(tmp_path):
    scene = load_scene("parabola-5.4hz", overrides=["air.drag=none"])
    sweep = Sweep(
        scene, (parse_vary("drive.frequency=5.0,5.4"),), impacts=20, transient=20,
        changes=("air.drag=none",),
    )  # fmt: skip
    directory = _interrupted_with(sweep, tmp_path)
    text = (directory / "sweep.toml").read_text()
    assert 'changes = ["air.drag=none"]' in text
    resumed = sweep_execute.load_sweep_dir(directory)
    assert resumed.changes == ("air.drag=none",)
    assert resumed.scene == sweep.scene


def _interrupted_with(sweep: Sweep, tmp_path: Path) -> Path:
    directory = tmp_path / "set"

    def stop(record):
        raise StopSweep

    with pytest.raises(SweepInterrupted, match="points kept"):
        run_sweep(sweep, directory, workers=1, on_point=stop, progress=_quiet(sweep))
    return directory


def test_reasons_file_is_read_line_by_line(tmp_path):
    from billiard.sweep.store import StoreError, read_reasons

    path = tmp_path / "reasons.jsonl"
    lines = [json.dumps({"index": i, "reason": f"r{i}"}) for i in range(3)]
    path.write_text("\n".join(lines) + '\n{"index": 3, "rea')
    assert list(read_reasons(path)) == [(0, "r0"), (1, "r1"), (2, "r2")]
    # only the points stored in points.npy, when asked
    assert list(read_reasons(path, bytearray([1, 0, 1, 1]))) == [(0, "r0"), (2, "r2")]
    path.write_text('{"index": 0, "reason": "r"}\n[1, 2]\n')
    with pytest.raises(StoreError, match="line 2 is not a point's reason"):
        list(read_reasons(path))


def test_a_folder_of_an_older_points_file_is_refused_in_one_line(tmp_path, capsys):
    directory = _interrupted(tmp_path)
    (directory / "points.npy").rename(directory / "points.jsonl")
    code, _, err = _cli(capsys, "--resume", str(directory))
    _one_line_error(code, err)
    assert f"{directory} holds a sweep of an older version (points.jsonl)" in err
    assert not (directory / "points.npy").exists()
