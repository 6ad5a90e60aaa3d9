"""Progress bars in logs: a line at each tenth of the work, never carriage returns."""

import io

import pytest

from flexval.validation.studies import campaign
from flexval.validation.studies.campaign import LOG_LINES, Progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize("total", [1, 7, 10, 237])
def test_a_bar_writes_a_line_per_tenth_into_a_log(total, monkeypatch):
    log = io.StringIO()
    monkeypatch.setattr(campaign.sys, "stderr", log)
    bar = Progress(total)
    for k in range(total):
        bar.step(f"path {k}")
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) == min(total, LOG_LINES)
    assert lines[-1].startswith("[" + "#" * 24 + "]") and f"{total}/{total}" in lines[-1]


def test_on_a_terminal_the_bar_is_redrawn_in_place(monkeypatch):
    screen = _Terminal()
    monkeypatch.setattr(campaign.sys, "stderr", screen)
    bar = Progress(5)
    for k in range(5):
        bar.step(f"path {k}")
    assert screen.getvalue().count("\r") == 5 and screen.getvalue().count("\n") == 1
