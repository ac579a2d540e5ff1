"""``billiard sweep``: measured attractors, the result file, determinism across workers,
interruption and resume, a Dask cluster, and bad input.

The sweeps are tiny (a few points of a few hundred impacts); most of the time goes into
starting worker processes.
"""

from __future__ import annotations

import io
import re
import shutil
import sys

import numpy as np
import pytest

from billiard import load_scene, with_values
from billiard.cli import main
from billiard.runfile.npyfile import header_size
from billiard.sweep import (
    StopSweep,
    Sweep,
    SweepError,
    SweepInterrupted,
    parse_vary,
    read_result,
    run_sweep,
)
from billiard.sweep.progress import SweepProgress


def _sweep(**settings) -> Sweep:
    axes = (parse_vary("drive.amplitude=0.015,0.02543"), parse_vary("drive.frequency=5.0:5.4:2"))
    args = {"impacts": 80, "transient": 150, "keep": 12} | settings
    return Sweep(load_scene("parabola-5.4hz"), axes, **args)


def _quiet(sweep: Sweep) -> SweepProgress:
    return SweepProgress(sweep.size, stream=io.StringIO())


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted sweep on one worker process."""
    sweep = _sweep()
    directory = tmp_path_factory.mktemp("reference")
    outcome = run_sweep(sweep, directory, workers=1, progress=_quiet(sweep))
    return sweep, outcome


def test_measures_the_calibrated_orbit_and_the_resting_ball(reference):
    sweep, outcome = reference
    data = read_result(outcome.result)
    assert list(data["drive_amplitude"]) == [0.015, 0.02543]
    assert list(data["drive_frequency"]) == [5.0, 5.4]
    # 25.43 mm at 5.4 Hz: the paper's orbit, one impact per half drive period, alternating
    # sides: the state repeats after two impacts, one drive period
    assert data["attractor"][1, 1] == "periodic"
    assert data["period"][1, 1] == 2
    assert data["drive_periods"][1, 1] == 1
    assert data["height_mean"][1, 1] == pytest.approx(0.07499, abs=2e-5)
    assert data["height_std"][1, 1] < 1e-6
    assert data["tof_mean"][1, 1] == pytest.approx(1 / (2 * 5.4), rel=1e-6)
    assert data["elastic_share"][1, 1] == 0.0
    assert data["lid_share"][1, 1] == 0.0
    # 15 mm at 5.4 Hz: chattering in the bottom, mostly low-velocity-rule impacts
    assert data["attractor"][0, 1] == "resting"
    assert data["elastic_share"][0, 1] > 0.5
    assert data["height_max"][0, 1] - data["rest_height"][0, 1] < 0.01
    assert data["rest_height"][0, 1] == pytest.approx(0.0063 + 1.55e-3)
    # the last K impacts are the run's last K heights
    assert data["last_height"].shape == (2, 2, 12)
    assert np.all(data["last_height"][1, 1] == pytest.approx(0.07499, abs=2e-5))
    assert list(data["impact"]) == list(range(-12, 0))
    assert set(data["status"].ravel()) == {"ok"}
    assert np.isnan(data["lyapunov"]).all()  # not asked for
    assert [p.name for p in outcome.plots] == ["heatmaps.png"]


def test_result_file_is_self_describing(reference):
    from scipy.io import netcdf_file

    _, outcome = reference
    with netcdf_file(outcome.result, "r", mmap=False) as f:
        freq = f.variables["drive_frequency"]
        assert freq.units == b"Hz"
        assert freq.scene_key == b"drive.frequency"
        assert f.variables["height_mean"].units == b"m"
        assert f.variables["tof_mean"].units == b"s"
        assert f.variables["height_mean"].dimensions == ("drive_amplitude", "drive_frequency")
        assert f.variables["last_tof"].dimensions[-1] == "impact"
        assert b'"drive.amplitude" = [0.015, 0.02543]' in f.sweep_definition
        assert b'curve = "parabola"' in f.base_scene
    text = outcome.result.read_bytes()
    assert b"points/s" not in text and b"impacts/s" not in text  # no timings inside
    log = (outcome.directory / "sweep.log").read_text()
    assert "impacts/s" in log


def test_outcome_prints_in_one_short_line(reference):
    _, outcome = reference
    text = repr(outcome)
    assert text == (
        f"<SweepOutcome {outcome.directory}: points 4 (4 ok); attractors 2 resting, "
        "1 periodic, 1 aperiodic; computed 4 in this session on 1 local worker process; "
        "files sweep.nc, heatmaps.png>"
    )
    assert "last_height" not in text  # no record is dumped
    html = outcome._repr_html_()
    assert html.startswith("<table>") and html.endswith("</table>")
    assert "<th style='text-align:left'>attractors</th>" in html
    assert "<td style='text-align:left'>2 resting, 1 periodic, 1 aperiodic</td>" in html


def test_outcome_dataset_is_the_result_in_xarray(reference):
    _, outcome = reference
    data = read_result(outcome.result)
    with outcome.dataset as ds:
        orbit = ds.sel(drive_amplitude=0.02543, drive_frequency=5.4)
        assert float(orbit.height_mean) == data["height_mean"][1, 1]
        assert ds.height_mean.attrs["units"] == "m"
        np.testing.assert_array_equal(ds.period.values, data["period"])


def test_outcome_dataset_without_xarray_names_the_extra(reference, monkeypatch):
    _, outcome = reference
    monkeypatch.setitem(sys.modules, "xarray", None)  # not installed
    with pytest.raises(ModuleNotFoundError) as caught:
        outcome.dataset  # noqa: B018
    assert str(caught.value) == (
        'SweepOutcome.dataset needs xarray: pip install "realworld-billiard[data]"'
    )


def test_two_workers_give_the_same_bytes(reference, tmp_path):
    sweep, outcome = reference
    other = run_sweep(_sweep(), tmp_path / "two", workers=2, progress=_quiet(sweep))
    assert other.result.read_bytes() == outcome.result.read_bytes()


def test_the_workers_have_ended_before_the_result_is_written(reference, tmp_path, monkeypatch):
    """The workers' memory (some 300 MiB a process) is given back before the result file
    and the plots are made, which take the most of the parent's: a 10^6-point map's peak
    stays under 1 GB. The bytes are the one-worker sweep's."""
    import multiprocessing

    from billiard.sweep import execute

    alive: list[int] = []
    write = execute.write_result

    def watched(*args, **kwargs):
        alive.append(len(multiprocessing.active_children()))
        return write(*args, **kwargs)

    monkeypatch.setattr(execute, "write_result", watched)
    sweep, outcome = reference
    other = run_sweep(_sweep(), tmp_path / "two", workers=2, progress=_quiet(sweep))
    assert alive == [0]
    assert other.result.read_bytes() == outcome.result.read_bytes()


def test_interrupted_sweep_resumes_to_the_same_bytes_without_recomputing(reference, tmp_path):
    sweep, outcome = reference
    directory = tmp_path / "cut"
    first: list[int] = []

    def stop(record):
        first.append(record["index"])
        raise StopSweep

    with pytest.raises(SweepInterrupted) as caught:
        run_sweep(_sweep(), directory, workers=1, chunk=2, on_point=stop, progress=_quiet(sweep))
    assert first == [0]
    assert caught.value.done == 2  # the chunk of the point that stopped it is kept whole
    assert not (directory / "sweep.nc").exists()
    rows = np.load(directory / "points.npy")
    assert rows["index"].tolist() == [0, 1]
    with open(directory / "points.npy", "ab") as f:  # a kill in the middle of a chunk
        f.write(rows[:1].tobytes()[:50])
    second: list[int] = []
    resumed = run_sweep(
        None,
        directory,
        resume=True,
        workers=2,
        on_point=lambda r: second.append(r["index"]),
        progress=_quiet(sweep),
    )
    assert sorted(second) == [2, 3]
    assert list(resumed.computed) == second
    assert resumed.result.read_bytes() == outcome.result.read_bytes()
    again = run_sweep(None, directory, resume=True, progress=_quiet(sweep))
    assert list(again.computed) == []
    assert again.result.read_bytes() == outcome.result.read_bytes()


def test_an_edited_point_is_not_published_on_resume(reference, tmp_path, capsys):
    """A value edited in points.npy after the sweep: the resume refuses the folder in one
    line naming the file (exit status 2), and sweep.nc keeps the measured values."""
    sweep, outcome = reference
    directory = shutil.copytree(outcome.directory, tmp_path / "edited")
    path = directory / "points.npy"
    rows = np.load(path)
    dtype = rows.dtype
    where = header_size(dtype) + dtype.fields["height_mean"][1]  # the first row's
    with open(path, "r+b") as f:
        f.seek(where)
        f.write(np.float64(rows["height_mean"][0] + 0.01).tobytes())
    (directory / "sweep.nc").unlink()  # a resume would write it again from points.npy
    with pytest.raises(SweepError, match=f"{path} differs from what checksums.json stores"):
        run_sweep(None, directory, resume=True, progress=_quiet(sweep))
    capsys.readouterr()
    assert main(["sweep", "--resume", str(directory), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith(f"billiard: error: cannot resume: {path} differs") and err.count("\n") == 1
    )
    assert not (directory / "sweep.nc").exists()


def test_a_sweep_without_checksums_is_resumed_with_a_one_line_notice(reference, tmp_path, capsys):
    """A folder written before checksums.json: the resume says in one line that its
    points are not verified, publishes them, and writes the checksums."""
    sweep, outcome = reference
    directory = shutil.copytree(outcome.directory, tmp_path / "older")
    (directory / "checksums.json").unlink()
    capsys.readouterr()
    assert main(["sweep", "--resume", str(directory), "--no-plot"]) == 0
    err = capsys.readouterr().err
    notice = (
        f"billiard: {directory} was written before checksums.json: its {sweep.size} stored "
        f"points are not verified (they are from now on)\n"
    )
    assert notice in err and "Warning" not in err
    assert (directory / "sweep.nc").read_bytes() == outcome.result.read_bytes()
    assert (directory / "checksums.json").is_file()


def test_chunk_size_does_not_change_the_bytes(reference, tmp_path):
    sweep, outcome = reference
    other = run_sweep(_sweep(), tmp_path / "one", workers=1, chunk=4, progress=_quiet(sweep))
    assert other.result.read_bytes() == outcome.result.read_bytes()
    assert np.load(tmp_path / "one" / "points.npy")["index"].tolist() == [0, 1, 2, 3]


def test_dask_local_cluster_gives_the_same_bytes(reference, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    sweep, outcome = reference
    with distributed.LocalCluster(
        n_workers=2, processes=False, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        other = run_sweep(
            _sweep(),
            tmp_path / "dask",
            dask=cluster.scheduler_address,
            chunk=3,
            progress=_quiet(sweep),
        )
    assert "Dask scheduler" in other.where
    # the scheduler names its dashboard (its HTTP server): the link is printed
    assert "billiard sweep: Dask dashboard at http://" in capsys.readouterr().err
    log = (tmp_path / "dask" / "sweep.log").read_text()
    assert "3 per chunk" in log and "chunk 0-2: 3 points (3 ok)" in log
    assert other.result.read_bytes() == outcome.result.read_bytes()


def test_failed_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    scene = with_values(load_scene("parabola-5.4hz"), {"boundary.ceiling": None})
    sweep = Sweep(
        scene, (parse_vary("boundary.escape_height=0.05,1.0"),), impacts=40, transient=100
    )
    outcome = run_sweep(sweep, tmp_path / "esc", workers=1, progress=_quiet(sweep))
    data = read_result(outcome.result)
    assert list(data["status"]) == ["failed", "ok"]
    assert data["reason"][0].startswith("ball escaped above escape_height = 0.05 m")
    assert data["reason"][1] == ""
    assert np.isnan(data["height_mean"][0]) and np.isnan(data["last_height"][0]).all()
    assert data["attractor"][1] == "periodic"
    assert [p.name for p in outcome.plots] == ["bifurcation.png"]


def test_lyapunov_on_request(tmp_path):
    sweep = Sweep(
        load_scene("wedge-6.6hz", overrides=["air.drag=none"]),
        (parse_vary("drive.frequency=6.6"),),
        impacts=150,
        transient=50,
        lyapunov=True,
    )
    outcome = run_sweep(sweep, tmp_path / "lyap", workers=1, progress=_quiet(sweep))
    data = read_result(outcome.result)
    assert np.isfinite(data["lyapunov"][0]) and np.isfinite(data["lyapunov_per_second"][0])
    expected = "chaotic" if data["lyapunov"][0] > 0.01 else "quasi-periodic"
    assert data["attractor"][0] == expected


# --- command line ------------------------------------------------------------------------


def _cli(capsys, *argv):
    code = main(["sweep", *argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_cli_basin_map_with_sweep_file_and_skip_invalid(tmp_path, capsys):
    sweep_file = tmp_path / "basin.toml"
    sweep_file.write_text(
        'scene = "parabola-5.4hz"\nimpacts = 30\ntransient = 60\nkeep = 5\n'
        '[vary]\n"initial.q1" = "0.0:0.04:2"\n"initial.q2" = [0.02, 0.06]\n'
    )
    out = tmp_path / "basin"
    code, stdout, err = _cli(
        capsys, str(sweep_file), "--out", str(out), "--workers", "1", "--skip-invalid"
    )
    assert code == 0, err
    assert "4 points" in stdout and "1 invalid" in stdout
    data = read_result(out / "sweep.nc")
    # q1 = 0.04 m, q2 = 0.02 m is inside the parabola's wall (f(0.04) = 0.048 m)
    assert data["status"][1, 0] == "invalid" and "into the wall" in data["reason"][1, 0]
    assert {p.name for p in out.glob("*.png")} == {"heatmaps.png", "basins.png"}
    # the folder's sweep.toml is a sweep file that runs the same sweep again
    code, _, err = _cli(capsys, str(out / "sweep.toml"), "--out", str(tmp_path / "again"),
                        "--workers", "1", "--skip-invalid")  # fmt: skip
    assert code == 0, err
    assert (tmp_path / "again" / "sweep.nc").read_bytes() == (out / "sweep.nc").read_bytes()


def test_starts_outside_the_container_are_recorded_invalid(tmp_path, capsys):
    """A basin map's rectangle reaches outside the container: such starts are blank
    points with the engine's reason, without --skip-invalid; the others are measured."""
    out = tmp_path / "out"
    code, stdout, err = _cli(
        capsys, "parabola-5.4hz", "--vary", "initial.q2=0.03,0.004", "--set", "initial.q1=0",
        "--impacts", "20", "--transient", "20", "--workers", "1", "--no-plot", "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    assert "1 invalid" in stdout
    data = read_result(out / "sweep.nc")
    assert list(data["status"]) == ["ok", "invalid"]
    assert (
        "q2 = 0.004 m puts the ball" in data["reason"][1] and "into the wall" in data["reason"][1]
    )


BAD_INPUT = {
    "misspelt key": (["--vary", "drive.frequncy=4:7:3"], "did you mean 'drive.frequency'?"),
    "misspelt section": (["--vary", "drvie.frequency=4:7:3"], "unknown scene section 'drvie'"),
    "empty values": (["--vary", "drive.frequency="], "drive.frequency=: no values"),
    "N < 1": (["--vary", "drive.frequency=4:7:0"], "N = 0 points; it must be >= 1"),
    "empty range": (["--vary", "drive.frequency=4:4:3"], "empty range (START = STOP)"),
    "not a number": (["--vary", "drive.frequency=4:x:3"], "START and STOP must be numbers"),
    "repeated value": (["--vary", "drive.frequency=4,5,4"], "the value 4 is given twice"),
    "no impacts": (
        ["--vary", "drive.frequency=4:7:3", "--impacts", "0"],
        "'impacts' must be an integer >= 1",
    ),
    "invalid scene": (
        ["--vary", "drive.amplitude=0.01:-0.01:3"],
        "point 2 (drive.amplitude = -0.01): scene key 'drive.amplitude' = -0.01 m is out of range",
    ),
    "no distributed": (
        ["--vary", "drive.frequency=5", "--dask", "tcp://127.0.0.1:1"],
        'pip install "realworld-billiard[dask]"',
    ),
    "nothing to vary": ([], "nothing to vary"),
}


@pytest.mark.parametrize("case", BAD_INPUT)
def test_cli_bad_input_is_one_line_and_writes_nothing(case, tmp_path, capsys, monkeypatch):
    argv, message = BAD_INPUT[case]
    if "--dask" in argv:
        monkeypatch.setitem(sys.modules, "distributed", None)  # not installed
    out = tmp_path / "out"
    code, stdout, err = _cli(capsys, "parabola-5.4hz", *argv, "--out", str(out))
    assert code == 2
    assert err.startswith("billiard: error: ") and err.count("\n") == 1, err
    assert message in err
    assert not out.exists()


def test_descending_range_runs_downwards():
    axis = parse_vary("drive.frequency=7:4:4")
    assert axis.values == (7.0, 6.0, 5.0, 4.0)


def test_progress_lines_when_not_a_terminal():
    stream = io.StringIO()
    progress = SweepProgress(10, done=4, stream=stream, interval=0.0)
    progress.point({"total_impacts": 500})
    progress.tick()
    lines = stream.getvalue().splitlines()
    assert lines and lines[-1].startswith("billiard sweep: 5/10 points")
    assert "impacts/s" in lines[-1] and "ETA" in lines[-1]


# --- chunks, workers and checks --------------------------------------------------------


def test_chunks_cover_the_points_left_in_index_order():
    from billiard.sweep.execute import _chunks, chunk_size

    assert chunk_size(12, 1) == 3 and chunk_size(10**6, 16) == 4096 and chunk_size(3, 8) == 1
    sweep = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=4:7:10"),))
    done = bytearray(10)
    for i in (0, 3, 4, 9):
        done[i] = 1
    tasks = list(_chunks(sweep, done, 3))
    assert [t.points().tolist() for t in tasks] == [[1, 2, 5], [6, 7, 8]]
    assert (tasks[0].start, tasks[0].stop) == (1, 6)
    assert tasks[1].indices is None  # a whole range: no indices sent


def test_window_follows_the_workers_present_and_a_lost_worker_is_logged(monkeypatch, tmp_path):
    import threading
    import time
    from concurrent.futures import ThreadPoolExecutor

    from billiard.sweep import execute
    from billiard.sweep.columns import ChunkResult, empty_columns
    from billiard.sweep.store import ChunkStore

    sweep = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=4:7:40"),), keep=2)
    lock = threading.Lock()
    running, most = [0], []

    def measure(task):
        with lock:
            running[0] += 1
            most.append((looks[0], running[0]))
        time.sleep(0.02)
        columns = empty_columns(len(task), sweep.keep)
        columns["index"][:] = task.points()
        with lock:
            running[0] -= 1
        return ChunkResult(columns)

    looks = [0]

    def present():  # one thread at first; a second worker joins, then the first leaves
        looks[0] += 1
        if looks[0] < 4:
            return {"tcp://a:1": 1}
        if looks[0] < 12:
            return {"tcp://a:1": 1, "tcp://b:2": 3}
        return {"tcp://b:2": 3}

    monkeypatch.setattr(execute, "measure_chunk", measure)
    monkeypatch.setattr(execute, "WORKERS_INTERVAL", 0.0)
    with ThreadPoolExecutor(8) as pool, ChunkStore(tmp_path, sweep.size, sweep.keep) as store:
        workers = execute.Workers(pool, "test", present)
        tasks = execute._chunks(sweep, store.done, 1)
        execute._drive(workers, tasks, store, _quiet(sweep), None, execute.array.array("q"), sweep)
        assert store.count == 40
    # two chunks in flight for one thread; once the second worker joins, up to eight
    assert max(n for look, n in most if look < 4) <= 2
    assert max(n for _, n in most) > 2
    log = (tmp_path / "sweep.log").read_text()
    assert "worker tcp://b:2 joined (3 threads)" in log
    assert "worker tcp://a:1 left; its chunks are recomputed" in log


def test_basin_map_starts_are_checked_as_the_engine_checks_them():
    from billiard.run.simulate import Simulation
    from billiard.sweep.execute import prepare

    axes = (parse_vary("initial.q1=-0.06:0.06:7"), parse_vary("initial.q2=0.005:0.05:4"))
    sweep = Sweep(load_scene("parabola-5.4hz"), axes, skip_invalid=True)
    invalid = prepare(sweep, skip_invalid=True)
    expected = {}
    for index in range(sweep.size):
        try:
            Simulation(with_values(sweep.scene, sweep.point_values(index)))
        except ValueError as exc:
            expected[index] = " ".join(str(exc).split())
    # the same starts, and the engine's words without how deep (a root search per start)
    assert invalid.keys() == expected.keys()
    for index, message in expected.items():
        assert invalid[index] == re.sub(r"puts the ball \S+ m into", "puts the ball into", message)
    assert 0 < len(invalid) < sweep.size


def test_chunks_are_sized_again_as_workers_come():
    from billiard.sweep.execute import _chunks, chunk_size

    sweep = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=4:7:200"),))
    threads = [1]
    asked: list[int] = []

    def size(left: int) -> int:
        asked.append(left)
        return chunk_size(left, threads[0])

    tasks = _chunks(sweep, bytearray(200), size)
    first = next(tasks)
    threads[0] = 10  # nine more threads join while the first chunk runs
    rest = list(tasks)
    sizes = [len(first), *(len(t) for t in rest)]
    assert sizes[0] == 50 and max(sizes[1:]) == 4  # 150 points left for 10 threads, 4 each
    assert sum(sizes) == 200 and asked[:2] == [200, 150]
    covered = np.concatenate([first.points(), *(t.points() for t in rest)])
    assert covered.tolist() == list(range(200))


def test_a_worker_missing_from_one_answer_is_not_said_to_have_left(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    from billiard.sweep import execute
    from billiard.sweep.store import ChunkStore

    sweep = Sweep(load_scene("parabola-5.4hz"), (parse_vary("drive.frequency=4:7:4"),), keep=2)
    answers = iter([{"a": 1}, {"a": 1, "b": 2}, {"b": 2}, {"a": 1, "b": 2}, {"b": 2}, {"b": 2}])
    with ThreadPoolExecutor(1) as pool, ChunkStore(tmp_path, sweep.size, sweep.keep) as store:
        workers = execute.Workers(pool, "test", lambda: next(answers))
        present = workers.present()
        seen = []
        for _ in range(5):
            present = execute._look_at_workers(workers, present, store)
            seen.append(sorted(present))
    log = (tmp_path / "sweep.log").read_text()
    assert log.count("worker a left") == 1 and log.count("worker b joined") == 1
    assert "worker a joined" not in log  # the answer that omitted it once was not believed
    assert seen == [["a", "b"], ["a", "b"], ["a", "b"], ["a", "b"], ["b"]]


def test_a_cluster_that_grows_and_loses_a_worker_gives_the_same_bytes(tmp_path, monkeypatch):
    """Started on one worker; two more join after the first chunk and one of the first
    two is closed mid-way: the late workers take chunks, and the result is the local
    run's, byte for byte."""
    distributed = pytest.importorskip("distributed")
    from billiard.sweep import execute

    monkeypatch.setattr(execute, "WORKERS_INTERVAL", 0.0)  # look after every chunk
    axes = (parse_vary("drive.amplitude=0.015:0.03:4"), parse_vary("drive.frequency=5.0:5.6:6"))
    sweep = Sweep(load_scene("parabola-5.4hz"), axes, impacts=40, transient=60, keep=4)
    local = run_sweep(sweep, tmp_path / "local", workers=1, progress=_quiet(sweep), plots=False)
    with distributed.LocalCluster(
        n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        events: list[str] = []

        def on_point(record):
            if not events:
                events.append("grow")
                cluster.scale(3)
                cluster.wait_for_workers(3, timeout=30)
            elif len(events) == 1 and record["index"] >= 12:
                events.append("lose")
                name = sorted(cluster.workers)[0]
                cluster.sync(cluster.workers[name].close)

        grown = run_sweep(
            sweep,
            tmp_path / "dask",
            dask=cluster.scheduler_address,
            on_point=on_point,
            progress=_quiet(sweep),
            plots=False,
        )
    assert events == ["grow", "lose"]
    log = (tmp_path / "dask" / "sweep.log").read_text()
    assert log.count(" joined (1 threads)") == 2, log
    assert "resized as workers come and go" in log
    # in the order handed out (chunks are made in index order), not as they finished
    chunks = sorted((int(a), int(n)) for a, n in re.findall(r"chunk (\d+)-\d+: (\d+) points", log))
    sizes = [n for _, n in chunks]
    # two chunks handed to the one worker (24 and 18 points left: a quarter each), then
    # 13 left among three workers: 4 chunks each, of 2 points (not 13 / 4 = 4)
    assert sizes[:3] == [6, 5, 2], sizes
    assert "left; its chunks are recomputed" in log
    assert grown.result.read_bytes() == local.result.read_bytes()
