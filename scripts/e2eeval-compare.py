#!/usr/bin/env python3
"""rtpipe's literature-named quantities against E2EEvaluation's own analyses,
on task sets E2EEvaluation's own WATERS generator draws.

Two subcommands:

  generate  run E2EEvaluation (TU Dortmund, Günzel et al.; its source at
            --e2eeval, in a venv with numpy < 2) end to end, as its
            `e2eMain.py generate-cecs` and `analyze-cecs
            --raw_analysis_results` do: one or more WATERS task sets at
            --util, automotive cause-effect chains, then its analyses of
            them; writes OUT/cause_effect_chains.yaml (its export) and
            OUT/results.csv (its results, in ms, one row per chain);
  compare   import that YAML with `rtpipe import e2eeval`, analyse and
            simulate it (every task released at 0 with its WCET, the one
            schedule Günzel et al.'s schedule-based analyses see when
            BCET = WCET), and print, per quantity that carries a literature
            name, the largest difference between rtpipe's figure and
            E2EEvaluation's (docs/analysis.md, "What each reported number
            is").

The fixtures `crates/cli/tests/data/e2eeval-util*.yaml` and their
`*-results.csv` were made with `generate` (the commands are in
crates/cli/tests/data/README.md); `crates/cli/tests/e2eeval_real.rs` holds
rtpipe to them.

  python3 scripts/e2eeval-compare.py generate --e2eeval DIR --util 0.8 \\
      --chains 8 --seed 7 OUT/
  python3 scripts/e2eeval-compare.py compare --rtpipe target/release/rtpipe OUT/
"""

import argparse
import csv
import json
import random
import subprocess
import sys
import tempfile
import types
from pathlib import Path

# E2EEvaluation's analyses run here (framework.analysesDict's keys), local
# chains on one ECU.
ANALYSES = [
    "davare07",
    "duerr19_mrt",
    "duerr19_mrda",
    "kloda18",
    "becker17_RESPONSE_TIMES",
    "becker17_NO_INFORMATION",
    "guenzel23_local_mrt",
    "guenzel23_local_mrda",
    "guenzel23_local_mda",
]


def generate(args):
    """E2EEvaluation's `run_evaluation`, as its console interface calls it."""
    sys.path.insert(0, str(Path(args.e2eeval).resolve()))
    # Its plotting module needs matplotlib and tikzplotlib; nothing here plots.
    sys.modules["plotting.plot"] = types.ModuleType("plotting.plot")
    import framework

    out = str(Path(args.out).resolve()) + "/"
    Path(out).mkdir(parents=True, exist_ok=True)
    # E2EEvaluation draws its per-task-set seeds from Python's `random`.
    random.seed(args.seed)
    general = dict(framework.default_general_params)
    general.update(generate_cecs=True, store_generated_cecs=True, number_of_threads=1)
    tasksets = dict(framework.default_taskset_generation_params)
    tasksets.update(
        use_automotive_taskset_generation=True,
        target_util=args.util,
        number_of_tasksets=args.tasksets,
    )
    cecs = dict(framework.default_cec_generation_params)
    cecs.update(
        generate_automotive_cecs=True,
        min_number_of_chains=args.chains,
        max_number_of_chains=args.chains,
    )
    output = dict(framework.default_output_params)
    output.update(raw_analysis_results=True, output_dir=out)
    methods = [framework.analysesDict[a] for a in ANALYSES]
    framework.run_evaluation(general, tasksets, cecs, methods, [], output)
    for name in ("cause_effect_chains.yaml", "results.csv"):
        print(out + name)
    return 0


def results(path):
    """E2EEvaluation's results.csv: {short name: [ms per chain]}."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    return {h: [float(r[k]) for r in body] for k, h in enumerate(head)}


def run_json(cmd):
    o = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(o.stdout)


# (rtpipe figure, E2EEvaluation column): the pairs that name the same
# quantity (docs/analysis.md, "What each reported number is"). `analyze`
# figures are bounds by the peer's formula; `simulate` figures are measured
# on the schedule Günzel et al. analyse exactly.
PAIRS = [
    ("analyze: reaction from_event.davare", "D07"),
    ("analyze: literature.max_reaction_time.duerr", "D19(MRT)"),
    ("analyze: literature.max_data_age.duerr", "D19(MRT)"),
    ("analyze: literature.max_reduced_data_age.duerr", "D19(MRDA)"),
    ("analyze: reaction known_offsets.from_event.sound", "K18"),
    ("simulate: max reaction time (reaction observed_from_event.max)", "G23(L-MRT)"),
    ("simulate: max data age (reaction observed_from_event.max)", "G23(L-MDA)"),
    ("simulate: max reduced data age (freshness observed.max)", "G23(L-MRDA)"),
]

# (rtpipe's sound bound, Günzel et al.'s exact figure): each must hold.
SOUND = [
    ("analyze: literature.max_reaction_time.sound", "G23(L-MRT)"),
    ("analyze: literature.max_data_age.sound", "G23(L-MDA)"),
    ("analyze: literature.max_reduced_data_age.sound", "G23(L-MRDA)"),
]


def chains(v, metric):
    return [c for c in v["chains"] if c["metric"] == metric]


def ours(analyze, simulate):
    """rtpipe's figure of each pair, per chain (ms)."""
    ar, af = chains(analyze, "reaction"), chains(analyze, "freshness")
    sr, sf = chains(simulate, "reaction"), chains(simulate, "freshness")
    lit = lambda cs, name, bound: [c["literature"][name][bound] for c in cs]
    return [
        [c["from_event"]["davare"] for c in ar],
        lit(ar, "max_reaction_time", "duerr"),
        lit(ar, "max_data_age", "duerr"),
        lit(af, "max_reduced_data_age", "duerr"),
        [c["known_offsets"]["from_event"]["sound"] for c in ar],
        [c["observed_from_event"]["max"] for c in sr],
        [c["observed_from_event"]["max"] for c in sr],
        [c["observed"]["max"] for c in sf],
    ], [
        lit(ar, "max_reaction_time", "sound"),
        lit(ar, "max_data_age", "sound"),
        lit(af, "max_reduced_data_age", "sound"),
    ]


def compare(args):
    out = Path(args.out)
    theirs = results(out / "results.csv")
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(
            [args.rtpipe, "import", "e2eeval", str(out / "cause_effect_chains.yaml"), tmp],
            check=True,
            capture_output=True,
        )
        (spec,) = sorted(Path(tmp).glob("*.toml"))
        analyze = run_json([args.rtpipe, "analyze", str(spec), "--json"])
        simulate = run_json(
            [args.rtpipe, "simulate", str(spec), "--duration", args.duration, "--json"]
        )
    same, sound = ours(analyze, simulate)
    worst, below = 0.0, 0
    print("| rtpipe | E2EEvaluation | chains | largest difference (ms) |")
    print("|---|---|---|---|")
    for (name, col), mine in zip(PAIRS, same):
        assert len(mine) == len(theirs[col]), (name, len(mine), len(theirs[col]))
        diffs = [abs(a - b) for a, b in zip(mine, theirs[col])]
        worst = max(worst, max(diffs))
        print(f"| {name} | {col} | {len(diffs)} | {max(diffs):.6f} |")
    print()
    print("| rtpipe's sound bound | Günzel et al.'s exact figure | chains below it | median ratio |")
    print("|---|---|---|---|")
    for (name, col), mine in zip(SOUND, sound):
        n = sum(a < b - 0.001 for a, b in zip(mine, theirs[col]))
        ratios = sorted(b / a for a, b in zip(mine, theirs[col]) if a > 0)
        below += n
        print(f"| {name} | {col} | {n} | {ratios[len(ratios) // 2]:.3f} |")
    # rtpipe rounds each WCET up to a whole ns (tests/e2eeval_real.rs).
    return 0 if worst < 0.001 and below == 0 else 1


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate")
    g.add_argument("--e2eeval", required=True, help="E2EEvaluation's checkout")
    g.add_argument("--util", type=float, default=0.5, help="utilisation per task set")
    g.add_argument("--tasksets", type=int, default=1)
    g.add_argument("--chains", type=int, default=10, help="chains per task set")
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("out")
    c = sub.add_parser("compare")
    c.add_argument("--rtpipe", default="target/release/rtpipe")
    c.add_argument("--duration", default="10s", help="simulated time (several hyperperiods)")
    c.add_argument("out")
    a = p.parse_args()
    return generate(a) if a.cmd == "generate" else compare(a)


if __name__ == "__main__":
    sys.exit(main())
