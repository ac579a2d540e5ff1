"""Curves named in scenes: paper curves, user curves, expressions derived on first use."""

from __future__ import annotations

import pytest

from billiard import curves
from billiard.curves import CurveNotFoundError, load_curve, user_curve_dir
from billiard.scene import load_scene, with_values
from billiard.simulate import simulate


def test_expression_in_a_scene_is_derived_once_and_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    scene = with_values(load_scene("parabola-5.4hz"), {"boundary.curve": "30*x**4 + 0.0063"})
    result = simulate(scene, collisions=50)
    assert len(result) == 50 and result.stop_reason is None
    cached = list((tmp_path / "curves").glob("expr_*.py"))
    assert len(cached) == 1
    # The second use must not derive again: make deriving impossible and load.
    import billiard.derivation.build as build

    def refuse(*args, **kwargs):
        raise AssertionError("derived twice")

    monkeypatch.setattr(build, "derive_user_curve", refuse)
    for module in [m for m in list(curves.sys.modules) if m.startswith("billiard_user_curves")]:
        monkeypatch.delitem(curves.sys.modules, module)
    curve = load_curve("30*x**4 + 0.0063")
    assert curve.f(0.01) == pytest.approx(30 * 0.01**4 + 0.0063, rel=1e-15)
    # Equivalent spellings share the cache entry.
    assert load_curve("30 * x**4 + 6.3e-3").source == curve.source


def test_parameters_of_an_expression_come_from_the_scene(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    curve = load_curve("a*x**2 + c", {"a": 10.0, "c": 0.002})
    assert curve.f(0.1) == pytest.approx(10 * 0.01 + 0.002, rel=1e-15)
    other = load_curve("a*x**2 + c", {"a": 20.0, "c": 0.002})
    assert other.f(0.1) == pytest.approx(20 * 0.01 + 0.002, rel=1e-15)
    assert other.source == curve.source  # one generated module, parameters bound at load


def test_paper_curve_parameters_can_be_overridden():
    assert load_curve("parabola").f(0.0) == pytest.approx(0.0063, rel=1e-15)
    assert load_curve("parabola", {"c": 0.01}).f(0.0) == pytest.approx(0.01, rel=1e-15)
    with pytest.raises(ValueError, match="no parameter"):
        load_curve("parabola", {"q": 1.0})


def test_unknown_curve_name_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    with pytest.raises(CurveNotFoundError, match="billiard derive --name bowlx"):
        load_curve("bowlx")
    assert user_curve_dir() == tmp_path / "curves"
