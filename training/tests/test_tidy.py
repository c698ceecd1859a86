"""Project checks of the Python sources, run as ordinary tests so that `make test` enforces them
(as rust-analyzer's tidy tests do): header keys spelled in one place, and ruff's formatting."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import luxest_contract as contract

ROOT = Path(__file__).resolve().parents[2]
SOURCES = ("training", "pipelines", "data-gen", "python")
CONTRACT = ROOT / "python" / "luxest_contract.py"
PREFIX = contract.SAMPLES.split(".")[0] + "."  # of every header key


def python_files():
    return sorted(p for d in SOURCES for p in (ROOT / d).rglob("*.py") if "__pycache__" not in p.parts)


def header_key_literals(path):
    """(line, text) of every string literal in `path` that starts with PREFIX (a header or
    model-metadata key); f-strings' literal parts included."""
    tree = ast.parse(path.read_text(), str(path))
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.startswith(PREFIX)
    ]


def test_header_keys_are_spelled_only_in_the_contract_module(tmp_path):
    # Every header key is luxest_contract's (SAMPLES, CHANNELS, MODEL_CONFIG, ...): a key typed
    # anywhere else would be a second home of the contract, free to drift from Rust's.
    files = python_files()
    assert CONTRACT in files and len(files) > 30
    assert header_key_literals(CONTRACT), "the contract module spells the keys"
    found = [
        f"{p.relative_to(ROOT)}:{line}: {text!r}"
        for p in files
        if p != CONTRACT
        for line, text in header_key_literals(p)
    ]
    assert found == [], "header keys outside python/luxest_contract.py:\n" + "\n".join(found)
    # The check can fail: a literal key in a source, plain or as an f-string's text, is found.
    bad = tmp_path / "bad.py"
    bad.write_text(f'KEY = "{contract.SAMPLES}"\nmsg = f"{contract.SEED} = {{1}}"\n')
    assert header_key_literals(bad) == [(1, contract.SAMPLES), (2, f"{contract.SEED} = ")]


def test_python_sources_are_ruff_formatted(tmp_path):
    ruff = Path(sys.executable).with_name("ruff")
    if not ruff.exists():
        pytest.fail(f"{ruff}: missing (training/requirements.txt pins it; scripts/setup-python.sh installs it)")
    r = subprocess.run([str(ruff), "format", "--check", *SOURCES], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr + "\n(.venv/bin/ruff format " + " ".join(SOURCES) + " formats them)"
    # The check can fail: an unformatted file under the same configuration is reported.
    bad = tmp_path / "bad.py"
    bad.write_text("x = [ 1,2 ]\n")
    r = subprocess.run(
        [str(ruff), "format", "--check", "--config", str(ROOT / "ruff.toml"), str(bad)], capture_output=True, text=True
    )
    assert r.returncode == 1 and "bad.py" in r.stdout + r.stderr
