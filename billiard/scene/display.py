"""How a scene shows itself: a one-line ``repr`` and a small HTML table for notebooks
(Jupyter calls ``_repr_html_``). A run's :class:`~billiard.run.result.Result` adds its
outcome to the same rows (:func:`html_table`).

Every number carries its unit (SI) and is shown to six significant digits (``%g``):
these are for reading; :func:`~billiard.scene.scene.scene_to_toml` gives the exact values.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["html_table", "scene_line", "scene_rows"]


def _number(value: float, unit: str) -> str:
    return f"{value:g} {unit}"


def _curve(scene: Any) -> str:
    boundary = scene.boundary
    text = boundary.curve
    if boundary.parameters:
        text += " (" + ", ".join(f"{k} = {v:g}" for k, v in boundary.parameters) + ")"
    if boundary.ceiling is not None:
        text += f", lid at {boundary.ceiling:g} m"
    return text


def _drive(scene: Any) -> str:
    drive = scene.drive
    if drive.amplitude == 0.0:
        return "none (fixed boundary)"
    return f"{drive.direction}, {drive.amplitude:g} m at {drive.frequency:g} Hz"


def _run(scene: Any) -> str:
    run = scene.run
    text = f"{run.collisions} impacts, method {run.method}"
    if run.duration is not None:
        text += f", at most {run.duration:g} s"
    return text


def scene_line(scene: Any) -> str:
    """The one-line ``repr`` of a scene: its name, curve, drive, restitution, contact
    model and impact count (units in the text)."""
    return (
        f"<Scene {scene.name!r}: curve {_curve(scene)}; drive {_drive(scene)}; "
        f"restitution {scene.contact.restitution:g}; contact model {scene.contact.model}; "
        f"{_run(scene)}>"
    )


def scene_rows(scene: Any) -> list[tuple[str, str]]:
    """(label, value with its unit) of the scene's main settings, in reading order."""
    contact, ball, air = scene.contact, scene.ball, scene.air
    rows = [("scene", scene.name)]
    if scene.description:
        rows.append(("description", scene.description))
    drag = air.drag
    if air.drag != "none":
        drag += f" ({air.c_lin:g} N s/m, {air.c_quad:g} N s^2/m^2)"
    rows += [
        ("curve", _curve(scene)),
        ("drive", _drive(scene)),
        ("ball", f"radius {_number(ball.radius, 'm')}, mass {_number(ball.mass, 'kg')}"),
        ("restitution", f"{contact.restitution:g}"),
        ("friction", f"mu_s = {contact.mu_static:g}, mu_k = {contact.mu_kinetic:g}"),
        ("contact model", contact.model),
        ("air drag", drag),
        ("run", _run(scene)),
    ]
    return rows


def html_table(rows: Sequence[tuple[str, str]], caption: str) -> str:
    """A small two-column HTML table (label, value), every text escaped."""
    import html  # here: only a notebook asks for HTML (html.entities takes a millisecond)

    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(label)}</th>"
        f"<td style='text-align:left'>{html.escape(value)}</td></tr>"
        for label, value in rows
    )
    return f"<table><caption>{html.escape(caption)}</caption>{body}</table>"
