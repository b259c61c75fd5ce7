"""A typed tour of rtpipe from Python: load a spec, analyse it, read a
chain's bounds as attributes, simulate it, and hand the tables to pandas.
``mypy --strict`` accepts it (crates/python/tests/test_typing.py checks).

    python tour.py [SPEC]   # default: examples/paper-table3.toml
"""

from __future__ import annotations

import sys
from pathlib import Path

import rtpipe
from rtpipe.reports import AnalysisReport, ObsChain, SimulationReport

SPEC = Path(__file__).resolve().parents[3] / "examples" / "paper-table3.toml"


def bounds(report: AnalysisReport) -> list[str]:
    """One line per chain and metric: its sound bound against its limit."""
    unit = report.time_unit
    lines = []
    for chain in report.chains:
        limit = "no limit" if chain.limit is None else f"limit {chain.limit:g} {unit}"
        lines.append(f"{chain.name or '-'} {chain.metric}: sound {chain.sound} {unit} ({limit})")
    return lines


def tightest(report: SimulationReport) -> ObsChain | None:
    """The chain whose largest observed latency comes nearest its sound
    bound (None when no chain has both)."""
    best: tuple[float, ObsChain] | None = None
    for chain in report.chains:
        seen, sound = chain.observed.max, chain.sound
        if seen is not None and sound:
            ratio = seen / sound
            if best is None or ratio > best[0]:
                best = (ratio, chain)
    return None if best is None else best[1]


def main(spec: Path) -> int:
    system = rtpipe.load(spec)
    try:
        report = system.analyze()
    except rtpipe.SpecError as e:
        print(f"{e.file}:{e.line}:{e.column}: {e.key}: {e.fix}", file=sys.stderr)
        return 2
    print(f"{report.system}: schedulable {report.schedulability.schedulable}, ok {report.ok}")
    print("\n".join(bounds(report)))
    chains = report.to_pandas("chains")
    print(chains[["chain", "metric", "sound"]].to_string(index=False))
    run = system.simulate(outputs=200, samples=True)
    near = tightest(run)
    if near is not None:
        print(f"tightest: {near.name or '-'} {near.metric}")
    if run.samples is not None:
        reaction = run.samples["reaction_ns"]
        print(f"{len(reaction)} samples, largest reaction {reaction.max()} ns")
    return run.exit_status


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else SPEC))
