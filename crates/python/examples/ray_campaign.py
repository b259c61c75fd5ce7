"""An rtpipe campaign across a Ray cluster.

One Ray task per shard: each runs ``rtpipe.campaign(config, tmp, shard=(k,
shards), jobs=1)`` in a scratch directory of its own node and returns the
shard's Parquet bytes; the driver writes them into OUTDIR. No shared file
system is needed, shards already in OUTDIR are skipped (resumable: only
complete shards of this campaign count, as ``rtpipe campaign`` counts them),
a directory of another campaign is refused, and the files are byte for byte
those one machine writes (``rtpipe campaign CONFIG OUTDIR``): a shard is a
function of the configuration alone.

    python ray_campaign.py CONFIG OUTDIR                 # a local cluster, every core
    python ray_campaign.py CONFIG OUTDIR --workers 4     # a local cluster of 4 workers
    python ray_campaign.py CONFIG OUTDIR --address auto  # an existing cluster (`ray start`)
    python ray_campaign.py CONFIG OUTDIR --address auto --wheel rtpipe-*.whl

Every node needs rtpipe: installed beforehand (``pip install
rtpipe-*.whl``), or, with ``--wheel``, shipped by Ray: the driver uploads
the wheel to the cluster and each node installs it into the job's runtime
environment (``runtime_env={"py_modules": [wheel]}``) before its first
shard. docs/guide/clusters.md has the recipe for a multi-node cluster.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import ray

import rtpipe


@ray.remote(num_cpus=1)  # type: ignore[untyped-decorator,unused-ignore]
def run_shard(config_text: str, k: int, shards: int) -> dict[str, Any]:
    """Shard k of the campaign, on whichever node Ray picks: its file's
    bytes, by name."""
    with tempfile.TemporaryDirectory(prefix="rtpipe-shard-") as tmp:
        config = Path(tmp) / "campaign.toml"
        config.write_text(config_text)
        out = Path(tmp) / "out"
        report = rtpipe.campaign(config, out, shard=(k, shards), jobs=1)
        files = {p.name: p.read_bytes() for p in out.glob("shard-*.parquet")}
    return {"files": files, "systems": report["systems_run"], "seconds": report["seconds"]}


def write_atomically(path: Path, data: bytes) -> None:
    """`path` whole or not at all: a fresh temporary beside it, created
    exclusively (never through a planted link, never over a file), renamed
    into place."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def run(
    config: Path,
    out: Path,
    workers: int | None = None,
    address: str | None = None,
    wheel: Path | None = None,
) -> dict[str, Any]:
    """Runs every shard `out` lacks on the cluster; returns what was done.
    A directory of another campaign is refused (``rtpipe.InputError``)
    before anything is written, as ``rtpipe campaign`` refuses it; a shard
    file that is not a complete shard of this campaign is run again."""
    # The plan checks `out` as a run does: its `_campaign.parquet` and
    # every shard's footer must be this campaign's, else it raises.
    plan = rtpipe.campaign(config, out, plan=True)
    done = set(plan["written"])
    missing = [k for k in range(plan["shards"]) if k not in done]
    # A part that owns no shard (index = shards) runs nothing: rtpipe
    # creates `out` and writes its `_campaign.parquet`, as any run does.
    rtpipe.campaign(config, out, shard=(plan["shards"], plan["shards"] + 1), jobs=1)
    if not ray.is_initialized():
        # A wheel in py_modules is uploaded once and pip-installed on each
        # node that runs a shard; without it the nodes' own rtpipe is used.
        runtime_env = {"py_modules": [str(wheel)]} if wheel else None
        # Without an address, a cluster of its own ("local"): Ray would
        # otherwise join the machine's latest `ray start` cluster, anyone's.
        ray.init(address=address or "local", num_cpus=workers, include_dashboard=False,
                 log_to_driver=False, runtime_env=runtime_env)
    # Timed from here: the cluster's start is not the campaign's work.
    started = time.monotonic()
    text = config.read_text()
    pending = [run_shard.remote(text, k, plan["shards"]) for k in missing]
    systems = 0
    while pending:
        ready, pending = ray.wait(pending, num_returns=1)
        result: dict[str, Any] = ray.get(ready[0])
        for name, data in result["files"].items():
            write_atomically(out / name, data)
        systems += result["systems"]
    seconds = time.monotonic() - started
    cpus = ray.cluster_resources()  # type: ignore[no-untyped-call,unused-ignore]
    return {
        "shards": plan["shards"],
        "written": len(missing),
        "skipped": plan["shards"] - len(missing),
        "systems": systems,
        "seconds": seconds,
        "workers": int(cpus.get("CPU", 0)),
    }


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("config", type=Path)
    p.add_argument("out", type=Path)
    p.add_argument("--workers", type=int, help="CPUs of a local cluster [every core]")
    p.add_argument("--address", help="an existing cluster's address (e.g. auto)")
    p.add_argument("--wheel", type=Path, help="an rtpipe wheel for Ray to install on every node")
    a = p.parse_args(argv)
    r = run(a.config, a.out, a.workers, a.address, a.wheel)
    print(f"{r['written']} shard(s) written ({r['skipped']} already there), "
          f"{r['systems']} systems in {r['seconds']:.2f} s on {r['workers']} worker(s): "
          f"{r['systems'] / max(r['seconds'], 1e-9):.0f} systems/s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
