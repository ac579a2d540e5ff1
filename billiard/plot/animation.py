"""An animated GIF of the ball inside the moving boundary."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib import rc_context
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.patches import Circle
from PIL import Image

from billiard.plot.common import (
    DRAW_RC,
    MM,
    Columns,
    Window,
    cannot_write,
    column,
    new_figure,
)
from billiard.plot.contacts import MODE_LABELS, MODE_STYLES, PhasePath, Side, joined, phase_path
from billiard.plot.density import density_image, use_density
from billiard.plot.flights import arcs, positions_at
from billiard.plot.outline import drive_offset
from billiard.plot.trajectory import boundary_positions, path_samples, view, window_rows
from billiard.scene.scene import Scene

__all__ = ["animate"]


def _phase_centres(
    path: PhasePath, frame_times: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """The centre (m) at each frame time (s) on the piece of ``path`` holding it, what the
    ball is doing then (for the clock) and the mode (``flight`` or a contact mode).

    A frame in no piece (the run's start before its first recorded event, or a gap the
    run files do not describe) keeps the ball where the last piece before it ended (or
    the first after it starts)."""
    x = np.full(frame_times.shape, np.nan)
    y = np.full(frame_times.shape, np.nan)
    what = [""] * frame_times.size
    modes = ["flight"] * frame_times.size
    pieces = path.pieces
    for piece in pieces:
        inside = np.flatnonzero((frame_times >= piece.t[0]) & (frame_times <= piece.t[-1]))
        if inside.size == 0:
            continue
        x[inside], y[inside] = piece.positions(frame_times[inside])
        if piece.kind == "flight":
            text = piece.source if piece.source.startswith("impact") else "flight"
            text = text if text == "flight" else f"flight after {text}"
        else:
            text = f"{MODE_LABELS[piece.kind]}, wall {piece.wall}"
        for i in inside:
            what[i], modes[i] = text, piece.kind
    ends = sorted((p.t[-1], p.x[-1], p.y[-1]) for p in pieces)
    firsts = sorted((p.t[0], p.x[0], p.y[0]) for p in pieces)
    for i in np.flatnonzero(np.isnan(x)):
        before = [e for e in ends if e[0] <= frame_times[i]]
        _, x[i], y[i] = before[-1] if before else firsts[0]
    return x, y, what, modes


def animate(
    columns: Columns,
    scene: Scene,
    path: str | os.PathLike[str],
    window: Window | None = None,
    fps: int = 30,
    *,
    max_frames: int = 150,
    dpi: int = 80,
    contacts: Side | None = None,
    samples: Side | None = None,
) -> Path:
    """Write an animated GIF of the ball inside the moving boundary.

    The still parts are drawn once; each frame redraws only the moving artists, and the
    frames are written with Pillow in one shared 64-colour palette.

    The ball is drawn as a circle of its true radius. Frames are spaced uniformly in time
    from the first to the last impact of the window; between impacts the centre follows
    the scene's flight (with air drag if the scene has it, see
    :mod:`billiard.plot.flights`) from the previous impact's position and velocity, and
    the boundary is drawn shifted by the drive D(t) (see :func:`drive_offset`). The faint
    line is the whole reconstructed path in the window. The GIF plays at ``fps`` frames
    per second, so it is in slow or fast motion; the speed relative to real time is
    written in the frame.

    With ``contacts`` (a run of ``contact.model = "phases"``) the frames span the window's
    flights and contact phases (see :mod:`billiard.plot.contacts`): the ball flies only
    between an impact or a phase's end and the next impact or phase, and rolls, slides
    or is held along the wall in between (from ``samples`` when given, else rebuilt); the
    ball and the faint path take the colour of the contact mode there, and the clock
    names the motion.

    Args:
        columns: a run's columns.
        scene: the run's scene.
        path: the GIF to write.
        window: impact numbers ``(n0, n1)``, n0 <= n < n1 (default: the last few drive
            periods, see :func:`billiard.plot.default_window`).
        fps: playback frames per second.
        max_frames: number of frames (at most; fewer if the window has one impact).
        dpi: pixels per inch of the frame, 5 inches wide (400 px at 80 dpi), as high
            as the view needs.
        contacts: the run's contact phases (the columns of contacts.csv), or None.
        samples: the run's samples (the columns of trajectory.csv), or None.

    Returns:
        The path written.

    Raises:
        RunDataError: the window holds no impacts, or the GIF cannot be written.
    """
    rows = window_rows(columns, scene, window)
    r = scene.ball.radius
    t = column(columns, "t")
    phases = None if contacts is None else phase_path(columns, rows, scene, contacts, samples)
    if phases is None:
        t0, t1 = float(t[rows[0]]), float(t[rows[-1]])
    else:
        t0, t1 = phases.t_lo, phases.t_hi
    count = max_frames if t1 > t0 else 1
    frame_times = np.linspace(t0, t1, count)
    q1 = column(columns, "q1")[rows]
    q2 = column(columns, "q2")[rows]
    dense = phases is None and use_density(rows.size)
    if dense:  # thousands of arcs: the path's density, drawn as an image
        arc_x, arc_y, _ = path_samples(columns, rows, scene)
        ball_x, ball_y, starts = positions_at(columns, rows, frame_times, scene)
        texts = [f"impact {int(columns['n'][row])}" for row in starts]
        colors = ["tab:blue"] * count
        all_x, all_y = np.concatenate([q1, arc_x]), np.concatenate([q2, arc_y])
    elif phases is None:
        arc_x, arc_y = arcs(columns, rows, scene)
        ball_x, ball_y, starts = positions_at(columns, rows, frame_times, scene)
        texts = [f"impact {int(columns['n'][row])}" for row in starts]
        colors = ["tab:blue"] * count
        all_x, all_y = np.concatenate([q1, arc_x]), np.concatenate([q2, arc_y])
    else:
        arc_x, arc_y = joined(phases.flights)
        ball_x, ball_y, texts, modes = _phase_centres(phases, frame_times)
        colors = [
            "tab:blue" if mode == "flight" else str(MODE_STYLES[mode]["color"]) for mode in modes
        ]
        stretch_x, stretch_y = phases.points()
        all_x = np.concatenate([q1, arc_x, stretch_x])
        all_y = np.concatenate([q2, arc_y, stretch_y])
    x_lim, y_lim, show_lid = view(scene, all_x, all_y)
    grid, height = boundary_positions(scene, x_lim)
    direction = scene.drive.direction

    aspect = (y_lim[1] - y_lim[0]) / (x_lim[1] - x_lim[0])
    fig = new_figure((5.0, float(np.clip(4.2 * aspect + 0.9, 2.5, 6.5))), dpi=dpi)
    ax = fig.add_subplot()
    if dense:
        density_image(
            ax,
            arc_x * MM,
            arc_y * MM,
            (x_lim[0] * MM, x_lim[1] * MM),
            (y_lim[0] * MM, y_lim[1] * MM),
            cmap="Greys",
            colorbar=False,
        ).set_zorder(0)
    else:
        ax.plot(arc_x * MM, arc_y * MM, color="0.8", linewidth=0.7, zorder=0)
    if phases is not None:
        for piece in phases.stretches:
            ax.plot(
                piece.x * MM,
                piece.y * MM,
                color=MODE_STYLES[piece.kind]["color"],
                alpha=0.45,
                linewidth=1.4,
                zorder=0.5,
            )
    (boundary,) = ax.plot(grid * MM, height * MM, color="black", linewidth=1.5)
    ceiling = scene.boundary.ceiling
    lid = None
    if ceiling is not None and show_lid:
        (lid,) = ax.plot(np.asarray(x_lim) * MM, [ceiling * MM] * 2, color="0.3", linewidth=1.2)
    ball = Circle(
        (float(q1[0]) * MM, float(q2[0]) * MM),
        r * MM,
        facecolor="tab:blue",
        edgecolor="navy",
        linewidth=0.6,
        zorder=3,
    )
    ax.add_patch(ball)
    ax.set_xlim(x_lim[0] * MM, x_lim[1] * MM)
    ax.set_ylim(y_lim[0] * MM, y_lim[1] * MM)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("$q_1$ (mm)")
    ax.set_ylabel("$q_2$ (mm)")
    duration = (count / fps) if count > 1 else 1.0
    speed = (t1 - t0) / duration if t1 > t0 else 1.0
    fig.suptitle(f"{scene.name}: {speed:.2g}x real time", fontsize=10)
    clock = ax.text(
        0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9, family="monospace"
    )

    moving = [boundary, ball, clock] + (
        [lid] if lid is not None and direction == "vertical" else []
    )
    for artist in moving:
        artist.set_animated(True)
    canvas = fig.canvas
    assert isinstance(canvas, FigureCanvasAgg)
    with rc_context(DRAW_RC):
        canvas.draw()
    fig.set_layout_engine("none")  # freeze the layout: the frames only move artists
    background = canvas.copy_from_bbox(fig.bbox)
    frames: list[Image.Image] = []
    for tf, x, y, text, color in zip(frame_times, ball_x, ball_y, texts, colors, strict=True):
        ball.center = (float(x) * MM, float(y) * MM)
        ball.set_facecolor(color)
        offset = float(drive_offset(scene, tf))
        if direction == "vertical":
            boundary.set_data(grid * MM, (height + offset) * MM)
            if lid is not None and ceiling is not None:
                lid.set_ydata([(ceiling + offset) * MM] * 2)
        else:
            boundary.set_data((grid + offset) * MM, height * MM)
        clock.set_text(f"t = {tf:8.3f} s\n{text}")
        canvas.restore_region(background)
        for artist in moving:
            ax.draw_artist(artist)
        frames.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
    fig.clear()
    path = Path(path)
    try:
        _save_gif(frames, path, fps)
    except OSError as exc:
        raise cannot_write(path, exc) from None
    return path


def _save_gif(frames: Sequence[Image.Image], path: Path, fps: int) -> None:
    """Save RGB frames as a looping GIF sharing one palette (small and fast to write;
    Pillow stores only the changed part of each frame)."""
    palette = frames[0].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    indexed = [palette] + [
        f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames[1:]
    ]
    indexed[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=indexed[1:],
        duration=max(1, round(1000 / fps)),
        loop=0,
    )
