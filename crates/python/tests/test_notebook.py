"""The notebook example (crates/python/examples/notebook.py, `# %%`
cells) runs top to bottom at small sizes and draws both figures: the
paper's Fig. 9 and E2EEvaluation's comparison."""

import os
import runpy
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
NOTEBOOK = ROOT / "crates" / "python" / "examples" / "notebook.py"


def test_the_notebook_draws_both_figures(tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    pytest.importorskip("pyarrow")
    monkeypatch.setenv("NOTEBOOK_OUTPUTS", "1000")
    monkeypatch.setenv("NOTEBOOK_SYSTEMS", "40")
    monkeypatch.setenv("NOTEBOOK_OUT", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    cells = [c for c in NOTEBOOK.read_text().split("# %%") if c.strip()]
    assert len(cells) >= 6, "a notebook of cells"
    ns = runpy.run_path(str(NOTEBOOK), run_name="notebook")
    for name in ("fig9.png", "e2e.png"):
        png = (tmp_path / name).read_bytes()
        assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000, name
    out = capsys.readouterr().out
    # Fig. 9's table: every chain and metric observed, none above its sound bound.
    rows = ns["rows"]
    assert {(n, m) for n, m, *_ in rows} == {(c, m) for c in ("P1", "P2") for m in ("reaction", "freshness")}
    for name, metric, count, worst, paper, sound in rows:
        assert count > 0 and worst <= sound, (name, metric, worst, sound)
    assert "| P1 | reaction |" in out
    # E2EEvaluation's comparison: the sound bound never above Davare's.
    for metric in ("reaction", "freshness"):
        assert (ns["reductions"][metric]["rtpipe sound"] >= -1e-12).all()
    assert "| maximum reduced data age | rtpipe sound |" in out
