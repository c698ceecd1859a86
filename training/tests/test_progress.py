"""The Python steps' progress (training/progress.py), shown as the Rust stages show theirs: plain
periodic lines in a log (make's output, Slurm's slurm-<job>.out), a line redrawn in place on a
terminal at most 10 times a second, nothing with LUXEST_PROGRESS=off."""

import io

import progress


class Clock:
    """A clock the test advances."""

    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class Terminal(io.StringIO):
    def isatty(self):
        return True


def run(stream, monkeypatch, env, updates, step=1.0, **kw):
    """Counts `updates` units, one per `step` seconds of a fake clock; returns what was written."""
    monkeypatch.delenv("LUXEST_PROGRESS", raising=False)
    monkeypatch.delenv("LUXEST_PROGRESS_INTERVAL", raising=False)
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    clock = Clock()
    with progress.Progress("train", kw.pop("total", updates), "steps", stream=stream, now=clock, **kw) as p:
        for i in range(updates):
            clock.t += step
            p.update(1, f"loss {1.0 / (i + 1):.4f}")
    return stream.getvalue()


def test_a_log_gets_plain_lines_every_interval_and_a_last_one(monkeypatch):
    text = run(io.StringIO(), monkeypatch, {"LUXEST_PROGRESS_INTERVAL": "10"}, 35)
    assert "\r" not in text and "\x1b" not in text
    lines = text.splitlines()
    assert lines == [
        "train: 28% (10 of 35 steps), 1.00 steps/s, 0:10 elapsed, ~0:25 left, loss 0.1000",
        "train: 57% (20 of 35 steps), 1.00 steps/s, 0:20 elapsed, ~0:15 left, loss 0.0500",
        "train: 85% (30 of 35 steps), 1.00 steps/s, 0:30 elapsed, ~0:05 left, loss 0.0333",
        "train: 100% (35 of 35 steps), 1.00 steps/s, 0:35 elapsed, done, loss 0.0286",
    ]


def test_a_short_step_logs_nothing_and_off_shows_nothing(monkeypatch):
    assert run(io.StringIO(), monkeypatch, {}, 20) == ""  # 20 s under the default 30 s
    assert run(Terminal(), monkeypatch, {"LUXEST_PROGRESS": "off"}, 20) == ""


def test_a_terminal_gets_frames_in_place_at_most_ten_a_second_then_erased(monkeypatch):
    text = run(Terminal(), monkeypatch, {}, 100, step=0.01)  # 100 updates in one second
    assert "\n" not in text
    frames = text.split("\r")[1:-1]
    assert 1 <= len(frames) <= 10, frames
    assert frames[0].startswith("train [") and frames[0].endswith("\x1b[K")
    assert text.endswith("\r\x1b[K")


def test_a_time_budget_bounds_the_fraction_and_the_time_left(monkeypatch):
    # A resumed training: 1000 of 5000 steps done before, 60 s of budget, 1 step per second.
    text = run(
        io.StringIO(),
        monkeypatch,
        {"LUXEST_PROGRESS": "lines", "LUXEST_PROGRESS_INTERVAL": "30"},
        30,
        total=5000,
        done=1000,
        budget=60.0,
    )
    first = text.splitlines()[0]
    assert first.startswith("train: 50% (1.03k of 5.00k steps), 1.00 steps/s, 0:30 elapsed, ~0:30 left"), first
