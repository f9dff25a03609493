#!/bin/bash
# Thread scaling of ibeam renders, one binary or two side by side.
#
#   bash peers/scaling.sh OUT SCENES BIN [BIN2]
#
# OUT: a folder for scaling.csv and the stats of every render.
# SCENES: a folder holding colonnade.vm, prospero.vm and the sphere
#   scenes spheres-N.ib that the harness's cold mode leaves in its --out
#   (run `ibeam-peers ... --out DIR` first, then pass DIR here with the
#   models copied beside them).
# BIN, BIN2: ibeam binaries; with two, each render runs with both in turn.
# THREADS (default "1 2 4 8 16") and REPS (default 3) from the environment.
#
# Each row of scaling.csv is one process: the workload, threads, binary,
# rep, the process's wall ms and its stats' time_ms and CPU sums (trace,
# shade, shadow), from which the parallel efficiency
# (trace + shade + shadow) / (threads × time_ms) follows.
set -u
OUT=$1 SCENES=$2; shift 2
BINS=("$@")
THREADS=${THREADS:-1 2 4 8 16}
REPS=${REPS:-3}
mkdir -p "$OUT/stats"
C="--eye 2.4,2.0,3.2 --target 0,0,0 --fov 40"
NAMES=(colonnade-default spheres-3000-shadows spheres-3000-corner spheres-1000-corner
  spheres-100-corner spheres-10-corner prospero-default)
args() {
  case $1 in
    colonnade-default) echo "$SCENES/colonnade.vm" ;;
    prospero-default) echo "$SCENES/prospero.vm" ;;
    spheres-3000-shadows) echo "$SCENES/spheres-3000.ib" ;;
    spheres-*-corner) n=${1#spheres-}; echo "$SCENES/spheres-${n%-corner}.ib --no-shadows $C" ;;
  esac
}
field() { grep -o "\"$1\": [0-9.e+-]*" "$2" | head -1 | sed 's/.*: //'; }
echo "workload,threads,binary,rep,wall_ms,time_ms,trace_cpu_ms,shade_cpu_ms,shadow_cpu_ms" > "$OUT/scaling.csv"
for r in $(seq "$REPS"); do
  for t in $THREADS; do
    for name in "${NAMES[@]}"; do
      set -- $(args "$name")
      [ -f "$1" ] || continue
      for bin in "${BINS[@]}"; do
        j="$OUT/stats/$name-$t-$(basename "$bin")-$r.json"
        t0=$(date +%s%N)
        timeout 120 "$bin" render "$@" --size 1024x1024 --threads "$t" --quiet \
          --stats-json "$j" -o "$OUT/last.png" --depth "$OUT/last-depth.png" \
          --normals "$OUT/last-normals.png" > /dev/null 2>> "$OUT/errors.txt"
        t1=$(date +%s%N)
        echo "$name,$t,$(basename "$bin"),$r,$(( (t1 - t0) / 1000000 )),$(field time_ms "$j"),$(field trace_cpu_ms "$j"),$(field shade_cpu_ms "$j"),$(field shadow_cpu_ms "$j")" >> "$OUT/scaling.csv"
      done
    done
  done
done
