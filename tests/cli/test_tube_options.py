"""``design --tube`` refuses the design options a tube does not use by comparing them with their defaults; the
table of defaults it compares with must be the design parser's own, or a changed default refuses every tube."""

from fabkiri.cli.main import build_parser
from fabkiri.cli.tube_cmd import options_not_for_tubes


def _parsed(*extra: str):
    argv = ["design", "--tube", "cylinder:100,60", "--tiles", "4x8", "-o", "t.json", *extra]
    return build_parser("design").parse_args(argv)


def test_a_bare_tube_design_gives_no_option_a_tube_does_not_use():
    assert options_not_for_tubes(_parsed()) == []


def test_an_option_given_is_named():
    assert options_not_for_tubes(_parsed("--solver", "full", "--size", "80")) == ["size", "solver"]
