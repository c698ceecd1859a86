"""Progress of a long step on stderr, shown as the Rust stages show theirs
(crates/io/src/progress.rs): the fraction done, the rate in the step's own units, the time
elapsed and the time left.

On a terminal, one line redrawn in place at most 10 times a second and erased at the end;
otherwise (make's output, Slurm's slurm-<job>.out) a plain line every LUXEST_PROGRESS_INTERVAL
seconds (default 30), so only a step that lasts that long prints any, and a last line when it
ends. LUXEST_PROGRESS=off shows nothing, =bar or =lines either display whatever stderr is (the
same variables as the stages')."""

import math
import os
import sys
import time

DEFAULT_INTERVAL = 30.0
FRAME_PERIOD = 0.1  # seconds between two frames on a terminal
SHORTEST_LINE_PERIOD = 0.01  # LUXEST_PROGRESS_INTERVAL=0: a line per update, at most every 10 ms
BAR_WIDTH = 20


def display(stream, environ=None):
    """(kind, seconds between draws, interval) for `stream`: kind "bar", "lines" or None."""
    env = os.environ if environ is None else environ
    try:
        interval = float(env.get("LUXEST_PROGRESS_INTERVAL", DEFAULT_INTERVAL))
    except ValueError:
        interval = DEFAULT_INTERVAL
    if not (interval >= 0 and math.isfinite(interval)):
        interval = DEFAULT_INTERVAL
    mode = env.get("LUXEST_PROGRESS", "auto").strip()
    if mode == "off":
        return None, 0.0, interval
    terminal = hasattr(stream, "isatty") and stream.isatty()
    if mode == "bar" or (mode != "lines" and terminal):
        return "bar", FRAME_PERIOD, interval
    return "lines", max(interval, SHORTEST_LINE_PERIOD), interval


def count(n):
    """A count: whole below 1000, else three significant digits with an SI prefix (`45.1k`)."""
    return f"{n:.0f}" if n < 999.5 else rate(n)


def rate(v):
    """A rate or count with three significant digits and an SI prefix: `0.31`, `812`, `1.23M`."""
    v = max(v, 0.0)
    prefix = 0
    while v >= 999.5 and prefix < 5:
        v, prefix = v / 1000.0, prefix + 1
    p = ["", "k", "M", "G", "T", "P"][prefix]
    return f"{v:.2f}{p}" if v < 9.995 else f"{v:.1f}{p}" if v < 99.95 else f"{v:.0f}{p}"


def clock(seconds):
    """`0:07`, `12:34`, `3:02:01`."""
    s = int(round(min(max(seconds, 0.0), 1e9)))
    h, m, s = s // 3600, s // 60 % 60, s % 60
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class Progress:
    """`total` units of `label`'s work (None: not known), `done` of them before this run (a
    resumed training), counted by update(); `budget`: seconds this run may take at most (a
    training's --minutes), which bounds the time left. A context manager: close() ends the
    display."""

    def __init__(self, label, total=None, unit="", done=0, budget=None, stream=None, now=time.monotonic):
        self.label, self.total, self.unit, self.budget = label, total, unit, budget
        self.stream = stream if stream is not None else sys.stderr
        self.kind, self.period, self.interval = display(self.stream)
        self.now = now
        self.start = self.last = now()
        self.done = self.first = done
        self.status, self.drawn = "", False

    def update(self, n=1, status=None):
        """Counts `n` more units done; `status` (e.g. `loss 0.0123`) is shown after the rest."""
        self.done += n
        if status is not None:
            self.status = status
        t = self.now()
        if self.kind and t - self.last >= self.period:
            self.last = t
            self._draw(t, last=False)

    def write(self, line):
        """Prints `line` on stderr above the progress."""
        self.stream.write(("\r\x1b[K" if self.drawn and self.kind == "bar" else "") + line + "\n")
        self.stream.flush()

    def close(self):
        t = self.now()
        if self.kind == "bar" and self.drawn:
            self.stream.write("\r\x1b[K")
        elif self.kind == "lines" and t - self.start >= self.interval:
            self._draw(t, last=True)
        self.stream.flush()
        self.kind = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def fraction(self, elapsed):
        """The fraction done: of the units, or of the time budget when that is further along."""
        f = [self.done / max(self.total, 1)] if self.total is not None else []
        f += [elapsed / self.budget] if self.budget else []
        return min(max(f), 1.0) if f else None

    def text(self, elapsed, last=False, bar=False):
        """The frame (`bar`) or the log's line after `elapsed` seconds, as the stages' read."""
        per_second = (self.done - self.first) / elapsed if elapsed > 0 else 0.0
        speed = f"{rate(per_second)} {self.unit}/s"
        left = None
        if self.total is not None and per_second > 0:
            left = (self.total - self.done) / per_second
        if self.budget:
            left = min(left if left is not None else math.inf, self.budget - elapsed)
        f = self.fraction(elapsed)
        pct = f"{math.floor(100 * f):.0f}%" if f is not None else ""
        done = f"{count(self.done)} {self.unit}"
        if self.total is not None:
            done = f"{count(self.done)} of {count(self.total)} {self.unit}"
        status = f", {self.status}" if self.status else ""
        if bar and f is not None:
            full = min(int(f * BAR_WIDTH), BAR_WIDTH)
            head = ">" if full < BAR_WIDTH else ""
            shown = "=" * full + head + " " * (BAR_WIDTH - full - len(head))
            ahead = f"~{clock(left)} left" if left is not None else "--:-- left"
            return f"{self.label} [{shown}] {pct:>4} {ahead}, {speed}, {clock(elapsed)} elapsed, {done}{status}"
        parts = [f"{self.label}: " + (f"{pct} ({done})" if pct else done), speed, f"{clock(elapsed)} elapsed"]
        if last:
            parts.append("done")
        elif left is not None:
            parts.append(f"~{clock(left)} left")
        return ", ".join(parts) + status

    def _draw(self, t, last):
        elapsed = t - self.start
        if self.kind == "bar":
            width = _terminal_width(self.stream) - 1
            frame = self.text(elapsed, bar=True)
            if len(frame) > width:
                cut = frame[:width]
                frame = cut[: cut.rfind(", ")] if ", " in cut else cut
            self.stream.write("\r" + frame + "\x1b[K")
        else:
            self.stream.write(self.text(elapsed, last=last) + "\n")
        self.stream.flush()
        self.drawn = True


def _terminal_width(stream):
    try:
        return max(os.get_terminal_size(stream.fileno()).columns, 20)
    except (AttributeError, OSError, ValueError):
        return 80
