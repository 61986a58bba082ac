"""The kagome front door's designs by route (first, pair rows, convex holes), for tests of one route; and
the one design with fabrication limits and an opening floor that two tests check."""

from __future__ import annotations

from types import SimpleNamespace


def route_of(kw: dict) -> str:
    return "convex" if kw.get("convex") else "pairs" if kw.get("pairs") else "first"


def design_solving_only(monkeypatch, route: str, *args):
    """``design_kagome(*args)`` with every design but those of ``route`` given no candidate (not solved),
    so that route is the one taken; returns the outcome and the routes asked, in order."""
    from fabkiri.api import kagome as AK

    real, routes = AK.design, []

    def design(*a, **kw):
        routes.append(route_of(kw))
        return real(*a, **kw) if routes[-1] == route else SimpleNamespace(candidates=())

    monkeypatch.setattr(AK, "design", design)
    return AK.design_kagome(*args), routes


# `design --lattice kagome` with the rows of both a material and an opening floor: its free design misses
# both (tiles thinner than acrylic-3's 3 mm, holes 50 % of the sheet), and the designs with the rows meet
# both. test_kagome_fab.py checks the web and the cut, test_opening.py the floor, on the one design
# (``shared_kagome_designs``, the group below: the design is made once per run).
ACRYLIC_OPEN_HEART = (
    "design", "--lattice", "kagome", "--tiles", "4x7", "--target", "heart", "--size", "80",
    "--symmetry", "none", "--material", "acrylic-3", "--min-opening", "0.55",
)  # fmt: skip
ACRYLIC_OPEN_GROUP = "kagome-heart-4x7-80-acrylic-open"
