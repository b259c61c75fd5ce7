"""E2EEvaluation's local-chain comparison, regenerated with rtpipe.

TU Dortmund's E2EEvaluation framework (Günzel, Chen, Ueter, von der
Brüggen, Dürr, Chen: "Timing Analysis of Asynchronized Distributed
Cause-Effect Chains", RTAS 2021) compares end-to-end analyses of
cause-effect chains on WATERS 2015 task sets as the *reduction of each
analysis' bound relative to Davare et al.* (DAC 2007), ``1 - bound /
Davare``, in box plots, for the maximum reaction time and the maximum data
age of local chains. This script runs the same comparison on an rtpipe
campaign (WATERS task sets, synchronous release, one CPU) with, beside the
peers' analyses as rtpipe implements them (Dürr et al. CASES 2019), rtpipe's
sound bound (arbitrary phasing) and its bound under the known offsets
(every task released at 0, the setting of Kloda et al. 2018 and Becker et
al. 2017). All bounds are from the event, as the literature's are.

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

# (label, column): the baseline is Davare's.
ANALYSES = [
    ("Dürr et al. (CASES'19)", "event_duerr_ns"),
    ("rtpipe sound", "event_sound_ns"),
    ("rtpipe, known offsets", "event_offsets_ns"),
]
METRICS = [("reaction", "maximum reaction time"), ("freshness", "maximum data age")]


# {metric: {analysis: array of 1 - bound/Davare}}
Reductions = Dict[str, Dict[str, Any]]


def run(config: Path, out: Path) -> Any:
    """The campaign's table (its shards run if `out` lacks them)."""
    rtpipe.campaign(config, out)
    return pq.read_table(out)


def reductions(table: Any) -> Reductions:
    """{metric: {analysis: array of 1 - bound/Davare}} over the chains
    every analysis bounds (schedulable systems)."""
    out: Reductions = {}
    for metric, _ in METRICS:
        t = table.filter(pc.equal(table["metric"], metric))
        t = t.filter(t["schedulable"])
        davare = t["event_davare_ns"].to_numpy(zero_copy_only=False).astype(float)
        cols = {label: t[c].to_numpy(zero_copy_only=False).astype(float) for label, c in ANALYSES}
        keep = np.isfinite(davare) & (davare > 0)
        for v in cols.values():
            keep &= np.isfinite(v)
        out[metric] = {label: 1.0 - v[keep] / davare[keep] for label, v in cols.items()}
    return out


def summary(red: Reductions) -> str:
    """Median and quartiles of each reduction, as a table."""
    lines = ["| metric | analysis | chains | median | 25 % | 75 % |", "|---|---|---|---|---|---|"]
    for metric, name in METRICS:
        for label, v in red[metric].items():
            q1, med, q3 = np.percentile(v, [25, 50, 75])
            lines.append(f"| {name} | {label} | {len(v)} | {med:.3f} | {q1:.3f} | {q3:.3f} |")
    return "\n".join(lines)


def plot(red: Reductions, path: str) -> None:
    """Box plots as E2EEvaluation draws them: one panel per metric."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, (metric, name) in zip(axes, METRICS):
        labels = list(red[metric])
        ax.boxplot([red[metric][l] for l in labels], whis=(1, 99), showfliers=False)
        ax.set_xticks(range(1, len(labels) + 1), labels, rotation=15, fontsize=8)
        ax.set_title(name)
        ax.axhline(0, color="grey", lw=0.5)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("reduction relative to Davare et al.")
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
