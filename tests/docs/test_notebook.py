"""docs/notebooks/derivation.ipynb: stored without outputs, executed by nbclient in a
kernel of this environment, its checks read back from the kernel; a sign error planted
in the derivation's source fails the checks that cover it."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
from billiard.derivation.build import sympy_mismatch

nbformat = pytest.importorskip("nbformat", reason="the test extra installs nbformat")
nbclient = pytest.importorskip("nbclient", reason="the test extra installs nbclient")
pytest.importorskip("ipykernel", reason="the test extra installs ipykernel")

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "docs" / "notebooks" / "derivation.ipynb"
#: The notebook's checks, each the result of one cell (see its first code cell, check()).
CHECKS = {
    "frames",
    "partial_velocities",
    "flight",
    "impact_impulses",
    "post_impact_velocity",
    "rolling_incline",
    "generated_code",
    "generated_numbers",
    "simulation_replay",
    "impacts_on_offset_curve",
}
MARK = "checks as json: "

#: Sign errors planted in the derivation's source: (module, text, replacement). The
#: restitution condition wn+ = -e wn- becomes wn+ = +e wn- (the impact maps change);
#: gravity in sustained contact points up (the rolling equations change).
PLANTS = (
    ("ball", "restitution = wn.subs(to_post) + e * wn", "restitution = wn.subs(to_post) - e * wn"),
    ("contact", "gravity = (C, -m * g * N.y)", "gravity = (C, m * g * N.y)"),
)
#: The checks each planted error fails, and only those.
PLANTED_FAILURES = {
    "impact_impulses",  # Rn = -(1 - e) m wn- instead of -(1 + e) m wn-
    "post_impact_velocity",
    "generated_code",  # the module generated from it differs from generated/ball.py
    "generated_numbers",
    "simulation_replay",  # the runtime (committed generated code) no longer agrees
    "rolling_incline",
}

PLANT_CELL = """\
import inspect

import billiard.derivation.{module} as planted

source = inspect.getsource(planted)
assert source.count({text!r}) == 1, "the planted line is not in the derivation"
exec(compile(source.replace({text!r}, {replacement!r}), planted.__file__, "exec"), planted.__dict__)
"""


def execute(tmp_path: Path, plant: bool = False) -> tuple[dict, object, Exception | None]:
    """Run the notebook in a fresh kernel ("python3": ipykernel's, in this interpreter's
    environment); return its checks, the executed notebook and the error that stopped
    it (None when it ran to the end).

    The kernels of the short simulation run interpreted (NUMBA_DISABLE_JIT=1, the same
    results to the last bit: tests/kernels/test_interpreted.py): compiling them first
    would take 40 s to minutes on a busy machine.
    """
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # Read the checks back just before the last cell, which fails on a failed check.
    nb.cells.insert(
        len(nb.cells) - 1,
        nbformat.v4.new_code_cell(f"import json\nprint({MARK!r} + json.dumps(checks))"),
    )
    if plant:
        cells = [
            nbformat.v4.new_code_cell(PLANT_CELL.format(module=m, text=t, replacement=r))
            for m, t, r in PLANTS
        ]
        nb.cells[:0] = cells
    client = nbclient.NotebookClient(
        nb,
        kernel_name="python3",
        timeout=600,
        resources={"metadata": {"path": str(tmp_path)}},
    )
    environment = dict(os.environ, NUMBA_DISABLE_JIT="1")
    error = None
    with pytest.MonkeyPatch.context() as patch:
        for key, value in environment.items():
            patch.setenv(key, value)
        try:
            client.execute()
        except nbclient.exceptions.CellExecutionError as exc:
            error = exc
    printed = [
        out.text
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "stream" and out.text.startswith(MARK)
    ]
    assert len(printed) == 1, f"the notebook stopped before its checks were read: {error}"
    return json.loads(printed[0].removeprefix(MARK)), nb, error


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    return execute(tmp_path_factory.mktemp("notebook"))


def test_the_notebook_is_stored_without_outputs() -> None:
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code and all(c.outputs == [] and c.execution_count is None for c in code)
    assert nb.metadata.kernelspec.name == "python3"


def test_the_notebook_runs_and_its_checks_hold(executed) -> None:
    checks, nb, error = executed
    assert error is None, error
    expected = dict.fromkeys(CHECKS, True)
    if sympy_mismatch() is not None:  # only the release that wrote generated/ reproduces it
        expected["generated_code"] = None
    assert checks == expected
    outputs = [out for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    # the figures: offset curves and frames; flights and an impact
    assert sum("image/png" in out.get("data", {}) for out in outputs) == 2
    # the cell that prints simplify(generated - textbook) for the impulses shows zeros
    [cell] = [c for c in nb.cells if "display(impact_difference)" in c.source]
    [shown] = [out.data["text/plain"] for out in cell.outputs if "data" in out]
    assert set(shown) <= set("0 ⎡⎤⎢⎥⎣⎦\n") and shown.count("0") == 4, shown
    # the last cell sums them up
    holding = sum(value is True for value in expected.values())
    assert nb.cells[-1].outputs[0].text.startswith(f"{holding} of {len(CHECKS)} checks hold")


def test_a_sign_error_planted_in_the_derivation_fails_its_checks(tmp_path) -> None:
    checks, _, error = execute(tmp_path, plant=True)
    failed = {name for name, holds in checks.items() if holds is False}
    if sympy_mismatch() is not None:
        failed.add("generated_code")  # not made under another sympy
    assert failed == PLANTED_FAILURES
    assert {name for name, holds in checks.items() if holds} == CHECKS - PLANTED_FAILURES
    # and the notebook's last cell stops the run naming them (jupyter execute exits with 1)
    assert error is not None
    named = re.search(r"checks that fail: \[([^\]]*)\]", str(error))
    assert named is not None, error
    assert set(re.findall(r"'(\w+)'", named.group(1))) == {n for n in failed if checks[n] is False}


def test_the_documentation_index_links_the_notebook_and_says_how_to_run_it() -> None:
    index = (ROOT / "docs" / "index.md").read_text()
    assert "](notebooks/derivation.ipynb)" in index
    assert "jupyter execute docs/notebooks/derivation.ipynb" in index
    assert 'pip install -e ".[test]"' in index
