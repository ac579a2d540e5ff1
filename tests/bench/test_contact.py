"""The contact section of ``billiard bench`` (bench/contact.py): what one measurement
computes, on a tiny case. No timing is asserted: only the structure, the counts the
models must produce, and that the derived numbers follow from the measured ones."""

from __future__ import annotations

import statistics

import pytest

from bench import contact
from bench.report import ratio_text, section_contact
from billiard.status import Status

DURATION = 0.2  # s of simulated time


@pytest.fixture(autouse=True, scope="module")
def billiard_home(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BILLIARD_HOME", str(tmp_path_factory.mktemp("billiard_home")))
        yield


@pytest.fixture(scope="module")
def bowl():
    case = next(c for c in contact.cases() if c.name == "bowl at rest")
    return contact.measure_case(case, DURATION, repeats=2, max_impacts=10_000)


def test_every_case_sets_the_contact_model():
    for case in contact.cases():
        for model in contact.MODELS:
            assert case.build(model).contact.model == model, case.name


def test_the_section_is_registered():
    from bench.run import SECTIONS
    from billiard.cli.bench import SECTIONS as CLI_SECTIONS
    from billiard.cli.bench import _sections

    assert "contact" in SECTIONS and SECTIONS == CLI_SECTIONS
    assert _sections("contact") == ("contact",)


def test_a_resting_ball_hops_under_impacts_and_lies_under_phases(bowl):
    hops, lying = bowl["impacts"], bowl["phases"]
    assert bowl["duration"] == DURATION
    # impacts: every impact relaunches the ball lying at the bottom, a few hundred per s
    assert hops["impacts"] > 50
    assert hops["resting"] == hops["impacts"] and hops["resting_share"] == 1.0
    assert hops["phases"] == 0 and hops["ended"] == "time"
    assert hops["times"] == {"flight": DURATION, "roll": 0.0, "slide": 0.0, "held": 0.0}
    # phases: no impact at all, one rolling phase open for the whole run
    assert lying["impacts"] == 0 and lying["resting"] == 0
    assert lying["phases"] == 1 and lying["finished_phases"] == 0
    assert lying["times"]["roll"] == pytest.approx(DURATION, rel=1e-12)
    assert lying["times"]["flight"] == pytest.approx(0.0, abs=1e-12)
    assert lying["impacts"] < hops["impacts"]
    assert bowl["chatter"] is True


def test_the_numbers_follow_from_the_runs(bowl):
    for model in contact.MODELS:
        m = bowl[model]
        assert len(m["cpus"]) == 2 and m["same_every_repeat"]
        assert m["cpu"] == statistics.median(m["cpus"])
        assert m["simulated"] == DURATION and m["comparable"]
        assert m["cpu_per_s"] == m["cpu"] / DURATION
        assert m["impacts_per_s"] == m["impacts"] / DURATION
    assert bowl["ratio"] == bowl["impacts"]["cpu_per_s"] / bowl["phases"]["cpu_per_s"]
    pairs = contact.paired_ratios(bowl)
    cpus = zip(bowl["impacts"]["cpus"], bowl["phases"]["cpus"], strict=True)
    assert pairs == [pytest.approx(a / b) for a, b in cpus]


def test_an_early_stop_means_at_rest_only_when_nothing_more_happens():
    assert contact.at_rest(Status.TIME_LIMIT, "the ball rests on the boundary")
    assert not contact.at_rest(Status.TIME_LIMIT, None)
    assert not contact.at_rest(Status.COLLAPSE, "inelastic collapse")


def test_a_run_that_ends_at_rest_counts_its_whole_duration():
    # without a duration, "phases" ends the run of a ball resting on the shaken table
    # early: at rest relative to the table for a whole drive period
    from billiard.engine.simulation import Simulation
    from billiard.runfile.record import MemoryRecorder

    table = next(c for c in contact.cases() if c.name == "shaken table")
    sim = Simulation(table.build("phases"))
    recorder = MemoryRecorder()
    reason = sim.run(100, recorder)
    assert contact.at_rest(sim.status, reason)
    done = contact.summary(sim, 2.0, reason, len(recorder), 0)
    assert done["ended"] == "at rest" and done["comparable"]
    assert done["simulated"] == 2.0 and done["impacts"] == 0 and done["phases"] == 1
    assert done["times"]["roll"] == pytest.approx(2.0, rel=1e-12)
    assert done["times"]["flight"] == pytest.approx(0.0, abs=1e-12)


def row(name, ratio, share):
    return {"case": name, "ratio": ratio, "chatter": share >= contact.CHATTER_SHARE}


def test_the_verdict_counts_only_compared_chatter_cases():
    rows = [
        row("rest", 400.0, 1.0),
        row("roll", 3.0, 0.7),
        row("chaos", 0.8, 0.6),
        row("orbit", 0.97, 0.1),
        row("vertex", None, 0.75),
    ]
    v = contact.verdict(rows)
    assert v["chatter"] == ["rest", "roll", "chaos", "vertex"]
    assert v["compared"] == ["rest", "roll", "chaos"]
    assert v["not_compared"] == ["vertex"]
    assert v["short"] == ["roll", "chaos"]
    assert v["slower"] == ["chaos"]
    assert v["equal"] == ["orbit"]
    assert not v["met"]
    assert contact.verdict(rows[:1])["met"]


def test_the_report_shows_the_measured_case(bowl):
    result = {
        "rows": [bowl],
        "repeats": 2,
        "paper_duration": 1.0,
        "duration": DURATION,
        "max_impacts": 10_000,
        "chatter_share": contact.CHATTER_SHARE,
        "target": contact.TARGET,
        "load": [0.0, 0.0, 0.0],
    }
    text = section_contact(result, "billiard bench")
    assert "| bowl at rest | impacts |" in text
    assert ratio_text(bowl["ratio"]) in text  # as the report formats a ratio
    assert "billiard bench --only contact" in text


def case(name, kind, ratio):
    return {"case": name, "kind": kind, "ratio": ratio, "target": 1.0 if kind == "paper" else 10.0}


def test_the_targets_are_per_kind_with_met_or_not():
    rows = [
        case("wedge", "paper", 0.2),
        case("bowl", "paper", 1.5),
        case("rest", "closed form", 80.0),
        case("table", "closed form", 12.0),
        case("slide", "closed form", None),
    ]
    paper = contact.ratio_targets(rows, "paper")
    assert (paper["target"], paper["short"], paper["met"]) == (1.0, ["wedge"], False)
    closed = contact.ratio_targets(rows, "closed form")
    assert closed["compared"] == ["rest", "table"] and closed["short"] == []
    assert closed["not_compared"] == ["slide"] and not closed["met"]  # one not compared
    assert contact.ratio_targets(rows[2:4], "closed form")["met"]
    # results saved before the targets were per case: from the kind
    assert contact.case_target({"kind": "paper"}) == contact.PAPER_TARGET
    assert contact.case_target({"kind": "closed form"}) == contact.TARGET


def test_a_phase_costs_the_phases_run_less_its_impacts_over_its_phases():
    impacts = {"cpu": 0.02, "impacts": 10_000}  # 2 us per impact
    phases = {"cpu": 0.05, "impacts": 5_000, "phases": 400}
    assert contact.phase_cost(impacts, phases) == pytest.approx(1e6 * (0.05 - 0.01) / 400)
    assert contact.phase_cost(impacts, {**phases, "phases": contact.PHASE_COUNT - 1}) is None
    rows = [{"case": "wedge", "impacts": impacts, "phases": phases}]
    assert contact.phase_costs(rows) == [("wedge", pytest.approx(100.0))]


def test_the_targets_table_judges_the_phase_cost_and_the_compile():
    from bench.report import contact_targets

    rows = [case("wedge", "paper", 1.2), case("rest", "closed form", 50.0)]
    rows[0]["phase_us"] = 12.0
    runs = [{"run": "wedge-6.6hz", "wall": 19.0, "notices": ["billiard: compiling"], "ok": True}]
    runs.append({"run": "wedge-6.6hz", "wall": 1.0, "notices": [], "ok": True})
    compiled = {"runs": runs, "compile_s": 18.0, "waits": 1, "target": 20.0}
    c = {"rows": rows, "compile": compiled}
    verdicts = [row[2] for row in contact_targets(c)]
    assert verdicts == ["met", "met", "met", "met"]
    rows[0]["phase_us"], compiled["waits"] = 16.0, 2
    verdicts = [row[2] for row in contact_targets(c)]
    assert verdicts[2:] == ["not met in 1 of 1", "not met"]
    assert len(contact_targets({"rows": rows})) == 3  # no compile measured: no row
