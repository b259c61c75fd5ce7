"""Campaigns from Python, and across a local multi-process Ray cluster:
the same Parquet files, byte for byte, as one machine's run."""

import importlib.util
import sys
from pathlib import Path

import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]
RECIPE = ROOT / "crates" / "python" / "examples" / "ray_campaign.py"


def small_config(tmp_path, systems=120, shard_size=20):
    text = (ROOT / "examples" / "campaigns" / "waters.toml").read_text()
    text = (
        text.replace("systems = 2000", f"systems = {systems}")
        .replace("shard_size = 500", f"shard_size = {shard_size}")
        .replace('duration = "2s"', 'duration = "300ms"')
    )
    path = tmp_path / "c.toml"
    path.write_text(text)
    return path


def shard_bytes(out):
    return {p.name: p.read_bytes() for p in sorted(Path(out).glob("shard-*.parquet"))}


def test_a_campaign_from_python_writes_and_resumes(tmp_path):
    config = small_config(tmp_path)
    plan = rtpipe.campaign(config, tmp_path / "out", plan=True)
    assert (plan["shards"], plan["written"]) == (6, [])
    assert not (tmp_path / "out").exists()
    r = rtpipe.campaign(config, tmp_path / "out", jobs=2)
    assert (r["written"], r["systems_run"], r["exit_status"]) == (6, 120, 0)
    assert r["systems_per_second_per_job"] > 0
    again = rtpipe.campaign(config, tmp_path / "out", shard=(1, 2))
    assert (again["part_shards"], again["written"], again["skipped"]) == (3, 0, 3)
    with pytest.raises(rtpipe.InputError, match="below n"):
        rtpipe.campaign(config, tmp_path / "out", shard="2/2")


def test_the_shards_read_back_with_pyarrow(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    config = small_config(tmp_path, systems=40)
    rtpipe.campaign(config, tmp_path / "out")
    t = pq.read_table(tmp_path / "out")  # `_campaign.parquet` is not data
    assert set(t.column("system").to_pylist()) <= set(range(40))
    assert t.schema.field("seed").type == "uint64"
    rows = t.to_pylist()
    assert all(r["metric"] in ("reaction", "freshness") for r in rows)
    # Simulated against the bounds: never above the one that holds.
    assert sum(r["observed_over_bound"] for r in rows) == 0
    for r in rows:
        if r["observed_max_ns"] is not None and r["sound_ns"] is not None:
            assert r["observed_max_ns"] <= r["sound_ns"]
        assert r["paper_ns"] is not None


def load_recipe():
    spec = importlib.util.spec_from_file_location("ray_campaign", RECIPE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["ray_campaign"] = module
    spec.loader.exec_module(module)
    return module


def test_ray_writes_what_one_machine_writes(tmp_path):
    ray = pytest.importorskip("ray")
    config = small_config(tmp_path)
    rtpipe.campaign(config, tmp_path / "one")
    recipe = load_recipe()
    try:
        r = recipe.run(config, tmp_path / "ray", workers=2)
        assert (r["written"], r["systems"], r["workers"]) == (6, 120, 2)
        assert shard_bytes(tmp_path / "ray") == shard_bytes(tmp_path / "one")
        # Resumed: a lost shard is run again, the others are kept.
        (tmp_path / "ray" / "shard-000003.parquet").unlink()
        r = recipe.run(config, tmp_path / "ray", workers=2)
        assert (r["written"], r["skipped"]) == (1, 5)
        assert shard_bytes(tmp_path / "ray") == shard_bytes(tmp_path / "one")
    finally:
        ray.shutdown()


def test_ray_refuses_another_campaigns_directory(tmp_path):
    pytest.importorskip("ray")
    config = small_config(tmp_path)
    rtpipe.campaign(config, tmp_path / "out")
    kept = (tmp_path / "out" / "_campaign.parquet").read_bytes()
    shards = shard_bytes(tmp_path / "out")
    other = tmp_path / "other.toml"
    other.write_text(config.read_text().replace("seed = 0", "seed = 1"))
    with pytest.raises(rtpipe.InputError, match="another campaign"):
        rtpipe.campaign(other, tmp_path / "out", plan=True)
    with pytest.raises(rtpipe.InputError, match="another campaign"):
        load_recipe().run(other, tmp_path / "out", workers=1)
    assert (tmp_path / "out" / "_campaign.parquet").read_bytes() == kept
    assert shard_bytes(tmp_path / "out") == shards


def test_the_e2e_figure_is_regenerated(tmp_path):
    pytest.importorskip("matplotlib")
    spec = importlib.util.spec_from_file_location(
        "e2e_figure", ROOT / "crates" / "python" / "examples" / "e2e_figure.py"
    )
    fig = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fig)
    text = (ROOT / "examples" / "campaigns" / "e2e-figure.toml").read_text()
    config = tmp_path / "e.toml"
    config.write_text(text.replace("systems = 1000", "systems = 30").replace("shard_size = 250", "shard_size = 15"))
    assert fig.main([str(config), str(tmp_path / "out"), str(tmp_path / "f.svg")]) == 0
    assert (tmp_path / "f.svg").read_text().lstrip().startswith("<?xml")
    red = fig.reductions(fig.run(config, tmp_path / "out"))
    for metric in ("reaction", "freshness"):
        by = {label.split("\n")[0]: v for label, v in red[metric].items()}
        sound, guenzel, duerr = by["rtpipe sound"], by["Günzel et al. '23"], by["Dürr et al. '19"]
        known = by["Kloda et al. '18" if metric == "reaction" else "rtpipe, known offsets"]
        assert len(sound) > 100
        # No bound above Davare's (D07, the one baseline of both panels),
        # the known offsets never loosen one, and no bound is below the
        # WCET schedule's exact figure (Günzel et al.'s).
        assert (sound >= -1e-12).all() and (duerr >= -1e-12).all()
        assert (known >= sound - 1e-12).all()
        assert (guenzel >= known - 1e-12).all()
    assert "| maximum reduced data age | rtpipe sound |" in fig.summary(red)
    assert "| maximum reaction time (= maximum data age) | Kloda et al. '18 (rtpipe, known offsets) |" in fig.summary(red)
