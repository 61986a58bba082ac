"""``view_pattern``: the interactive deployment viewer of a pattern as one standalone HTML page.

The frames are the ``deploy`` front door's (:func:`fabkiri.api.deploy.deploy_pattern`, no files), drawn by
:mod:`fabkiri.render.viewer`; ``serve_page`` hands the page to a browser on localhost.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..pattern.model import Pattern
from ..render.viewer import cut_sheets, viewer_data, viewer_page
from .deploy import DeployOutcome, deploy_pattern
from .report_folders import check_report_folders


@dataclass(frozen=True, eq=False)
class ViewOutcome:
    """The page and the deployment it draws (``problems``: what ``deploy`` would exit 1 for)."""

    page: str
    deploy: DeployOutcome

    @property
    def problems(self) -> list[str]:
        return self.deploy.problems


def view_pattern(pattern: Pattern, steps: int = 40, *, cut: str | None = None) -> ViewOutcome:
    """The viewer page of ``pattern`` along its deployment path of ``steps`` steps; ``cut``: a ``fabkiri
    cut`` folder of this pattern (its assembly pieces on hover, its sheets at true scale).

    A pattern that does not close has no path: :class:`fabkiri.errors.CheckFailed`, as ``deploy``."""
    check_report_folders(pattern, {"--cut": cut})  # a cut folder, of this pattern
    pieces, sheets = cut_sheets(cut)
    out = deploy_pattern(pattern, steps, frames=False)
    data = viewer_data(pattern, out.path, pieces=pieces, problems=out.problems, sheets=sheets)
    return ViewOutcome(page=viewer_page(data), deploy=out)


def serve_page(page: str, port: int, ready: Callable[[str], None]) -> None:
    """Serve ``page`` at ``http://127.0.0.1:PORT/`` until interrupted (port 0: any free port).

    ``ready`` gets the address once the socket listens. Only this one page is served (any path)."""
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    body = page.encode("utf-8")

    class Page(BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 (the standard library's name)
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, format: str, *args: object) -> None:  # noqa: A002
            pass  # the terminal shows the address, not every request

    with ThreadingHTTPServer(("127.0.0.1", port), Page) as server:
        ready(f"http://127.0.0.1:{server.server_address[1]}/")
        server.serve_forever()
