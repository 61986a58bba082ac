"""The design's line for a bent strip (``api/design_summary.py``): it names other rows and columns only where
the strip has them (a 4x4 asked stays 4x4 on a strip, the floor of tiles across binding)."""

from __future__ import annotations

from fabkiri.api.design_summary import _strip_line


def test_the_strips_line_names_other_rows_only_where_they_differ():
    why = "every design missed; a strip bends along the outline"
    same = _strip_line({"tiles": [4, 4], "asked": [4, 4], "why": why})
    # main: "the lattice is 4x4 tiles, not the 4x4 asked"; "the lattice is" starts it, as make keeps it
    assert "not the" not in same
    assert same.startswith("the lattice is the 4x4 tiles asked, laid as a strip")
    other = _strip_line({"tiles": [42, 6], "asked": [16, 16], "why": why})
    assert other.startswith("the lattice is 42x6 tiles, not the 16x16 asked: ")
