"""A cut or print that a check refuses comes back from fabkiri.cut / fabkiri.print_pattern as a
result with ok false, the reasons and the checked options; bad input still raises."""

from __future__ import annotations

import fabkiri
import pytest
from fabkiri.errors import CheckFailed, InputError


@pytest.fixture(scope="module")
def square():
    return fabkiri.standard("4x4")


def _refused(result, process):
    assert not result.ok and result.files == {}
    assert result.problems and result.error is not None and isinstance(result.error, CheckFailed)
    line = result.summary()
    assert line.startswith(f"{process} standard-4x4: REFUSED: ") and "\n" not in line
    assert result.problems[0] in line and line in repr(result)
    assert result.alternatives and len(result.advice) == len(result.alternatives)
    assert result.advice[0] in line
    assert "REFUSED" in result._repr_html_()


def test_cut_too_thin_for_the_material_is_a_refused_result(square, tmp_path):
    heard = []
    result = fabkiri.cut(square, "acrylic-3", scale=0.1, progress=lambda *a: heard.append(a))
    _refused(result, "cut")
    assert "thinner than the minimum web" in result.problems[0]
    assert result.advice[0] == "cut with material='acrylic-3', hinge='tape', scale=0.3001"
    assert heard[-1][:2] == ("cut", 1.0) and heard[-1][2].startswith("refused: ")
    with pytest.raises(CheckFailed):  # nothing to write: the refusal again
        result.write(tmp_path / "out")
    assert not (tmp_path / "out").exists()
    again = fabkiri.cut(square, result.alternatives[0].changes["material"], scale=0.3001)
    assert again.ok and again.files


def test_print_past_the_bed_is_a_refused_result(square):
    result = fabkiri.print_pattern(square, scale=40)
    _refused(result, "print")
    assert "does not fit" in result.problems[0] and result.scale == 40.0
    assert "print_pattern with printer='prusa-mk4', style='strips', scale=40" in result.advice


def test_bad_input_still_raises(square):
    with pytest.raises(InputError, match="unknown material"):
        fabkiri.cut(square, "no-such-material")
    with pytest.raises(InputError):
        fabkiri.print_pattern(square, "no-such-printer")
