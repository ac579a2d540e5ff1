"""The interactive view of a run: one self-contained HTML page (``billiard view DIR``).

The page (the template ``view_template.html`` beside this module, with the run's data
inlined as JSON) needs no server and no network: it opens from disk, and its content
security policy forbids every load from outside the page. The user scrubs through the
run with a slider or the keyboard; four panels are linked to the selection:

* the container: the boundary drawn where the drive has moved it at the selected time
  (the curve's samples y = f(x) in its own frame are computed here; the page shifts them
  by the drive's displacement D(t) = A sin(omega t + phase)), its extreme positions +-A,
  the lid, the ball (a circle of the ball's radius) and its recent path, with contact
  phases drawn in the styles of the trajectory figure;
* the return map q2,n+1 against q2,n, the selected pair ringed;
* the phase plot (the paper's normalized height against normalized tangential velocity,
  :func:`billiard.plot.phase.phase_coordinates`), the selected impact ringed;
* the time series of the ball's height around the selection, the impacts marked.

Between impacts the page places the ball on the flight q(tau) = q0 + v0 tau + a tau^2/2
from the impact's recorded position q0 and velocity v0, with the constant acceleration a
that ends the flight at the next impact's recorded position: the exact parabola of a run
without air drag; with drag it differs from the integrated flight by micrometres (see
docs/design.md, "The interactive view"). At an impact the ball is at the run's recorded
position exactly. A run with contact phases ships its path instead: each flight as three
exact points (start, middle, end; the page draws the parabola through them) and each
contact stretch as its points (:func:`billiard.plot.contacts.phase_path`), at most
:data:`MAX_STRETCH_POINTS` of them each.

A page holds at most :data:`MAX_IMPACTS` consecutive impacts: a longer run (or window)
is cut to its last ones, and the page says so.
"""

from __future__ import annotations

import html
import json
import math
import os
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from billiard.plot.common import Columns, RunDataError, Window, column, lid_mask
from billiard.plot.contacts import MODE_LABELS, Side, phase_path
from billiard.plot.outline import boundary_outline
from billiard.plot.phase import phase_coordinates
from billiard.plot.titles import scene_title
from billiard.plot.trajectory import view as view_limits
from billiard.plot.trajectory import window_rows
from billiard.runfile.folder import VIEW_NAME
from billiard.scene.scene import Scene

__all__ = [
    "MAX_IMPACTS",
    "MAX_STRETCH_POINTS",
    "VIEW_NAME",
    "View",
    "view",
    "view_data",
    "view_page",
    "write_view",
]

#: The most impacts one page holds (consecutive ones; a longer run keeps its last ones).
#: A page of this many impacts is about 2.7 MB (140 bytes per impact).
MAX_IMPACTS = 20_000
#: The most points a contact stretch is drawn with (its points thinned evenly, ends kept).
MAX_STRETCH_POINTS = 120
#: Points of the boundary's outline shipped to the page.
OUTLINE_POINTS = 801
#: Significant digits of what the page only draws (outline, stretches, phase plot);
#: the impacts' times, positions and velocities are shipped exactly.
DRAWN_DIGITS = 8
#: Regime codes of the ``regime`` array on the page.
REGIMES = ("stick", "slip", "elastic")
#: The marker the template's data script holds, replaced by the run's JSON.
_DATA_MARK = "/*BILLIARD_VIEW_DATA*/null"
_TEMPLATE = "view_template.html"


def _exact(values: np.ndarray) -> list[float | None]:
    """Floats as JSON numbers that read back to the same doubles (NaN as null)."""
    return [v if math.isfinite(v) else None for v in np.asarray(values, dtype=float).tolist()]


def _drawn(values: np.ndarray) -> list[float | None]:
    """Floats for drawing only: :data:`DRAWN_DIGITS` significant digits (NaN as null)."""
    return [
        float(f"{v:.{DRAWN_DIGITS}g}") if math.isfinite(v) else None
        for v in np.asarray(values, dtype=float).tolist()
    ]


def _thin(count: int, limit: int) -> np.ndarray:
    """Indices of at most ``limit`` of ``count`` points, evenly spread, both ends kept."""
    if count <= limit:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, limit)).astype(int))


def _plain_title(scene: Scene, impacts: int) -> str:
    title = scene_title(scene, impacts)
    return title.replace("$\\mu_s$", "\u03bcs").replace("$\\mu_k$", "\u03bck")


def _pieces(
    columns: Columns, rows: np.ndarray, scene: Scene, contacts: Side, samples: Side | None
) -> list[dict[str, Any]]:
    """The path of a run with contact phases over ``rows``: flights as three exact points
    (start, middle, end), stretches as at most :data:`MAX_STRETCH_POINTS` points."""
    path = phase_path(columns, rows, scene, contacts, samples)
    out = []
    for piece in path.pieces:
        if piece.kind == "flight":
            keep = np.unique([0, piece.t.size // 2, piece.t.size - 1])
        else:
            keep = _thin(piece.t.size, MAX_STRETCH_POINTS)
        out.append(
            {
                "kind": piece.kind,
                "wall": piece.wall,
                "t": _exact(piece.t[keep]),
                "x": _drawn(piece.x[keep]),
                "y": _drawn(piece.y[keep]),
            }
        )
    return out


def view_data(
    columns: Columns,
    scene: Scene,
    contacts: Side | None = None,
    samples: Side | None = None,
    *,
    window: Window | None = None,
) -> dict[str, Any]:
    """The data one page ships: the run's impacts (at most :data:`MAX_IMPACTS`), the
    boundary's outline, the view's limits and, for a run with contact phases, its path.

    Args:
        columns: the run's impacts (the columns of collisions.csv).
        scene: the run's scene.
        contacts: the run's contact phases (contacts.csv), or None.
        samples: the run's samples (trajectory.csv), or None.
        window: ``(n0, n1)``: impact numbers n0 <= n < n1 (either may be None for an open
            end); default the whole run. Either way at most the last :data:`MAX_IMPACTS`.

    Returns:
        A JSON-ready dict; lengths in m, times in s, velocities in m/s (the page draws mm).

    Raises:
        RunDataError: a column is missing, or the window holds no impacts.
    """
    n = column(columns, "n")
    if n.size == 0:
        raise RunDataError("the run has no impacts to view")
    rows = window_rows(columns, scene, window if window is not None else (None, None))
    asked = rows.size
    rows = rows[-MAX_IMPACTS:]
    part = {name: np.asarray(values)[rows] for name, values in columns.items()}
    q1, q2 = column(part, "q1"), column(part, "q2")
    try:
        phase_x, phase_y = phase_coordinates(part, scene)
        phase_problem = None
    except RunDataError as exc:
        phase_x = phase_y = np.full(rows.size, np.nan)
        phase_problem = str(exc)
    regime = np.asarray(part["regime"]).astype(str) if "regime" in part else None
    codes = (
        [REGIMES.index(r) if r in REGIMES else -1 for r in np.char.strip(regime).tolist()]
        if regime is not None
        else [-1] * rows.size
    )
    pieces = None
    xs, ys = [q1], [q2]
    if contacts is not None:
        pieces = _pieces(columns, rows, scene, contacts, samples)
        for p in pieces:
            xs.append(np.array(p["x"], dtype=float))
            ys.append(np.array(p["y"], dtype=float))
    x_lim, y_lim, show_lid = view_limits(scene, np.concatenate(xs), np.concatenate(ys))
    amplitude = scene.drive.amplitude
    grid, height = boundary_outline(
        scene, x_lim[0] - amplitude, x_lim[1] + amplitude, OUTLINE_POINTS
    )
    drive = scene.drive
    limited = asked > rows.size
    first, last = int(n[rows[0]]), int(n[rows[-1]])
    note = (
        f"impacts {first} to {last} of {int(n[0])} to {int(n[-1])}: a page holds at most "
        f"{MAX_IMPACTS:,} impacts (its last ones); choose others with billiard view --window"
        if limited
        else ""
    )
    return {
        "format": 1,
        "title": _plain_title(scene, int(n.size)),
        "scene": {
            "name": scene.name,
            "radius": scene.ball.radius,
            "gravity": scene.run.gravity,
            "ceiling": scene.boundary.ceiling,
            "show_lid": bool(show_lid),
            "drive": {
                "amplitude": amplitude,
                "frequency": drive.frequency,
                "omega": drive.omega,
                "phase": drive.phase,
                "direction": drive.direction,
            },
        },
        "run": {
            "impacts": int(n.size),
            "first": first,
            "last": last,
            "shown": int(rows.size),
            "cap": MAX_IMPACTS,
            "limited": limited,
            "note": note,
            "phase_problem": phase_problem,
        },
        "impacts": {
            "n": [int(v) for v in column(part, "n").tolist()],
            "t": _exact(column(part, "t")),
            "q1": _exact(q1),
            "q2": _exact(q2),
            "v1": _exact(column(part, "v1")),
            "v2": _exact(column(part, "v2")),
            "lid": [int(v) for v in lid_mask(part).tolist()],
            "regime": codes,
            "phase_x": _drawn(phase_x),
            "phase_y": _drawn(phase_y),
        },
        "regimes": list(REGIMES),
        "modes": dict(MODE_LABELS),
        "boundary": {"x": _drawn(grid), "y": _drawn(height)},
        "limits": {"x": list(x_lim), "y": list(y_lim)},
        "pieces": pieces,
    }


def _template() -> str:
    return resources.files("billiard.plot").joinpath(_TEMPLATE).read_text(encoding="utf-8")


def page_from_data(data: Mapping[str, Any]) -> str:
    """The HTML page with ``data`` (from :func:`view_data`) inlined as JSON.

    ``</`` is written ``<\\/`` inside the JSON (the same string to a JSON reader), so no
    value can end the script element that holds it.
    """
    text = json.dumps(data, separators=(",", ":"), allow_nan=False, ensure_ascii=False)
    text = text.replace("</", "<\\/").replace("<!--", "<\\u0021--")
    template = _template()
    if template.count(_DATA_MARK) != 1:
        raise RuntimeError(f"{_TEMPLATE}: expected one data marker {_DATA_MARK!r}")
    return template.replace(_DATA_MARK, text)


def view_page(
    columns: Columns,
    scene: Scene,
    contacts: Side | None = None,
    samples: Side | None = None,
    *,
    window: Window | None = None,
) -> str:
    """The interactive view of a run as one self-contained HTML page (see
    :func:`view_data` for the arguments)."""
    return page_from_data(view_data(columns, scene, contacts, samples, window=window))


class View:
    """The interactive view of a run: the page's HTML, shown inline by a notebook.

    Attributes:
        html: the self-contained page (what ``billiard view`` writes to view.html).
        data: the data the page holds (:func:`view_data`).
    """

    #: height (px) of the frame a notebook shows the page in
    height = 1000

    def __init__(self, data: Mapping[str, Any]):
        self.data = dict(data)
        self.html = page_from_data(self.data)

    def __repr__(self) -> str:
        run = self.data["run"]
        return (
            f"<billiard View of {self.data['scene']['name']!r}: impacts {run['first']} to "
            f"{run['last']} of {run['impacts']}, {len(self.html):,} bytes of HTML>"
        )

    def _repr_html_(self) -> str:
        """The page in an iframe's ``srcdoc``: its scripts run in a sandbox of their own,
        apart from the notebook's."""
        return (
            f'<iframe srcdoc="{html.escape(self.html, quote=True)}" sandbox="allow-scripts" '
            f'style="width: 100%; height: {self.height}px; border: 0" '
            f'title="billiard view: {html.escape(self.data["scene"]["name"])}"></iframe>'
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the page to ``path`` (UTF-8); returns the path.

        Raises:
            RunDataError: it cannot be written (one line naming it).
        """
        path = Path(path)
        try:
            path.write_text(self.html, encoding="utf-8")
        except OSError as exc:
            reason = exc.strerror or str(exc) or type(exc).__name__
            raise RunDataError(f"{path}: cannot write the view: {reason}") from None
        return path


def view(source: Any, *, window: Window | None = None) -> View:
    """The interactive view of a run, for a notebook (it displays inline) or to save.

    Args:
        source: a :class:`~billiard.run.result.Result` (from :func:`billiard.simulate`),
            or a run folder (``str`` or path; what ``billiard run`` writes).
        window: ``(n0, n1)``: impact numbers n0 <= n < n1 (either may be None); default
            the whole run, at most its last :data:`MAX_IMPACTS` impacts.

    Raises:
        RunDataError: the folder is not a run's, or its files cannot be read.
        SceneError: the folder's scene.toml is not a valid scene.
    """
    if isinstance(source, (str, os.PathLike)):
        from billiard.plot.run import load_run, load_sides

        columns, scene = load_run(source)
        contacts, samples = load_sides(source)
    elif hasattr(source, "columns") and hasattr(source, "scene"):
        columns, scene = source.columns, source.scene
        contacts, samples = source.contacts, source.trajectory
    else:
        raise RunDataError(f"view: expected a Result or a run folder, got {type(source).__name__}")
    return View(view_data(columns, scene, contacts, samples, window=window))


def write_view(
    run_dir: str | os.PathLike[str],
    out: str | os.PathLike[str] | None = None,
    *,
    window: Window | None = None,
) -> Path:
    """Write the interactive view of the run in ``run_dir`` to ``out`` (default
    ``run_dir/view.html``); returns the path written.

    Raises:
        RunDataError: the folder is not a run's, its files cannot be read, or the page
            cannot be written.
        SceneError: the folder's scene.toml is not a valid scene.
    """
    page = view(Path(run_dir), window=window)
    return page.save(Path(out) if out is not None else Path(run_dir) / VIEW_NAME)
