"""A scene shows itself: a one-line ``repr`` with its name, curve, drive, restitution,
contact model and impacts (units in the text), and a small HTML table, both from the
scene's values and escaped where a value holds markup."""

from __future__ import annotations

from billiard import load_scene, with_values


def test_repr_is_one_line_with_the_scene_values():
    scene = with_values(
        load_scene("wedge-6.6hz"),
        {"drive.amplitude": 0.031, "contact.restitution": 0.5, "run.collisions": 1234},
    )
    assert repr(scene) == (
        "<Scene 'wedge-6.6hz': curve wedge, lid at 0.2 m; drive horizontal, 0.031 m at "
        "6.6 Hz; restitution 0.5; contact model impacts; 1234 impacts, method event>"
    )


def test_repr_of_a_fixed_boundary_and_a_curve_with_parameters():
    scene = with_values(
        load_scene("parabola-5.4hz"),
        {
            "boundary.curve": "a*x**2",
            "boundary.parameters": {"a": 26.0},
            "boundary.ceiling": None,
            "drive.amplitude": 0.0,
            "run.duration": 3.0,
        },
    )
    text = repr(scene)
    assert "curve a*x**2 (a = 26);" in text and "drive none (fixed boundary)" in text
    assert "at most 3 s>" in text and "\n" not in text


def test_html_is_a_table_of_the_settings():
    scene = load_scene("parabola-5.4hz")
    page = scene._repr_html_()
    assert page.startswith("<table><caption>Scene &#x27;parabola-5.4hz&#x27;</caption>")
    for label, value in [
        ("curve", "parabola, lid at 0.2 m"),
        ("drive", f"horizontal, {scene.drive.amplitude:g} m at 5.4 Hz"),
        ("restitution", "0.393"),
        ("ball", f"radius {scene.ball.radius:g} m, mass {scene.ball.mass:g} kg"),
    ]:
        assert (
            f"<th style='text-align:left'>{label}</th><td style='text-align:left'>{value}" in page
        )


def test_html_escapes_the_description():
    scene = with_values(load_scene("parabola-5.4hz"), {"description": "a <b>bowl</b> & ball"})
    page = scene._repr_html_()
    assert "a &lt;b&gt;bowl&lt;/b&gt; &amp; ball" in page and "<b>" not in page
