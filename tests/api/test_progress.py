"""The progress line: elapsed time and an ETA from a fake clock, and notebook HTML for results."""

from __future__ import annotations

import base64
import io
import re
from html.parser import HTMLParser

import fabkiri
import pytest
from fabkiri.api.display import result_html
from fabkiri.api.maker_result import MakeResult
from fabkiri.api.progress import ProgressLine, clock_text, on_terminal, three_args

PNG = b"\x89PNG\r\n\x1a\n"


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.mark.parametrize(
    ("fraction", "expected"),
    [
        (None, "make: design  0:12 elapsed"),
        (0.0, "make: design  [0/4] 0 %  0:12 elapsed"),  # nothing done: no ETA, no division
        (0.5, "make: design  [2/4] 50 %  0:12 elapsed, ~0:12 left"),
        (1.0, "make: design  [4/4] 100 %  0:12 elapsed, ~0:00 left"),
    ],
)
def test_progress_line_from_a_fake_clock(fraction, expected):
    clock = FakeClock()
    line = ProgressLine("make", steps=4, clock=clock)
    clock.now += 12
    assert line.line("design", fraction) == expected


def test_progress_line_without_steps_and_at_time_zero():
    clock = FakeClock()
    line = ProgressLine("design", clock=clock)
    assert line.line("solve", 0.6) == "design: solve 60 %  0:00 elapsed, ~0:00 left"
    clock.now += 12
    assert line.line("solve", 0.6) == "design: solve 60 %  0:12 elapsed, ~0:08 left"
    assert clock_text(3725) == "1:02:05" and clock_text(-1) == "0:00"


def test_per_stage_eta_is_timed_from_the_stage_start():
    clock = FakeClock()
    line = ProgressLine("design", clock=clock, per_stage=True)
    clock.now += 60  # a minute of guesses before the continuation starts
    assert line.line("continuation", 0.0) == "design: continuation 0 %  1:00 elapsed"
    clock.now += 10
    assert line.line("continuation", 0.25) == (
        "design: continuation 25 %  1:10 elapsed, ~0:30 left"
    )  # the stage's 10 s for a quarter, not the design's 70 s
    clock.now += 20
    assert line.line("minimax", 0.5) == "design: minimax 50 %  1:30 elapsed, ~0:00 left"


def test_terminal_status_line_sits_under_the_messages():
    stream, clock = io.StringIO(), FakeClock()
    show = on_terminal(stream, ProgressLine("make", steps=4, clock=clock))
    show("design", 0.0, "make: design ...")
    clock.now += 30
    show("design", 0.25, "make: design ok in 30 s")
    show("", None, "")  # the end: the status line is cleared
    text = stream.getvalue()
    assert "make: design ...\n" in text and "make: design ok in 30 s\n" in text
    assert "[1/4] 25 %  0:30 elapsed, ~1:30 left" in text and text.endswith("\r\033[K")


def test_three_args_takes_either_callback():
    heard: list = []
    three_args(heard.append)("cut", 0.5, "make: cut ...")  # one argument: the line alone
    told = three_args(lambda stage, fraction, text: heard.append((stage, fraction, text)))
    told("cut", 0.5, "make: cut ok")
    assert heard == ["make: cut ...", ("cut", 0.5, "make: cut ok")]


class _Page(HTMLParser):
    """Collects the open/close tags (to check they pair), the text and the images' sources."""

    def __init__(self) -> None:
        super().__init__()
        self.open: list[str] = []
        self.text, self.images = "", list[str]()

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.images.append(dict(attrs)["src"])
        else:
            self.open.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag("img" if tag == "img" else tag, attrs)

    def handle_endtag(self, tag):
        assert self.open and self.open.pop() == tag

    def handle_data(self, data):
        self.text += data


def _check_html(page_html: str, summary: str) -> None:
    page = _Page()
    page.feed(page_html)
    page.close()
    assert page.open == [] and summary in page.text
    assert "array(" not in page_html and len(page.images) == 1
    head, data = page.images[0].split(",", 1)
    assert head == "data:image/png;base64" and base64.b64decode(data).startswith(PNG)


def test_results_show_their_summary_and_picture_in_html():
    closed = fabkiri.contract(fabkiri.standard("3x3"))
    _check_html(closed._repr_html_(), closed.summary())
    checked = fabkiri.verify(fabkiri.standard("3x3"))
    _check_html(checked._repr_html_(), checked.summary())


def test_html_escapes_the_summary():
    page = result_html("R", "a <b> & 'c'", PNG + b"rest")
    assert "&lt;b&gt; &amp;" in page and "<b> &" not in page
    _check_html(page, "a <b> & 'c'")
    assert "<img" not in result_html("R", "no picture", None)


class _FakeMake:
    """What MakeResult's display reads, without a minute of making."""

    ok = False

    def summary(self):
        return ["make: star <5 points> at 60 mm", "  design: FAILED"]

    def _repr_png_(self):
        return PNG + b"picture"


def test_make_result_shows_its_first_summary_line_in_html():
    page = MakeResult._repr_html_(_FakeMake())  # type: ignore[arg-type]
    _check_html(page, "make: star <5 points> at 60 mm; FAILED")
    assert "design: FAILED" not in page and re.search("&lt;5 points&gt;", page)
