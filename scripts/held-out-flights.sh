#!/bin/bash
# The held-out flights of docs/flight.md ("Held-out missions"): each design
# below flown on racer5 and aero1kg over seeds 10-29 on three missions no
# design or sweep saw (examples/missions/). Prints one row per design and
# vehicle: flights that met their criteria / flown, per mission.
# Usage: [DESIGNS="table-v ..."] [PHASES=M] scripts/held-out-flights.sh [first_seed] [last_seed]
# (DESIGNS: the designs below to fly, by name; default all of them.
# PHASES: with M > 1, each design and vehicle gets a second row flown at M
# phase draws per seed (`fly --phase K`, the sweep's draws: every task's
# first release and the steps within the motor period), draw
# 1000 + M * seed + j for j < M: a draw of its own per flight, none of the
# draws 1..M-1 a sweep's --phases M flies; default 1, the nominal row alone.)
# Re-run after any change to the flight model; it builds nothing, so build
# first: cargo build --release -p rtpipe.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${RTPIPE:-${CARGO_TARGET_DIR:-target}/release/rtpipe}
FIRST=${1:-10}
LAST=${2:-29}
MISSIONS=${MISSIONS:-steps-turbulent aggressive-steps gusty-120s}
PHASES=${PHASES:-1}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# A design of examples/cleanflight.toml: Table V with some periods replaced
# (us), written to $TMP/NAME.toml.
design() {
  local name=$1; shift
  python3 - "$TMP/$name.toml" "$@" <<'PY'
import re, sys
out, pairs = sys.argv[1], sys.argv[2:]
src = open("examples/cleanflight.toml").read()
for pair in pairs:
    task, period = pair.split("=")
    block = re.search(r"\[tasks\.%s\]\n(.*?)(?=\n\[)" % task, src, re.S)
    body = re.sub(r"period = \d+", "period = %s" % period, block.group(1), count=1)
    src = src[:block.start(1)] + body + src[block.end(1):]
open(out, "w").write(src)
PY
}

# Table V's six guaranteed periods (us; the background tasks keep theirs)
# each x K, rounded to the microsecond: a point of the sweep's period scale.
scaled() {
  local name=$1 k=$2
  design "$name" $(python3 -c "
k = $k
for t, p in [('gyro', 1000), ('accl', 1000), ('ahrs', 5000), ('radio', 10000), ('pid', 2000), ('pwm', 5000)]:
    print('%s=%d' % (t, round(p * k)))")
}

design table-v
# design --fly's answer before the pass-rate rule (docs/flight.md).
design old-fly gyro=3959 accl=3959 ahrs=1840 radio=15754 pid=1964 pwm=44000
# 0.9 x racer5's refined sweep limits (fly --sweep, seed 0): every period
# x 0.9 x 1.948 (the last passing scale), and the PWM period alone at
# 0.9 x 8.39 x 5 ms.
design scale-0.9 gyro=1753 accl=1753 ahrs=8766 radio=17532 pid=3506 pwm=8766
design pwm-0.9 pwm=37755
# 0.9 x aero1kg's refined sweep limits (fly --vehicle aero1kg --sweep, seed
# 0, with the oscillation, effort and tracking criteria): every period x
# 0.9 x 3.226, and the PWM period alone at 0.9 x 56.946 ms.
design a-scale-0.9 gyro=2903 accl=2903 ahrs=14517 radio=29034 pid=5807 pwm=14517
design a-pwm-0.9 pwm=51251

# 0.9 x the limits of the sweep over both vehicles and both missions
# (fly --sweep --vehicle racer5,aero1kg --mission steps,gusty --seeds 3,
# seeds 0-2; racer5's gusty decides both): every period x 0.9 x 1.211
# (the last passing scale), and the PWM period alone at 0.9 x 13.213 ms.
scaled sg-scale-0.9 "0.9 * 1.211"
design sg-pwm-0.9 pwm=11892

# 0.9 x the limits the sweep that adds steps in light turbulence
# (--mission steps,gusty,examples/missions/sweep-steps-breeze.toml, the
# same vehicles and seeds) wrote while settling was judged on the plain
# +-5 % band: every period x 0.9 x 1.114, and the PWM period alone at
# 0.9 x 5.649 ms. (On the band widened by the hover's tracked error in
# turbulence, docs/flight.md, it writes the sg-* limits above.)
scaled sgb-scale-0.9 "0.9 * 1.114"
design sgb-pwm-0.9 pwm=5084

# 0.9 x the PWM limit of the same sweep over ten seeds judged by pass rate
# (--seeds 10 --pass-rate 0.9: of the 58 flights Table V's timing passes,
# a lower bound >= 0.9 at 95 % confidence; the period scale's limit stays
# 1.211, flown by sg-scale-0.9): the PWM period alone at 0.9 x 13.622 ms.
design pr-pwm-0.9 pwm=12260
# The PWM period alone at 0.5-0.8 x that limit, down towards Table V's 5 ms:
# a limit holds only if every shorter period holds too.
pwm_of() {
  local name=$1 limit_us=$2 k=$3
  design "$name" pwm=$(python3 -c "print(round($limit_us * $k))")
}
for k in 0.5 0.6 0.7 0.8; do pwm_of "pr-pwm-$k" 13622 "$k"; done

# 0.9 x the limits of the same sweep over ten seeds and four phase draws
# (--seeds 10 --phases 4 --pass-rate 0.9, 240 flights a timing): every
# period x 0.9 x 1.13, and the PWM period alone at 0.9 x 12.436 ms.
scaled p4-scale-0.9 "0.9 * 1.13"
pwm_of p4-pwm-0.9 12436 0.9

# 0.9 x the limits of the three-seed all-pass sweep of sg-* with the check
# below each limit (--seeds 3 --check-step 0.02: every period scale and
# motor period from x 1 up to each edge at steps of x 1.02): the scale's
# limit stays 1.211 (sg-scale-0.9), the PWM's comes down to 12.189 ms (a
# check at 12.43 ms fails aero1kg's breeze): the PWM alone at 0.9 x it.
pwm_of ck3-pwm-0.9 12189 0.9

# 0.9 x the limits of the sweep over ten seeds and four phase draws judged
# per vehicle/mission setup, with the check (--seeds 10 --phases 4
# --pass-rate 0.9 --check-step 0.02): every period x 0.9 x 1.0824 (a check
# at x 1.1041 fails racer5's gusty), and the PWM period alone at 0.9 x
# 8.367 ms (a check at 8.53 ms fails aero1kg's breeze).
scaled p4c-scale-0.9 "0.9 * 1.0824"
pwm_of p4c-pwm-0.9 8367 0.9

# design --fly's answer on examples/cleanflight-design-flown.toml (those
# plain-band limits, each period capped at Table V's x 1.114): --fly
# steps,gusty --vehicle racer5,aero1kg answers it, and so does bare --fly
# (steps, gusty and breeze) with a step's overshoot judged, in turbulence,
# against 20 % plus the hover's tracked error over the step's span.
design flown-fly gyro=1114 accl=1114 ahrs=5116 radio=10000 pid=2012 pwm=5488
# The same with the breeze mission among the acceptance flights at a pass
# rate of 0.8 (--fly steps,gusty,examples/missions/sweep-steps-breeze.toml
# --flights 60 --pass-rate 0.8).
design flown-fly-b gyro=1114 accl=1114 ahrs=5386 radio=10000 pid=2012 pwm=5488
# design --fly's default acceptance (bare --fly: steps, gusty and the built-in
# breeze, steps in light turbulence, on racer5 and aero1kg; the default
# pass-rate bound, 0.95 at 95 % confidence, 78 flights a design) while the
# overshoot was judged against the plain 20 % in turbulence too.
design flown-fly-d gyro=1114 accl=1114 ahrs=5386 radio=9024 pid=2012 pwm=5488

# The sweep -> design loop's answer (docs/flight.md, "The loop: sweep ->
# design -> fly"): `fly --sweep --resolution 0 --write-limits limits.toml
# --free-periods` on racer5's steps, then `design limits.toml`: every
# period at the scale's last passing point, Table V x 1.587.
design loop gyro=1587 accl=1587 ahrs=7937 radio=15874 pid=3174 pwm=7937
# design --objective margin --max-utilization 0.7 on
# examples/cleanflight-design-flown.toml: every exec x 1.782 keeps every
# limit (U = 0.6669; docs/flight.md, "The margins of Table V, ...").
design margin-0.7 gyro=1114 accl=1114 ahrs=2114 radio=2971 pid=2114 pwm=5570

# Flights of design $1 on vehicle $2 and mission $3 over the seeds at
# phase draws "$4" (per seed: "nominal", or M draws of its own): passed/flown.
flights() {
  local d=$1 v=$2 m=$3 phases=$4 pass=0 n=0 draws
  for s in $(seq "$FIRST" "$LAST"); do
    if [ "$phases" = nominal ]; then draws=0; else draws=$(seq $((1000 + PHASES * s)) $((1000 + PHASES * s + PHASES - 1))); fi
    for k in $draws; do
      n=$((n + 1))
      if "$B" fly "$TMP/$d.toml" --vehicle "$v" --mission "examples/missions/$m.toml" --seed "$s" --phase "$k" > /dev/null 2>&1; then
        pass=$((pass + 1))
      fi
    done
  done
  echo "$pass/$n"
}

ROWS=nominal
if [ "$PHASES" -gt 1 ]; then ROWS="nominal $PHASES"; fi
printf "%-12s %-8s %-8s" design vehicle phases
for m in $MISSIONS; do printf " %17s" "$m"; done
echo
for d in ${DESIGNS:-table-v old-fly scale-0.9 pwm-0.9 a-scale-0.9 a-pwm-0.9 sg-scale-0.9 sg-pwm-0.9 sgb-scale-0.9 sgb-pwm-0.9 pr-pwm-0.9 pr-pwm-0.8 pr-pwm-0.7 pr-pwm-0.6 pr-pwm-0.5 p4-scale-0.9 p4-pwm-0.9 ck3-pwm-0.9 p4c-scale-0.9 p4c-pwm-0.9 flown-fly flown-fly-b flown-fly-d loop margin-0.7}; do
  for v in ${VEHICLES:-racer5 aero1kg}; do
    for row in $ROWS; do
      printf "%-12s %-8s %-8s" "$d" "$v" "$row"
      for m in $MISSIONS; do
        printf " %17s" "$(flights "$d" "$v" "$m" "$row")"
      done
      echo
    done
  done
done
