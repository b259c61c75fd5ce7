#!/usr/bin/env python3
"""Sinha & West's pipeline benchmark as rtpipe design problems, and the
acceptance count of `rtpipe design` on them.

Sinha and West, "End-to-end Scheduling of Real-time Task Pipelines on
Multiprocessors" (artifact: github.com/sohamm17/pipe_schedule). Their
uniprocessor data sets are pickles: a list of task sets, each a list of
(budget, period) pairs; only the budgets (WCETs) are used, the periods are
what is designed. A pipeline t0 -> t1 -> ... -> t(n-1) on one CPU, rate
monotonic, judged by the Liu-Layland bound, with an end-to-end delay bound
of int(sum(budgets) * LBG) (their `e2e_delay_threshold`; for the WATERS
sets LBG = n * NLBG). docs/design.md, "Sinha & West's benchmark", gives the
mapping and where the models differ.

  convert  the first --count task sets of a pickle at one LBG, as specs
  run      `rtpipe design` on a folder of specs: per spec its status,
           seconds, objective and gap, one line each, then the count

Usage:
  python3 scripts/sinha-west.py convert --lbg 11 --count 100 dataset_0.75_10 OUTDIR
  python3 scripts/sinha-west.py run --rtpipe target/release/rtpipe OUTDIR
"""

import argparse
import glob
import json
import os
import pickle
import subprocess
import time


def spec_text(name, budgets, lbg):
    """One pipeline as an rtpipe spec (times in the data set's units,
    written as µs: only ratios matter to the problem)."""
    limit = int(sum(budgets) * lbg)
    lines = [
        f"# Sinha & West task set {name}: budgets {budgets}, LBG {lbg}",
        "[system]",
        f'name = "{name}"',
        'time_unit = "us"',
        'scheduler = "rm"',
        'schedulability = "liu-layland"',
        "",
        "[channels.mem]",
        "bandwidth = 1",
        'overhead = "0us"',
        "",
    ]
    for i, c in enumerate(budgets):
        lines.append(f"[tasks.t{i}]")
        lines.append(f"exec = {c}")
        if i > 0:
            lines.append(f'reads = ["t{i - 1}"]')
        lines.append('output = { channel = "mem", size = 0 }')
        # No period: free from C up to the delay bound (rtpipe's default
        # top, the largest chain limit), which every design meets anyway;
        # GEKKO's top, 20000 C, lies above it.
        lines.append("")
    lines.append("[[chain]]")
    lines.append("path = [" + ", ".join(f'"t{i}"' for i in range(len(budgets))) + "]")
    lines.append(f"max_reaction_time = {limit}")
    return "\n".join(lines) + "\n"


def convert(args):
    with open(args.dataset, "rb") as f:
        sets = pickle.load(f)
    os.makedirs(args.outdir, exist_ok=True)
    base = os.path.basename(args.dataset)
    for k, s in enumerate(sets[: args.count]):
        budgets = [int(b) for b, _ in s]
        name = f"{base}-lbg{args.lbg:g}-{k:04d}"
        with open(os.path.join(args.outdir, name + ".toml"), "w") as f:
            f.write(spec_text(name, budgets, args.lbg))


def run(args):
    accepted = 0
    files = sorted(glob.glob(os.path.join(args.folder, "*.toml")))
    times = []
    for path in files:
        cmd = [args.rtpipe, "design", "--mode", args.mode, "--json", path]
        if args.time_limit:
            cmd[2:2] = ["--time-limit", str(args.time_limit)]
        t0 = time.monotonic()
        out = subprocess.run(cmd, capture_output=True, text=True)
        dt = time.monotonic() - t0
        try:
            d = json.loads(out.stdout)["design"]
        except (ValueError, KeyError):
            print(os.path.basename(path), "error", out.stderr.strip().splitlines()[:1])
            continue
        ok = d["status"] in ("optimal", "feasible")
        accepted += ok
        first = d.get("first_design_seconds")
        if ok and first is not None:
            times.append(first)
        gap = d.get("gap")
        print(os.path.basename(path), d["status"], f"{dt:.3f}s", f"first {first}", d.get("objective"),
              None if gap is None else round(gap, 4), flush=True)
    mean = sum(times) / len(times) if times else 0.0
    worst = max(times) if times else 0.0
    print(f"accepted {accepted}/{len(files)}; time to the first verified design: "
          f"mean {1000 * mean:.0f} ms, worst {1000 * worst:.0f} ms")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("convert")
    c.add_argument("--lbg", type=float, required=True,
                   help="LBG; for the WATERS sets (watersdata_n), n x NLBG")
    c.add_argument("--count", type=int, default=1000)
    c.add_argument("dataset")
    c.add_argument("outdir")
    r = sub.add_parser("run")
    r.add_argument("--rtpipe", default="target/release/rtpipe")
    r.add_argument("--mode", default="sound", choices=["sound", "paper"])
    r.add_argument("--time-limit", type=float)
    r.add_argument("folder")
    args = ap.parse_args()
    if args.cmd == "convert":
        convert(args)
    else:
        run(args)


if __name__ == "__main__":
    main()
