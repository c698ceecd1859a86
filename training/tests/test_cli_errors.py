"""The training scripts' bad input: one line naming the file and the problem, a non-zero exit,
and nothing written (train.py, preprocess.py, export.py, compare_image.py)."""

import re
import sys
from pathlib import Path

import pytest

TRAINING = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TRAINING))

import compare_image  # noqa: E402
import export  # noqa: E402
import preprocess  # noqa: E402
import train  # noqa: E402


def fails(main, argv, pattern):
    with pytest.raises(SystemExit) as e:
        main(argv)
    message = str(e.value.code)
    assert e.value.code not in (0, None) and "\n" not in message, message
    assert re.search(pattern, message), message


def test_missing_inputs_are_one_line_errors_and_write_nothing(tmp_path):
    gone, out = tmp_path / "gone", tmp_path / "out"
    fails(
        train.main,
        ["--prep-dir", str(gone), "--run-dir", str(out / "run")],
        r"^train: .*gone[/\\]train: no preprocessed pairs",
    )
    (gone / "train").mkdir(parents=True)  # a split without images is no dataset either
    fails(
        preprocess.main,
        ["--data-dir", str(gone), "--prep-dir", str(out / "prep")],
        r"^preprocess: error: .*gone: no images in train/, valid/ or test/",
    )
    fails(
        export.main,
        ["--run-dir", str(gone), "--out", str(out / "m.onnx")],
        r"^export: .*gone[/\\]config.json: not found",
    )
    fails(
        export.main,
        ["--from-onnx", str(gone / "m.onnx"), "--out", str(out / "m.onnx")],
        r"^export: .*m.onnx: not found",
    )
    fails(
        compare_image.main,
        [
            "--model",
            str(gone / "m.onnx"),
            "--split-dir",
            str(gone),
            "--work-dir",
            str(out / "w"),
            "--evaluate",
            sys.executable,
        ],
        r"^compare_image: error: --model .*m.onnx: not found",
    )
    assert not out.exists()
