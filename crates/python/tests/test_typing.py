"""The package's types hold: ``mypy --strict`` accepts the rtpipe package
(its stubs and typed results) and every example that uses it, the typed
tour among them."""

import subprocess
import sys
from pathlib import Path

import pytest

import rtpipe

PYTHON = Path(__file__).resolve().parents[1]


def test_mypy_strict_accepts_the_package_and_the_examples(tmp_path):
    pytest.importorskip("mypy", reason="mypy is not installed (pip install mypy)")
    package = Path(rtpipe.__file__).parent
    examples = sorted(str(p) for p in (PYTHON / "examples").glob("*.py"))
    assert any(p.endswith("tour.py") for p in examples)
    for target in (["-p", "rtpipe"], examples):
        out = subprocess.run(
            [sys.executable, "-m", "mypy", "--config-file", str(PYTHON / "mypy.ini"),
             "--no-incremental", *target],
            capture_output=True, text=True, check=False, cwd=tmp_path,
        )
        assert out.returncode == 0, out.stdout + out.stderr


def test_the_tour_runs():
    out = subprocess.run([sys.executable, str(PYTHON / "examples" / "tour.py")],
                         capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert "P1 reaction: sound 526.5 ms" in out.stdout
