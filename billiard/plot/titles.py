"""Figure titles and legend labels."""

from __future__ import annotations

import textwrap

from billiard.plot.common import MM
from billiard.scene.scene import Scene

__all__ = ["camera_label", "fmt", "scene_title", "short_label"]


def fmt(value: float) -> str:
    return f"{value:.4g}"


def _curve_text(scene: Scene) -> str:
    curve = scene.boundary.curve
    if scene.boundary.kind == "expression":
        text = "f(x) = " + (curve if len(curve) <= 50 else curve[:47] + "...")
    else:
        text = f"curve {curve}"
    if scene.boundary.parameters:
        text += " (" + ", ".join(f"{k}={fmt(v)}" for k, v in scene.boundary.parameters) + ")"
    return text


def scene_title(scene: Scene, n_impacts: int | None = None, width: int = 90) -> str:
    """A figure title: the scene's name, then curve, drive, restitution and friction.

    The parts are joined with "; " on lines of at most ``width`` characters, e.g.::

        parabola-5.4hz, 25000 impacts
        curve parabola; drive 5.4 Hz, A = 5 mm horizontal; e = 0.393, mu_s = 0.61, mu_k = 0.47

    (mu_s and mu_k are drawn as Greek letters).
    """
    head = scene.name if n_impacts is None else f"{scene.name}, {n_impacts} impacts"
    drive = scene.drive
    drive_text = (
        f"drive {fmt(drive.frequency)} Hz, A = {fmt(drive.amplitude * MM)} mm {drive.direction}"
    )
    contact = scene.contact
    contact_text = (
        f"e = {fmt(contact.restitution)}, $\\mu_s$ = {fmt(contact.mu_static)}, "
        f"$\\mu_k$ = {fmt(contact.mu_kinetic)}"
    )
    # Break between the parts where possible; wrap a part only if it is too long alone.
    # Lengths are measured on plain text, so that the mathtext of mu counts as 4 characters.
    lines: list[str] = []
    for part in (_curve_text(scene), drive_text, contact_text):
        plain = _plain(part)
        current = lines[-1] if lines else None
        if current is not None and len(_plain(current)) + 2 + len(plain) <= width:
            lines[-1] = f"{current}; {part}"
        elif len(plain) <= width:
            lines.append(part)
        else:
            lines += textwrap.wrap(part, width=width)
    return head + "\n" + "\n".join(lines)


def _plain(text: str) -> str:
    return text.replace("$\\mu_s$", "mu_s").replace("$\\mu_k$", "mu_k")


def short_label(scene: Scene) -> str:
    """A panel title such as 'wedge, 6.6 Hz'."""
    curve = scene.name if scene.boundary.kind == "expression" else scene.boundary.curve
    return f"{curve}, {fmt(scene.drive.frequency)} Hz"


def camera_label(frame_interval: float, count: int) -> str:
    fps = 1.0 / frame_interval
    return f"camera, frame {frame_interval * 1e3:.3g} ms ({fps:.3g} fps): {count} impacts"
