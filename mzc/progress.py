"""A long step's progress on stderr, for a person watching a terminal.

The command line installs a ticker (``install``) when stderr is a terminal; the library marks
its steps (``step``; ``mzc.errors.about`` does for every step it names, so a file's reading,
slicing, encoding, decoding, densifying and measuring all are). Once a step has run for
DELAY seconds the ticker draws ``mzc: scan.laz: slicing it... 5 s`` on one line, redrawn each
TICK, and clears it when the step ends. Nothing is drawn when stderr is not a terminal, for a
step shorter than DELAY, or in a program that uses mzc as a library (no ticker is installed):
stdout carries data only, and a log keeps only what went wrong.
"""

import contextlib
import threading
import time

DELAY = 2.0   # seconds a step runs before its line appears
TICK = 0.5    # seconds between redraws

ticker = None   # the Ticker the command line installed, else None


class Ticker:
    """A daemon thread that draws the innermost running step on ``stream``."""

    def __init__(self, stream):
        self.stream = stream
        self.steps = []          # [(text, start)], innermost last
        self.drawn = False
        self.lock = threading.Lock()
        threading.Thread(target=self.run, name="mzc-progress", daemon=True).start()

    def run(self):
        """Redraw every TICK while the process lives (a daemon thread ends with it)."""
        while True:
            time.sleep(TICK)
            with self.lock:
                if self.steps:
                    text, start = self.steps[-1]
                    elapsed = time.monotonic() - start
                    if elapsed >= DELAY:
                        self.write(f"\r\x1b[Kmzc: {text}... {elapsed:.0f} s")
                        self.drawn = True

    def enter(self, text):
        """A step begins."""
        with self.lock:
            self.steps.append((text, time.monotonic()))

    def leave(self):
        """The innermost step ends: its line is cleared."""
        with self.lock:
            self.steps.pop()
            self.clear()

    def clear(self):
        """Clear the drawn line (with the lock held), so that a message starts on a clean line."""
        if self.drawn:
            self.write("\r\x1b[K")
            self.drawn = False

    def write(self, text):
        """Draw on the stream; a closed or broken terminal only ends the drawing."""
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):
            self.steps.clear()


def install(stream):
    """Draw long steps' progress on ``stream`` when it is a terminal (the command line's stderr)."""
    global ticker
    if ticker is None and stream.isatty():
        ticker = Ticker(stream)


def clear():
    """Clear the progress line, if one is drawn, before a message is printed (a warning)."""
    if ticker is not None:
        with ticker.lock:
            ticker.clear()


@contextlib.contextmanager
def step(text):
    """Mark a step (``scan.laz: slicing it``) for the ticker, when one is installed."""
    if ticker is None:
        yield
        return
    ticker.enter(text)
    try:
        yield
    finally:
        ticker.leave()
