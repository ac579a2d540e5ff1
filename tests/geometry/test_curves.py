"""Curves named in scenes: paper curves, user curves, expressions derived on first use."""

from __future__ import annotations

import pytest

from billiard.geometry import curves
from billiard.geometry.curves import CurveNotFoundError, load_curve, user_curve_dir
from billiard.run.simulate import simulate
from billiard.scene.scene import load_scene, with_values


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


def _billiard(home, *args):
    """``billiard ARGS`` in a fresh interpreter, as a user runs it: (status, stderr lines)."""
    import os
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-m", "billiard.cli", *args],
        capture_output=True,
        text=True,
        env={**os.environ, "BILLIARD_HOME": str(home)},
        timeout=300,
    )
    return proc.returncode, proc.stderr.strip().splitlines()


# --- one rule for names, one table of built-ins ------------------------------------------


def test_curve_names_follow_one_rule_everywhere():
    from billiard.derivation.expr import BUILTIN_CURVES, PAPER_CURVES, is_curve_name

    from billiard.scene.scene import BUILTIN_CURVES as SCENE_BUILTINS
    from billiard.scene.scene import curve_kind

    assert curves.PAPER_CURVES == SCENE_BUILTINS == BUILTIN_CURVES == tuple(PAPER_CURVES)
    for text in ("my-bowl", "bowl", "b_2", "my-curve_2"):
        assert is_curve_name(text) and not curves.is_expression(text)
        assert curve_kind(text) == "named"
    for text in ("x", "pi", "my - bowl", "26*x**2", "-x**2", "2bowl"):
        assert not is_curve_name(text) and curves.is_expression(text)


def test_hyphenated_name_is_a_curve_in_scenes_and_derive(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    from billiard.cli import main

    assert main(["derive", "--name", "my-bowl", "--curve", "30*x**4 + 0.0063"]) == 0
    scene = with_values(load_scene("parabola-5.4hz"), {"boundary.curve": "my-bowl"})
    assert scene.boundary.kind == "named" and scene.boundary.expression is None
    result = simulate(scene, collisions=20)
    assert len(result) == 20 and result.stop_reason is None


def test_the_parser_does_not_load_sympy():
    import subprocess
    import sys

    code = (
        "import sys, billiard.scene.scene, billiard.geometry.curves, billiard.geometry.boundary\n"
        "from billiard.derivation.expr import parse_curve\n"
        "parse_curve('26*x**2 + 0.0063').evaluate(0.1)\n"
        "assert 'sympy' not in sys.modules, 'sympy loaded'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


# --- the cache shared by processes -------------------------------------------------------


def _derive_in_a_fresh_process(home: str, expression: str) -> str:
    import os
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from billiard.geometry.curves import load_curve\n"
        "curve = load_curve(sys.argv[1])\n"
        "print(curve.source)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, expression],
        capture_output=True,
        text=True,
        env={**os.environ, "BILLIARD_HOME": home},
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def test_two_processes_derive_the_same_new_expression_at_once(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    expression = "31*x**4 + 0.5*x**2 + 0.0063"
    with ThreadPoolExecutor(2) as pool:
        paths = list(
            pool.map(lambda _: _derive_in_a_fresh_process(str(tmp_path), expression), [0, 1])
        )
    assert paths[0] == paths[1]
    files = sorted((tmp_path / "curves").iterdir())
    assert [p.name for p in files] == [paths[0].rsplit("/", 1)[1]]  # no temporary left
    from billiard.derivation.contenthash import hash_matches

    assert hash_matches(files[0].read_text())


def test_an_edited_user_curve_module_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    from billiard.cli import main

    assert main(["derive", "--name", "edited", "--curve", "30*x**4 + 0.0063"]) == 0
    path = tmp_path / "curves" / "edited.py"
    text = path.read_text()
    assert "return 30*" in text
    path.write_text(text.replace("return 30*", "return 31*"))
    with pytest.raises(CurveNotFoundError, match="changed after it was generated") as info:
        load_curve("edited")
    assert "billiard derive --name edited" in str(info.value) and "--force" in str(info.value)


def test_a_read_only_curve_cache_is_named_in_the_error(tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    (home / "curves").write_text("")  # the cache cannot be made, even by root
    code, err = _billiard(
        home,
        "run",
        "parabola-5.4hz",
        "--set",
        "boundary.curve=32*x**4 + 0.0063",
        "--no-plot",
        "--collisions",
        "5",
        "--out",
        str(tmp_path / "run"),
    )
    assert code == 2 and len(err) == 1, err
    assert "user curve cache" in err[0] and str(home / "curves") in err[0]
    assert "BILLIARD_HOME" in err[0] and "cannot write the run" not in err[0]


# --- curves that are not real and finite where the ball can go -------------------------


@pytest.mark.parametrize("text", ["1/x", "log(x)", "x**-2", "sqrt(-1-x**2)", "abs(x)**1.5"])
def test_run_with_an_undefined_curve_is_one_line(text, tmp_path):
    code, err = _billiard(
        tmp_path,
        "run",
        "parabola-5.4hz",
        "--set",
        f"boundary.curve={text}",
        "--no-plot",
        "--collisions",
        "5",
        "--out",
        str(tmp_path / "run"),
    )
    assert code == 2 and len(err) == 1 and err[0].startswith("billiard: error:"), err
    assert "cannot hold a ball" in err[0]


def test_a_curve_made_singular_by_its_parameters_is_a_geometry_error(tmp_path):
    code, err = _billiard(
        tmp_path,
        "derive",
        "--name",
        "sing",
        "--curve",
        "26*x**2 + sqrt(x**2 + a)",
        "--param",
        "a=1e-4",
    )
    assert code == 0, err
    code, err = _billiard(
        tmp_path,
        "run",
        "parabola-5.4hz",
        "--set",
        "boundary.curve=sing",
        "--set",
        "boundary.parameters.a=-1e-4",
        "--no-plot",
        "--collisions",
        "5",
        "--out",
        str(tmp_path / "run"),
    )
    assert code == 2 and len(err) == 1, err
    assert "boundary curve 'sing' is not real and finite at x = 0 m" in err[0]


def test_an_old_unchecked_module_fails_as_a_geometry_error(tmp_path, monkeypatch):
    """A module derived before the shape checks (written here without them)."""
    from billiard.derivation import build

    from billiard.errors import GeometryError

    monkeypatch.setenv("BILLIARD_HOME", str(tmp_path))
    directory = tmp_path / "curves"
    directory.mkdir()
    cd = build.curve_from_text("old", "1/x", {})
    (directory / "old.py").write_text(build.curve_module(cd))
    scene = with_values(load_scene("parabola-5.4hz"), {"boundary.curve": "old"})
    with pytest.raises(GeometryError, match=r"boundary curve 'old' is not real and finite at x"):
        simulate(scene, collisions=5)
