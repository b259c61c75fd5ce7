"""E2EEvaluation's local-chain comparison, regenerated with rtpipe.

TU Dortmund's E2EEvaluation framework (Günzel, Chen, Ueter, von der
Brüggen, Dürr, Chen: "Timing Analysis of Asynchronized Distributed
Cause-Effect Chains", RTAS 2021) compares end-to-end analyses of
cause-effect chains on WATERS 2015 task sets in box plots of each
analysis' reduction relative to Davare et al. (DAC 2007): ``(D07 - bound)
/ D07`` (its ``AnalysisMethod.normalize``), where D07 is Davare's one
bound, the same baseline in both panels. The panels are the maximum
reaction time (which Günzel et al. 2023 prove equal to the maximum data
age) and the maximum reduced data age (from a sample's read to its last
output; docs/analysis.md, "What each reported number is"). This script runs
the comparison on an rtpipe campaign (WATERS task sets, synchronous
release, one CPU, each system simulated with every job at its WCET) with:

- Dürr et al. (CASES 2019): their Theorems 5.4 and 5.10 (D19(MRT),
  D19(MRDA));
- Kloda et al. (2018): rtpipe's bound under the known offsets (every task
  released at 0), which is Kloda's bound where BCET = WCET (K18; on
  E2EEvaluation's own task sets, tests/e2eeval_real.rs); the campaign's
  task sets have best cases below their worst, which rtpipe's bound uses
  and Kloda's does not;
- Günzel et al. (2023, local): the exact figures of the schedule with
  every job at its WCET, measured by the simulator (G23(L-MRT),
  G23(L-MRDA) where BCET = WCET);
- rtpipe's sound bound (any phasing).

Becker et al. (2017), which E2EEvaluation draws in the data-age panel, is
not drawn: rtpipe does not implement their analysis.

    python e2e_figure.py CONFIG OUTDIR FIGURE.svg

In a notebook: ``table = run(config, out)``, then ``reductions(table)`` and
``plot(reductions(table), "figure.svg")``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Dict

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq

import rtpipe

# The baseline: Davare's bound, reaction from the event (D07).
BASELINE = ("reaction", "event_davare_ns")

# Per panel: (metric, title, [(label, column)]). Reaction from the event is
# the maximum reaction time (= the maximum data age); freshness from the
# read is the maximum reduced data age.
PANELS = [
    (
        "reaction",
        "maximum reaction time (= maximum data age)",
        [
            ("Dürr et al. '19", "event_duerr_ns"),
            ("Kloda et al. '18\n(rtpipe, known offsets)", "event_offsets_ns"),
            ("Günzel et al. '23\n(WCET schedule)", "event_observed_max_ns"),
            ("rtpipe sound", "event_sound_ns"),
        ],
    ),
    (
        "freshness",
        "maximum reduced data age",
        [
            ("Dürr et al. '19", "duerr_ns"),
            ("rtpipe, known offsets", "offsets_ns"),
            ("Günzel et al. '23\n(WCET schedule)", "observed_max_ns"),
            ("rtpipe sound", "sound_ns"),
        ],
    ),
]


# {metric: {analysis: array of 1 - bound/Davare}}
Reductions = Dict[str, Dict[str, Any]]


def run(config: Path, out: Path) -> Any:
    """The campaign's table (its shards run if `out` lacks them)."""
    rtpipe.campaign(config, out)
    return pq.read_table(out)


def column(t: Any, name: str) -> Any:
    return t[name].to_numpy(zero_copy_only=False).astype(float)


def metric_rows(table: Any, metric: str) -> Any:
    """The rows of `metric` of the schedulable systems, ordered by
    (system, chain) so that both metrics' rows line up."""
    t = table.filter(pc.equal(table["metric"], metric))
    t = t.filter(t["schedulable"])
    return t.sort_by([("system", "ascending"), ("chain", "ascending")])


def reductions(table: Any) -> Reductions:
    """{metric: {analysis: array of (D07 - bound) / D07}} over the chains
    every analysis bounds, as E2EEvaluation normalises."""
    base = metric_rows(table, BASELINE[0])
    davare = column(base, BASELINE[1])
    keys = (column(base, "system"), column(base, "chain"))
    out: Reductions = {}
    for metric, _, analyses in PANELS:
        t = metric_rows(table, metric)
        assert (column(t, "system") == keys[0]).all() and (column(t, "chain") == keys[1]).all()
        cols = {label: column(t, c) for label, c in analyses}
        keep = np.isfinite(davare) & (davare > 0)
        for v in cols.values():
            keep &= np.isfinite(v)
        out[metric] = {label: (davare[keep] - v[keep]) / davare[keep] for label, v in cols.items()}
    return out


def summary(red: Reductions) -> str:
    """Median and quartiles of each reduction, as a table."""
    lines = ["| metric | analysis | chains | median | 25 % | 75 % |", "|---|---|---|---|---|---|"]
    for metric, name, _ in PANELS:
        for label, v in red[metric].items():
            q1, med, q3 = np.percentile(v, [25, 50, 75])
            label = label.replace("\n", " ")
            lines.append(f"| {name} | {label} | {len(v)} | {med:.3f} | {q1:.3f} | {q3:.3f} |")
    return "\n".join(lines)


def plot(red: Reductions, path: str) -> None:
    """Box plots as E2EEvaluation draws them: one panel per metric, the
    y-axis from 0 to 1."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, (metric, name, _) in zip(axes, PANELS):
        labels = list(red[metric])
        ax.boxplot([red[metric][l] for l in labels], whis=(1, 99), showfliers=False)
        ax.set_xticks(range(1, len(labels) + 1), labels, fontsize=7)
        ax.set_title(name)
        ax.set_ylim(-0.05, 1.0)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("reduction relative to Davare et al. (D07)")
    fig.tight_layout()
    fig.savefig(path)


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print(__doc__.split("\n\n")[-2].strip(), file=sys.stderr)
        return 2
    table = run(Path(argv[0]), Path(argv[1]))
    red = reductions(table)
    plot(red, argv[2])
    print(summary(red))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
