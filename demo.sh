#!/usr/bin/env bash
# The demo: analyse the paper's examples, design two (Cleanflight in both
# modes), fly one on Table V's schedule and one driven by the gyro (threads
# and data-triggered tasks). `rtpipe
# analyze` exits 1 when a limit fails (a finding, shown in the output) and 2
# on bad input (an error).
set -uo pipefail
cd "$(dirname "$0")"
cargo build --release -q -p rtpipe || exit 2
bin="${CARGO_TARGET_DIR:-target}/release/rtpipe"
status=0
for spec in examples/paper-table2.toml examples/cleanflight.toml examples/paper-table3.toml \
  examples/work-queues.toml; do
  echo "\$ rtpipe analyze $spec"
  "$bin" analyze "$spec"
  code=$?
  echo "(exit status $code)"
  echo
  [ "$code" -ge 2 ] && status=$code
done
echo "\$ rtpipe analyze examples/paper-table2.toml --all-paths  (worst path per source/sink pair)"
"$bin" analyze examples/paper-table2.toml --all-paths | sed -n '/all source-to-sink/,$p'
for run in "examples/table2-design.toml --mode paper" "examples/cleanflight-design.toml --mode paper" \
  "examples/cleanflight-design.toml --mode sound"; do
  echo
  echo "\$ rtpipe design $run"
  # shellcheck disable=SC2086 # the spec and its flags, split on purpose
  "$bin" design $run | sed -n '1,3p'
  code=${PIPESTATUS[0]}
  [ "$code" -ge 2 ] && status=$code
done
echo
echo "\$ rtpipe fly examples/cleanflight.toml  (the flight controller on Table V's schedule, flying a simulated quad)"
"$bin" fly examples/cleanflight.toml | sed -n '1,10p'
code=${PIPESTATUS[0]}
[ "$code" -ge 2 ] && status=$code
echo
echo "\$ rtpipe fly examples/cleanflight-triggered.toml  (the same loop driven by the gyro: AHRS, PID and motor output data-triggered)"
"$bin" fly examples/cleanflight-triggered.toml | sed -n '1,10p'
code=${PIPESTATUS[0]}
[ "$code" -ge 2 ] && status=$code
exit $status
