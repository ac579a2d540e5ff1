"""Every figure of one run directory: :func:`plot_run` (``billiard plot DIR``)."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from billiard.plot.animation import animate
from billiard.plot.common import (
    SINGLE_SIZE,
    Columns,
    RunDataError,
    Window,
    new_figure,
    output_directory,
    read_collisions,
    save,
    uniform_legend_markers,
)
from billiard.plot.inputs import checked_interval
from billiard.plot.maps import return_map, time_map
from billiard.plot.phase import PHASE_CAPTION, phase_plot
from billiard.plot.titles import scene_title
from billiard.plot.trajectory import trajectory, window_rows
from billiard.run.verify import verify_run
from billiard.runfile.figure_files import (
    DEFAULT_DPI,
    DEFAULT_FORMAT,
    check_dpi,
    figure_names,
)
from billiard.runfile.folder import FIGURE_NAMES, data_file, side_file
from billiard.scene.scene import Scene, SceneError, scene_from_toml
from billiard.scene.userfile import MAX_SCENE_BYTES, FileRefused, read_limited

__all__ = ["FIGURE_NAMES", "load_run", "load_sides", "plot_run", "read_scene"]


def read_scene(path: str | os.PathLike[str]) -> Scene:
    """Read and validate a run's ``scene.toml`` (see :func:`billiard.scene.scene.scene_from_toml`).

    Raises:
        RunDataError: the file is missing or unreadable (one line, naming it).
        SceneError: the file is not valid TOML or not a valid scene (one line, naming it).
    """
    try:
        text = read_limited(path, MAX_SCENE_BYTES).decode("utf-8")
    except FileRefused as exc:
        raise RunDataError(f"{path}: {exc.reason}") from None
    except FileNotFoundError:
        raise RunDataError(
            f"{path}: file not found (the run's scene is needed "
            "for the ball's mass, the boundary and the titles)"
        ) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RunDataError(f"{path}: cannot read: {' '.join(str(exc).split())}") from None
    try:
        return scene_from_toml(text, name=Path(path).parent.name or "run", source=str(path))
    except SceneError as exc:
        message = " ".join(str(exc).split())
        raise SceneError(message if str(path) in message else f"{path}: {message}") from None


def load_run(run_dir: str | os.PathLike[str]) -> tuple[dict[str, np.ndarray], Scene]:
    """Columns of ``run_dir/collisions.csv`` (or ``collisions.npy``) and the scene of
    ``run_dir/scene.toml``.

    Raises:
        RunDataError: a file is missing or malformed, or the CSV has no impacts, or
            differs from what the run's checkpoint recorded
            (:class:`~billiard.run.verify.DamagedRunError`).
        SceneError: the scene file is not a valid scene.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise RunDataError(f"{run_dir}: not a directory")
    # the files are the run's, as its checkpoint recorded them
    verify_run(run_dir, absent_ok=True)
    csv_path = data_file(run_dir)
    columns = read_collisions(csv_path)
    if columns["t"].size == 0:
        raise RunDataError(f"{csv_path}: no impacts to plot")
    return columns, read_scene(run_dir / "scene.toml")


def load_sides(
    run_dir: str | os.PathLike[str],
) -> tuple[dict[str, np.ndarray] | None, dict[str, np.ndarray] | None]:
    """The columns of ``run_dir/contacts.csv`` and ``run_dir/trajectory.csv`` (a run of
    ``contact.model = "phases"``, and one with ``--sample``; ``.npy`` for a binary run),
    each None when absent.

    Raises:
        RunDataError: a file is present but cannot be read (one line, naming it).
    """
    from billiard.runfile.tables import read_contacts, read_trajectory

    out: list[dict[str, np.ndarray] | None] = []
    for name, read in (("contacts", read_contacts), ("trajectory", read_trajectory)):
        path = side_file(run_dir, name)
        out.append(None if path is None else read(path))
    return out[0], out[1]


def _legend_outside(fig: Figure, ax: Axes, caption: str | None = None) -> None:
    """Move the axes' legend below the axes, so that it hides no data; ``caption`` is
    written above the legend's entries."""
    legend = ax.get_legend()
    if legend is None:
        return
    handles, labels = ax.get_legend_handles_labels()
    legend.remove()
    uniform_legend_markers(
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncol=2,
            fontsize=8,
            frameon=False,
            title=caption,
            title_fontsize=7,
        )
    )


def _single(
    draw: Callable[[Axes], object],
    title: str | None,
    path: Path,
    *,
    dpi: int,
    fit_height: bool = False,
    caption: str | None = None,
) -> Path:
    """One-panel figure, 6 inches wide, with the title on top (none when ``title`` is
    None) and the legend below; saved at ``dpi`` pixels per inch (PNG).

    With ``fit_height``, the height follows the shape of the (equal-aspect) view;
    ``caption`` is small text under the axes, above the legend. A trajectory's contact
    stretches add legend entries, and the figure grows by their height.
    """
    fig = new_figure()
    ax = fig.add_subplot()
    drawn = draw(ax)
    if fit_height:
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        aspect = abs(y1 - y0) / max(abs(x1 - x0), 1e-300)
        height = 4.6 * aspect + 2.0
        if isinstance(drawn, dict) and "stretches" in drawn:
            height += 0.2 * (len(drawn["stretches"]) + 1)
        fig.set_size_inches(SINGLE_SIZE[0], float(np.clip(height, 3.6, 8.0)))
    if title is not None:
        fig.suptitle(title, fontsize=9)
    _legend_outside(fig, ax, caption)
    return save(fig, path, dpi=dpi)


def _figures(
    columns: Columns,
    scene: Scene,
    out: Path,
    interval: float | None,
    window: tuple[int, int],
    sides: tuple[Columns | None, Columns | None] = (None, None),
    *,
    names: Sequence[str],
    dpi: int,
    title: bool,
    density: bool | None,
) -> list[Path]:
    heading = scene_title(scene, int(columns["t"].size)) if title else None
    return [
        _single(
            lambda ax: return_map(columns, ax, frame_interval=interval, density=density),
            heading,
            out / names[0],
            dpi=dpi,
        ),
        _single(
            lambda ax: time_map(columns, ax, frame_interval=interval, density=density),
            heading,
            out / names[1],
            dpi=dpi,
        ),
        _single(
            lambda ax: phase_plot(columns, scene, ax, frame_interval=interval, density=density),
            heading,
            out / names[2],
            dpi=dpi,
            caption=PHASE_CAPTION,
        ),
        _single(
            lambda ax: trajectory(
                columns,
                scene,
                ax,
                window,
                frame_interval=interval,
                contacts=sides[0],
                samples=sides[1],
                title=title,
            ),
            heading,
            out / names[3],
            dpi=dpi,
            fit_height=True,
        ),
    ]


def plot_run(
    run_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    frame_interval: float | None = None,
    window: Window | None = None,
    gif: bool = True,
    format: str = DEFAULT_FORMAT,
    dpi: int = DEFAULT_DPI,
    title: bool = True,
    density: bool | None = None,
) -> list[Path]:
    """Draw every figure of a run.

    Reads ``run_dir/collisions.csv`` and ``run_dir/scene.toml`` and writes into
    ``out_dir`` (default ``run_dir``, created if missing): ``return_map``, ``time_map``,
    ``phase`` and ``trajectory`` in ``format`` (``.png``, ``.svg`` or ``.pdf``) and, unless
    ``gif`` is False, ``animation.gif``. Each figure is 6 inches wide (a PNG 1200 px at the
    default 200 dpi), titled with the scene's name and key parameters unless ``title`` is
    False. A run of ``contact.model = "phases"`` (``contacts.csv`` present) gets its
    contact phases drawn in the trajectory and the animation as stretches along the wall,
    from ``trajectory.csv``'s samples when present (see :mod:`billiard.plot.contacts`).

    The maps and the phase plot draw each impact as a dot up to
    :data:`billiard.plot.density.DENSITY_THRESHOLD` impacts, and above it a density image
    of the impacts per bin with a colour bar (``density`` True or False forces one or the
    other).

    With ``frame_interval`` (s), the maps also show, as hollow rings in a second colour,
    the data a camera with that frame interval would have recorded (the experiment missed
    impacts in rapid succession; see :func:`billiard.analysis.camera.camera_filter`), with the
    frame interval and impact counts in the legend, and the trajectory rings the impacts
    the camera would have seen. The files keep the same names.

    Args:
        run_dir: a directory written by ``billiard run``.
        out_dir: where to write the figures.
        frame_interval: the camera's frame interval (s), or None for the model data only.
        window: impact numbers ``(n0, n1)``, n0 <= n < n1, for the trajectory and the
            animation (default: :func:`billiard.plot.default_window`, the last few drive
            periods); either may be None for an open end.
        gif: write the animation (the slowest figure, about a second; at most 150 frames
            whatever the window).
        format: the still figures' file format: ``"png"``, ``"svg"`` or ``"pdf"`` (see
            :data:`billiard.runfile.figure_files.FIGURE_FORMATS`).
        dpi: pixels per inch of a PNG, a whole number from 20 to 1200; SVG and PDF are
            vector files and ignore it. The animation keeps its own size (400 px wide).
        title: write the title above each still figure (and the window's impacts and
            times above the trajectory); False leaves them to a caption.
        density: True or False to draw the maps' and phase plot's points as a density
            image or as dots; None (default) chooses by their number.

    Returns:
        The paths written, in the order of :data:`FIGURE_NAMES`
        (:func:`billiard.runfile.figure_files.figure_names` gives them for ``format``).

    Raises:
        RunDataError: (a ValueError) a missing, empty or malformed file, a window with no
            impacts, a bad frame interval, format or dpi, or an output directory that
            cannot be written; the message is one line.
        SceneError: (a ValueError) ``scene.toml`` is not a valid scene; one line.
    """
    names = figure_names(format)
    dpi = check_dpi(dpi)
    interval = checked_interval(frame_interval)
    columns, scene = load_run(run_dir)
    rows = window_rows(columns, scene, window)  # check the window before drawing
    chosen = (int(columns["n"][rows[0]]), int(columns["n"][rows[-1]]) + 1)
    contacts, samples = load_sides(run_dir)
    out = output_directory(out_dir if out_dir is not None else run_dir)
    written = _figures(
        columns,
        scene,
        out,
        interval,
        chosen,
        (contacts, samples),
        names=names,
        dpi=dpi,
        title=title,
        density=density,
    )
    if gif:
        written.append(
            animate(
                columns,
                scene,
                out / names[4],
                window=chosen,
                contacts=contacts,
                samples=samples,
            )
        )
    return written
