# %% [markdown]
# # Two figures, end to end, from Python
#
# A notebook in the percent format (`# %%` cells: VS Code, PyCharm,
# Spyder and Jupytext open it as a notebook; `python notebook.py` runs it
# top to bottom). It reproduces
#
# 1. **the paper's Fig. 9** (Cheng, West, Einstein, EMSOFT 2018): the
#    observed reaction and freshness times of pipelines P1 and P2 of Table
#    III after 100,000 outputs of τ5 and τ7, against the predicted bounds;
# 2. **E2EEvaluation's local-chain comparison** (Günzel et al., RTAS
#    2021): the reduction of each end-to-end bound relative to Davare et
#    al.'s on WATERS task sets, as box plots, through `e2e_figure.py`.
#
# Run from the repository root with the wheel installed. The sizes come
# from the environment so that a test can run the notebook small:
# `NOTEBOOK_OUTPUTS` (outputs of the slowest sink, 100000 as in the
# paper), `NOTEBOOK_SYSTEMS` (task sets of the comparison, 1000) and
# `NOTEBOOK_OUT` (where the campaign and the PNGs go, `notebook-out`).

# %%
import os
import sys
from pathlib import Path

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import rtpipe

# The examples' folder: e2e_figure.py is imported from there.
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path("crates/python/examples")
ROOT = HERE.parents[2]
sys.path.insert(0, str(HERE))
import e2e_figure  # noqa: E402

OUTPUTS = int(os.environ.get("NOTEBOOK_OUTPUTS", "100000"))
SYSTEMS = int(os.environ.get("NOTEBOOK_SYSTEMS", "1000"))
OUT = Path(os.environ.get("NOTEBOOK_OUT", "notebook-out"))
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## 1. Fig. 9: observed against predicted, Table III's system
#
# `paper-table3-loaded.toml` is Table III with the paper's background
# load. Random release offsets and execution times uniform up to each
# task's WCET (seed 1), until the slowest sink has published `OUTPUTS`
# outputs; `samples=True` returns one row per sample of each chain's head
# as numpy columns.

# %%
system = rtpipe.load(ROOT / "examples" / "paper-table3-loaded.toml")
run = system.simulate(outputs=OUTPUTS, phasing="random", exec="uniform", seed=1, samples=True)
samples = run["samples"]
METRICS = ("reaction", "freshness")


def observed_ms(chain: int, metric: str) -> np.ndarray:
    """The chain's observed times from the head's read, in ms (the
    samples' cells are ns; a sample without an output is masked)."""
    values = np.ma.masked_invalid(samples[f"{metric}_ns"][samples["chain"] == chain])
    return np.ma.compressed(values) / 1e6


# Each chain's bounds, by name and metric (the report's `paper` and
# `sound`, in the spec's unit, ms).
bounds = {(c["name"], c["metric"]): c for c in run["chains"]}
rows = []
for i, name in enumerate(system.chains):
    for metric in METRICS:
        seen = observed_ms(i, metric)
        b = bounds[(name, metric)]
        rows.append((name, metric, len(seen), seen.max(), b["paper"], b["sound"]))
print("| chain | metric | samples | observed max | paper | sound | max/sound |")
print("|---|---|---|---|---|---|---|")
for name, metric, n, worst, paper, sound in rows:
    print(f"| {name} | {metric} | {n} | {worst:.1f} | {paper:g} | {sound:g} | {worst / sound:.3f} |")

# %%
fig, axes = plt.subplots(len(system.chains), 2, figsize=(10, 6), squeeze=False)
for i, name in enumerate(system.chains):
    for j, metric in enumerate(METRICS):
        ax, b = axes[i][j], bounds[(name, metric)]
        ax.hist(observed_ms(i, metric), bins=60, color="tab:blue", alpha=0.8, label="observed")
        ax.axvline(b["paper"], color="tab:orange", ls="--", label=f"paper {b['paper']:g}")
        ax.axvline(b["sound"], color="tab:red", label=f"sound {b['sound']:g}")
        ax.set_title(f"{name} {metric}")
        ax.set_xlabel("end-to-end time (ms)")
        ax.legend(fontsize=7)
fig.suptitle(f"Fig. 9: observed vs. predicted, Table III ({OUTPUTS} outputs, random offsets)")
fig.tight_layout()
fig9_png = OUT / "fig9.png"
fig.savefig(fig9_png, dpi=100)
print("wrote", fig9_png)

# %% [markdown]
# ## 2. E2EEvaluation's comparison on WATERS task sets
#
# `e2e-figure.toml` is the comparison's task sets (WATERS 2015 runnables,
# one CPU, 50–90 % utilisation, synchronous release) as a campaign; the
# campaign folder is Parquet only, so any DataFrame library reads it (here
# pyarrow, through `e2e_figure.run`; `polars.read_parquet(folder)` and
# `pandas.read_parquet(folder)` read the same rows). A folder that already
# holds the campaign is not run again.

# %%
text = (ROOT / "examples" / "campaigns" / "e2e-figure.toml").read_text()
shard_size = max(1, min(250, SYSTEMS // 2))
config = OUT / "e2e-figure.toml"
config.write_text(
    text.replace("systems = 1000", f"systems = {SYSTEMS}").replace(
        "shard_size = 250", f"shard_size = {shard_size}"
    )
)
table = e2e_figure.run(config, OUT / "e2e-campaign")
reductions = e2e_figure.reductions(table)
print(e2e_figure.summary(reductions))

# %%
e2e_png = OUT / "e2e.png"
e2e_figure.plot(reductions, str(e2e_png))
print("wrote", e2e_png)
