"""The wheel as a researcher installs it: `pip install` into a fresh
virtual environment (nothing of the build's environment), then the
Python guide's tour runs there and prints what the guide says it prints."""

import os
import re
import subprocess
import sys
import venv
from pathlib import Path

import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]
GUIDE = ROOT / "docs" / "guide" / "python.md"


def the_tour():
    """The guide's first Python block and the text it says it prints."""
    text = GUIDE.read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S)
    printed = re.search(r"\nprints\n\n```text\n(.*?)```", text, re.S)
    assert code and printed, f"{GUIDE} lost its tour or its output"
    return code.group(1), printed.group(1)


def wheel():
    """The wheel test.sh built (RTPIPE_WHEEL), else the newest in
    target/wheels*; None when there is none."""
    given = os.environ.get("RTPIPE_WHEEL")
    if given:
        return Path(given)
    found = sorted(ROOT.glob("target/wheels*/rtpipe-*.whl"), key=lambda p: p.stat().st_mtime)
    return found[-1] if found else None


def test_the_wheel_installs_into_a_fresh_venv_and_the_tour_runs(tmp_path):
    whl = wheel()
    if whl is None:
        pytest.skip("no wheel built (test.sh sets RTPIPE_WHEEL)")
    env_dir = tmp_path / "fresh"
    # Without pip of its own (ensurepip is slow): this pip installs into it.
    venv.EnvBuilder(with_pip=False, system_site_packages=False).create(env_dir)
    python = env_dir / "bin" / "python"
    pip = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "-q",
         "--disable-pip-version-check", str(whl)],
        capture_output=True, text=True,
    )
    assert pip.returncode == 0, pip.stderr
    # The tour's files: the bundled examples, and ages.csv (latencies
    # measured before: here a simulation's samples, which --observed reads).
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    rtpipe.load(ROOT / "examples" / "cleanflight.toml").simulate(
        duration="1s", samples=str(tmp_path / "ages.csv")
    )
    code, printed = the_tour()
    (tmp_path / "tour.py").write_text(code)
    clean = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    run = subprocess.run([python, "tour.py"], cwd=tmp_path, capture_output=True, text=True, env=clean)
    assert run.returncode == 0, run.stderr
    assert run.stdout == printed
    # The package is the fresh environment's own, not the build's.
    where = subprocess.run(
        [python, "-c", "import rtpipe; print(rtpipe.__file__)"],
        capture_output=True, text=True, env=clean,
    )
    assert where.stdout.startswith(str(env_dir)), where.stdout
