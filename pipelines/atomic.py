"""Atomic text output for the pipeline scripts (standard library only, so that the scripts run
by the system python3 can use it): the file appears complete or not at all."""

from pathlib import Path


def write_text(path, text):
    """Writes `text` to `path` through a temporary file beside it and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)
