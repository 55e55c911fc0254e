"""The progress line of ``render`` and ``code-bank`` (``satagraph.cli.progress``)."""
from __future__ import annotations

import io

from satagraph.cli.progress import ProgressLine


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_total_is_said_beside_the_count():
    term = Terminal()
    line = ProgressLine(term, "frames drawn", clock=lambda: 0.0)
    line(1, 300), line(300, 300), line.end()
    assert term.getvalue() == "\r1 of 300 frames drawn, 0 s\r300 of 300 frames drawn, 0 s\n"


def test_a_log_gets_a_line_every_so_often_and_nothing_to_end():
    now = [0.0]
    log = io.StringIO()
    line = ProgressLine(log, "frames drawn", every=30.0, clock=lambda: now[0])
    for drawn, t in ((100, 10.0), (900, 31.0), (1000, 35.0), (2571, 61.5)):
        now[0] = t
        line(drawn, 2571)
    line.end()
    assert log.getvalue() == "900 of 2571 frames drawn, 31 s\n2571 of 2571 frames drawn, 62 s\n"


def test_add_keeps_a_running_count_of_what_each_batch_did():
    term = Terminal()
    line = ProgressLine(term, "windows refined", clock=lambda: 0.0)
    for batch in (16, 16, 3):
        line.add(batch)
    line.end()
    assert line.count == 35
    assert term.getvalue().split("\r")[1:] == ["16 windows refined, 0 s",
                                               "32 windows refined, 0 s",
                                               "35 windows refined, 0 s\n"]
