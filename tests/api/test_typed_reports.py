"""Typed reports (issue #34): every report a command writes validates against the JSON Schema shipped
beside the code that writes it, the design attempts and make's steps are read by name, and the design,
kagome and tube outcomes share one ``summary(path=None)`` and one ``max_equality_residual``."""

from __future__ import annotations

import json

import pytest
from fabkiri.api.design import PatternRequest, design_pattern
from fabkiri.api.design_report import report_problem
from fabkiri.schemas import load_schema, schema_problem


@pytest.fixture(scope="module")
def circle():
    """A 4x4 circle: the cheapest quad design with every part of the report."""
    return design_pattern(PatternRequest(tiles=(4, 4), target="circle"))


def test_the_design_report_written_into_pattern_json_validates(circle, tmp_path):
    out = tmp_path / "p.json"
    circle.write(out)
    written = json.loads(out.read_text())["design"]["report"]
    assert report_problem(written) is None
    assert written["preview"] == "p.png"  # the report as written, not only the one in memory
    broken = {k: v for k, v in written.items() if k != "shape"}
    assert report_problem(broken) == "top level: 'shape' is a required property"
    bad = {**written, "attempts": [{"init": "conformal", "status": "converged"}]}
    assert "attempts/0" in str(report_problem(bad))
    # a withheld tile estimate names the count and why (api/shape_limits.py)
    missed = {"status": "missed", "tol_rel": 0.02, "hausdorff_rel": 0.05}
    held = {**missed, "estimate_withheld": {"tiles": [28, 28], "why": "rows bind"}}
    assert report_problem({**written, "shape": {"deployed": held}}) is None
    for broken_estimate in ({"tiles": [28, 28]}, {"tiles": [28], "why": "rows bind"}):
        shape = {"deployed": {**missed, "estimate_withheld": broken_estimate}}
        assert "estimate_withheld" in str(report_problem({**written, "shape": shape}))


def test_one_summary_and_one_residual_name_on_every_design_outcome(circle, tmp_path):
    assert circle.max_equality_residual == circle.report["max_equality_residual"] < 1e-10
    assert circle.summary(tmp_path / "p.json")[0].startswith(
        f"wrote {tmp_path / 'p.json'}: converged"
    )
    assert circle.summary()[0].startswith("designed: converged")
    assert circle.summary()[1:] == circle.summary("p.json")[1:]


def test_the_tube_outcome_has_the_same_summary_and_residual_names():
    from fabkiri.api.tube import design_tube_pattern

    tube = design_tube_pattern((4, 6), "cylinder:60,40")
    assert tube.max_equality_residual == tube.result.report["equality_max"]
    assert tube.summary("t.json")[0] == "wrote t.json: " + tube.summary()[0]
    assert tube.summary()[0].startswith("converged: max equality residual")


def test_the_deploy_report_validates(circle):
    from fabkiri.api.deploy import SCHEMA, deploy_pattern

    out = deploy_pattern(circle.pattern, steps=8, frames=False)
    written = json.loads(out.files["deploy.json"])
    schema = load_schema("fabkiri.api", SCHEMA)
    assert written == out.summary and schema_problem(written, schema) is None
    assert written["pattern_fingerprint"]["sha256"]
    assert schema_problem({**written, "path": "flying"}, schema) is not None
    del written["frames"]
    assert schema_problem(written, schema) == "top level: 'frames' is a required property"


def test_the_verify_report_validates(circle):
    from fabkiri.verify import verify_pattern
    from fabkiri.verify.report import SCHEMA

    report = verify_pattern(circle.pattern)
    written = json.loads(report.to_json())
    schema = load_schema("fabkiri.verify", SCHEMA)
    assert written == report.to_dict() and schema_problem(written, schema) is None
    assert len(written["checks"]) > 10
    written["checks"][0]["op"] = "<"
    assert schema_problem(written, schema) is not None


def test_the_make_record_validates():
    from fabkiri.api.maker_result import SCHEMA, MakeResult, Step
    from fabkiri.api.maker_tiles import TilesChoice

    tiles = TilesChoice((8, 8), "given", 12.0, 3.0, given=True)
    result = MakeResult("heart", 150.0, "cut", "acrylic-3 tape", tiles, "heart")
    result.steps.append(Step("design", True, 0, 1.0, 0.9, "converged", ["heart.json"]))
    result.steps.append(Step("cut", False, 1, 0.5, 0.4, "refused", [], ["too thin"]))
    written = json.loads(result.manifest_text())
    schema = load_schema("fabkiri.api", SCHEMA)
    assert schema_problem(written, schema) is None
    assert written["failed_step"] == "cut" and written["exit_code"] == 1
    written["steps"][0]["extra"] = 1
    assert "steps/0" in str(schema_problem(written, schema))


def test_a_design_attempt_and_a_make_step_are_read_by_name():
    from fabkiri.api.design_judge import _rank
    from fabkiri.api.design_report import DesignAttempt
    from fabkiri.api.maker_design import StepRun

    report = {"conformance": {"deployed": {"hausdorff_rel": 0.01}}, "shape": {}}
    valid = DesignAttempt(None, report, [], True, {})
    invalid = valid._replace(valid=False, problems=["state 1 does not close"])
    assert valid.valid and not invalid.valid and _rank(valid) < _rank(invalid)
    run = StepRun(True, 0, "figures", {}, [])
    assert run.ok and run.exit_code == 0 and run._replace(details=["x"]).details == ["x"]


@pytest.mark.slow
@pytest.mark.xdist_group("kagome-circle-6x11-120")  # shares its design (shared_kagome_designs)
def test_the_kagome_design_report_validates(tmp_path, run_cli, shared_kagome_designs):
    out = tmp_path / "c.json"
    args = ("--lattice", "kagome", "--tiles", "6x11", "--target", "circle", "--size", "120")
    code, _, err = run_cli("design", *args, "-o", out)
    assert code == 0, err
    written = json.loads(out.read_text())["design"]["report"]
    assert report_problem(written) is None and "verify_failed" in written
    del written["tol"]
    assert report_problem(written) == "top level: 'tol' is a required property"


def test_a_refusal_speaks_in_parameters_and_the_cli_in_flags(run_cli, tmp_path):
    """A library caller reads ``size=24.54`` and gets the value as a number; the CLI prints the same
    message with ``--size 24.54``, as it always did."""
    import pickle

    from fabkiri.errors import InputError

    request = PatternRequest(tiles=(8, 8), target="heart", size=20, material="acrylic-3")
    with pytest.raises(InputError) as caught:
        design_pattern(request)
    exc = caught.value
    assert str(exc).endswith("the smallest size that could work is size=24.54")
    assert exc.cli_message() == str(exc).replace("size=24.54", "--size 24.54")
    assert exc.params["size"] == pytest.approx(24.54, abs=0.005)
    assert pickle.loads(pickle.dumps(exc)).cli_message() == exc.cli_message()  # a sweep's worker
    args = ("--tiles", "8x8", "--target", "heart", "--size", "20", "--material", "acrylic-3")
    code, _, err = run_cli("design", *args, "-o", tmp_path / "x.json")
    assert code == 2 and err == f"fabkiri: error: {exc.cli_message()}\n"
    with pytest.raises(InputError) as caught:
        design_pattern(PatternRequest(tiles=None, target="circle", solver="reduced"))
    assert str(caught.value).startswith("quad designs need tiles=(rows, cols)")
    assert caught.value.cli_message().startswith("quad designs need --tiles ROWSxCOLS")
    with pytest.raises(InputError) as caught:
        design_pattern(PatternRequest(tiles=(4, 4), target="circle", solver="reduced"))
    assert str(caught.value).startswith("solver='reduced' needs rigid=True,")
    assert caught.value.cli_message().startswith("--solver reduced needs --rigid,")
    assert caught.value.params == {"solver": "reduced", "rigid": True}
    named = pickle.loads(
        pickle.dumps(caught.value)
    )  # a parameter named alone survives pickling too
    assert str(named) == str(caught.value) and named.cli_message() == caught.value.cli_message()
