"""A campaign folder as DataFrame libraries read it: polars, pandas and
pyarrow take the folder's path and nothing else, and read the same rows
(the configuration file, `_campaign.parquet`, adds none)."""

from pathlib import Path

import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("folder")
    text = (ROOT / "examples" / "campaigns" / "waters.toml").read_text()
    config = tmp / "c.toml"
    config.write_text(
        text.replace("systems = 2000", "systems = 60")
        .replace("shard_size = 500", "shard_size = 20")
        .replace('duration = "2s"', 'duration = "100ms"')
    )
    out = tmp / "out"
    report = rtpipe.campaign(config, out)
    assert report["written"] == 3
    return out, report["rows"]


def key(rows):
    """Rows as sortable tuples (readers may order the files differently)."""
    return sorted(tuple((k, str(v)) for k, v in sorted(r.items())) for r in rows)


def test_the_folder_is_parquet_only(folder):
    out, _ = folder
    names = sorted(p.name for p in out.iterdir())
    assert names == ["_campaign.parquet"] + [f"shard-{k:06}.parquet" for k in range(3)]


def test_pyarrow_reads_the_folder(folder):
    pq = pytest.importorskip("pyarrow.parquet")
    ds = pytest.importorskip("pyarrow.dataset")
    out, rows = folder
    table = pq.read_table(out)
    assert table.num_rows == rows
    assert ds.dataset(out).to_table().num_rows == rows
    # The configuration is in the kept file's footer, as it was given.
    meta = pq.read_metadata(out / "_campaign.parquet").metadata
    assert b"[campaign]" in meta[b"rtpipe.config"]


def test_polars_reads_the_folder(folder):
    pl = pytest.importorskip("polars")
    pa = pytest.importorskip("pyarrow.parquet")
    out, rows = folder
    frame = pl.read_parquet(out)
    assert frame.height == rows
    assert pl.scan_parquet(out).select(pl.len()).collect().item() == rows
    assert key(frame.to_dicts()) == key(pa.read_table(out).to_pylist())
    assert frame.schema["seed"] == pl.UInt64


def test_pandas_reads_the_folder(folder):
    pd = pytest.importorskip("pandas")
    pa = pytest.importorskip("pyarrow.parquet")
    out, rows = folder
    frame = pd.read_parquet(out)
    assert len(frame) == rows
    assert sorted(frame["system"].unique()) == sorted(set(pa.read_table(out)["system"].to_pylist()))
