#!/bin/bash
# The timing margins of four designs of Cleanflight side by side
# (docs/flight.md, "The margins of Table V, the loop design and the --fly
# answer"): Table V, the sweep -> design loop's answer and `design --fly`'s
# answer, and `design --objective margin --max-utilization 0.7`'s on the
# flown limits, each put into four specs that differ only in their limits, and
# `rtpipe analyze --margins --json` run on each. Prints per design and
# limits the critical scaling factor (every exec x the factor keeps every
# limit and the schedulability test; "fails" when the design already breaks
# a limit) and the least exec margin in % of its exec, with its task.
# It builds nothing, so build first: cargo build --release -p rtpipe.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${RTPIPE:-${CARGO_TARGET_DIR:-target}/release/rtpipe}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# racer5's sweep limits, as "The loop: sweep -> design -> fly" derives them.
"$B" fly examples/cleanflight.toml --sweep --resolution 0 \
  --write-limits "$TMP/racer5-limits.toml" --free-periods > /dev/null

# $1 with the guaranteed periods (us) of design $3 written to $2; with
# "none" as $4 its chains and max_periods are dropped (schedulability alone).
put() {
  python3 - "$@" <<'PY'
import re, sys
src_path, out, design, limits = sys.argv[1:5]
periods = {
    "table-v": [1000, 1000, 5000, 10000, 2000, 5000],
    "loop": [1587, 1587, 7937, 15874, 3174, 7937],
    "fly": [1114, 1114, 5386, 9024, 2012, 5488],
    "margin": [1114, 1114, 2114, 2971, 2114, 5570],
}[design]
src = open(src_path).read()
for task, period in zip(["gyro", "accl", "ahrs", "radio", "pid", "pwm"], periods):
    block = re.search(r"\[tasks\.%s\]\n(.*?)(?=\n\[)" % task, src, re.S)
    body = re.sub(r"period = (\{[^}]*\}|\"?\d+(us)?\"?)", 'period = "%dus"' % period, block.group(1), count=1)
    src = src[:block.start(1)] + body + src[block.end(1):]
if limits == "none":
    src = src[: src.find("[[chain]]")] if "[[chain]]" in src else src
    src = re.sub(r"\nmax_period = .*", "", src)
open(out, "w").write(src)
PY
}

# One row: the margins of design $1 under the limits of spec $3 (named $2).
row() {
  local design=$1 name=$2 spec=$3 drop=${4:-keep}
  put "$spec" "$TMP/spec.toml" "$design" "$drop"
  # Exit 1 is a verdict that fails (the margins are still printed).
  "$B" analyze "$TMP/spec.toml" --margins --json > "$TMP/margins.json" 2> /dev/null || [ $? -eq 1 ]
  python3 -c '
import json, sys
design, name = sys.argv[1:3]
m = json.load(sys.stdin)["margins"]
system = [s for s in m["scaling"] if s["cpu"] is None][0]
factor = "%.6f" % system["factor"] if system["factor"] is not None else "fails"
execs = [e for e in m["exec"] if e["margin_percent"] is not None]
least = min(execs, key=lambda e: e["margin_percent"], default=None)
least = "%+.1f %% (%s)" % (least["margin_percent"], least["task"]) if least else "none"
print("%-8s %-22s %9s  %-16s %s" % (design, name, factor, least, system["limited_by"]))
' "$design" "$name" < "$TMP/margins.json"
}

printf "%-8s %-22s %9s  %-16s %s\n" design limits factor "least exec" "limited by"
for d in table-v loop fly margin; do
  row "$d" "schedulability alone" examples/cleanflight.toml none
  row "$d" "paper (Table II)" examples/cleanflight.toml
  row "$d" "racer5 sweep" "$TMP/racer5-limits.toml"
  row "$d" "both vehicles, flown" examples/cleanflight-design-flown.toml
done
