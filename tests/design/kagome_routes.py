"""The kagome front door's designs by route (first, pair rows, convex holes), for tests of one route."""

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
