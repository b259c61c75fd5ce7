"""The cluster recipes of docs/guide/clusters.md, as far as one machine
can run them: the Slurm array script run by hand for every index, then
its merge, writes what one `rtpipe campaign` writes, byte for byte; the
Ray recipe on a local cluster of two nodes, with the wheel shipped through
Ray's runtime environment, does too."""

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

import rtpipe

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "crates" / "python" / "examples"


def small_config(tmp_path, systems=50, shard_size=10):
    text = (ROOT / "examples" / "campaigns" / "waters.toml").read_text()
    path = tmp_path / "c.toml"
    path.write_text(
        text.replace("systems = 2000", f"systems = {systems}")
        .replace("shard_size = 500", f"shard_size = {shard_size}")
        .replace('duration = "2s"', 'duration = "100ms"')
    )
    return path


def files(folder):
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir())}


def rtpipe_bin():
    found = os.environ.get("RTPIPE_BIN") or str(ROOT / "target" / "release" / "rtpipe")
    if not Path(found).is_file():
        pytest.skip("no rtpipe binary (test.sh sets RTPIPE_BIN)")
    return found


def slurm(script, *args, env=None):
    run = subprocess.run(
        ["bash", str(EXAMPLES / script), *map(str, args)],
        capture_output=True, text=True, env={**os.environ, "RTPIPE": rtpipe_bin(), **(env or {})},
    )
    return run


def test_the_slurm_array_writes_what_one_run_writes(tmp_path):
    config = small_config(tmp_path)
    one = tmp_path / "one"
    rtpipe.campaign(config, one)
    out = tmp_path / "out"
    count = 3
    for index in range(count):
        env = {"SLURM_ARRAY_TASK_ID": str(index), "SLURM_ARRAY_TASK_COUNT": str(count),
               "SLURM_ARRAY_TASK_MIN": "0", "SLURM_ARRAY_TASK_MAX": str(count - 1)}
        r = slurm("slurm_campaign.sbatch", config, out, env=env)
        assert r.returncode == 0, r.stderr
        assert (tmp_path / "out.parts" / str(index) / "_campaign.parquet").is_file()
    # Task 1 run again (a requeue): its part's shards are kept.
    r = slurm("slurm_campaign.sbatch", config, out, env={"SLURM_ARRAY_TASK_ID": "1", "SLURM_ARRAY_TASK_COUNT": "3"})
    assert r.returncode == 0 and "wrote 0 shard(s)" in r.stdout, r.stdout + r.stderr
    r = slurm("slurm_merge.sh", config, out)
    assert r.returncode == 0, r.stderr
    assert "wrote 0 shard(s)" in r.stdout and "(5 already there)" in r.stdout, r.stdout
    assert files(out) == files(one)
    assert not (tmp_path / "out.parts").exists()


def test_the_slurm_scripts_refuse_what_they_cannot_run(tmp_path):
    config = small_config(tmp_path)
    r = slurm("slurm_campaign.sbatch", config, tmp_path / "out", env={"SLURM_ARRAY_TASK_ID": ""})
    assert r.returncode != 0 and "array job" in r.stderr
    env = {"SLURM_ARRAY_TASK_ID": "1", "SLURM_ARRAY_TASK_COUNT": "2", "SLURM_ARRAY_TASK_MIN": "1",
           "SLURM_ARRAY_TASK_MAX": "2"}
    r = slurm("slurm_campaign.sbatch", config, tmp_path / "out", env=env)
    assert r.returncode == 2 and "contiguous from 0" in r.stderr
    # The merge into another campaign's folder: refused before anything moves.
    other = tmp_path / "other.toml"
    other.write_text(config.read_text().replace("seed = 0", "seed = 1"))
    rtpipe.campaign(other, tmp_path / "theirs")
    before = files(tmp_path / "theirs")
    env = {"SLURM_ARRAY_TASK_ID": "0", "SLURM_ARRAY_TASK_COUNT": "1"}
    assert slurm("slurm_campaign.sbatch", config, tmp_path / "theirs", env=env).returncode == 0
    r = slurm("slurm_merge.sh", config, tmp_path / "theirs")
    assert r.returncode == 2 and "another campaign" in r.stderr
    assert files(tmp_path / "theirs") == before
    assert len(list((tmp_path / "theirs.parts" / "0").glob("shard-*.parquet"))) == 5


def load_recipe():
    spec = importlib.util.spec_from_file_location("ray_campaign", EXAMPLES / "ray_campaign.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["ray_campaign"] = module
    spec.loader.exec_module(module)
    return module


def wheel():
    given = os.environ.get("RTPIPE_WHEEL")
    if given:
        return Path(given)
    found = sorted(ROOT.glob("target/wheels*/rtpipe-*.whl"), key=lambda p: p.stat().st_mtime)
    return found[-1] if found else None


def test_ray_on_a_two_node_cluster_ships_the_wheel(tmp_path, monkeypatch):
    pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    # The cluster's files, its address among them, in a directory of its
    # own: Ray's default (/tmp/ray) is the machine's, where any
    # `ray.init()` without an address would join this cluster. Short, for
    # the sockets' path limit.
    ray_tmp = Path(tempfile.mkdtemp(prefix="rt-", dir="/tmp"))
    monkeypatch.setenv("RAY_TMPDIR", str(ray_tmp))

    whl = wheel()
    if whl is None:
        pytest.skip("no wheel built (test.sh sets RTPIPE_WHEEL)")
    config = small_config(tmp_path, systems=40, shard_size=10)
    rtpipe.campaign(config, tmp_path / "one")
    # Two raylets on this machine: a head node and a worker node, one CPU
    # each, as `ray start --head` and `ray start --address` make them.
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    cluster.add_node(num_cpus=1)
    cluster.wait_for_nodes()
    recipe = load_recipe()
    import ray

    try:
        r = recipe.run(config, tmp_path / "ray", address=cluster.address, wheel=whl)
        assert (r["written"], r["systems"], r["workers"]) == (4, 40, 2)
        assert len(ray.nodes()) == 2
        assert files(tmp_path / "ray") == files(tmp_path / "one")
    finally:
        ray.shutdown()
        cluster.shutdown()
        shutil.rmtree(ray_tmp, ignore_errors=True)
