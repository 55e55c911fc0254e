"""A command's progress on stderr: a count redrawn in place on a terminal,
a line now and then in a log."""
from __future__ import annotations

import time
from typing import Any, Callable, Optional


class ProgressLine:
    """A count (of a total, where one is given) and the seconds since it
    started, on :obj:`stream`: one line redrawn in place on a terminal, a
    line of its own every :obj:`every` seconds elsewhere (a log file read
    the redrawn line as one run-on line: ``16 windows, 0 s22 windows, 0
    s...``).

    Args:
        stream: Where it is written (``sys.stderr``).
        what (str): What is counted (``"windows"``, ``"frames drawn"``).
        every (float): Seconds between the lines of a log.
        clock (callable): The time in seconds (``time.monotonic``).
    """

    def __init__(self, stream: Any, what: str, every: float = 30.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.stream, self.what, self.every, self.clock = stream, what, every, clock
        self.start = self.last = clock()
        self.live = bool(getattr(stream, "isatty", lambda: False)())
        self.drawn = False
        self.count = 0

    def __call__(self, count: int, total: Optional[int] = None) -> None:
        now = self.clock()
        of = "" if total is None else f" of {total}"
        text = f"{count}{of} {self.what}, {now - self.start:.0f} s"
        if self.live:
            print(f"\r{text}", end="", file=self.stream, flush=True)
            self.drawn = True
        elif now - self.last >= self.every:
            print(text, file=self.stream, flush=True)
            self.last = now

    def add(self, count: int) -> None:
        """Count :obj:`count` more and show the running count (for work
        that reports each batch it did, not how far it is)."""
        self.count += count
        self(self.count)

    def end(self) -> None:
        """End a redrawn line (nothing to end elsewhere)."""
        if self.drawn:
            print(file=self.stream)
            self.drawn = False
