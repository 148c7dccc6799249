#!/bin/sh
# Smoke test of bench/ocean/large.py (label bench): a small version of the
# scaled ocean case (40 floes on 128^2 cells, 0.05 s) on the given rank
# counts; every row must have run steps, a loop time, and a peak memory per
# process for each process of its rank count.
# usage: ocean_large_smoke.sh SOURCE_DIR BUILD_DIR WORK "RANKS..."
set -eu
src="$1"; build="$2"; work="$3"; ranks="$4"
rm -rf "$work"; mkdir -p "$work"
# shellcheck disable=SC2086
/usr/bin/python3 "$src/bench/ocean/large.py" --build "$build" --floes 40 --cells 128 --until 0.05 \
  --ranks $ranks --work "$work" --csv "$work/large.csv" > "$work/out.txt" 2>&1 || { cat "$work/out.txt"; exit 1; }
awk -F, -v want="$ranks" '
  BEGIN { n = split(want, r, " ") }
  /^#/ || /^ranks,/ { next }
  {
    rows++
    processes = split($13, rss, " ")
    expected = ($1 == 0) ? 1 : $1
    if ($4 < 1 || $3 <= 0) { print "no steps or no loop time: " $0; bad = 1 }
    if (processes != expected) { print "peak memory of " processes " processes, " expected " expected: " $0; bad = 1 }
    for (i = 1; i <= processes; i++) if (rss[i] <= 0) { print "no peak memory: " $0; bad = 1 }
  }
  END {
    if (rows != n) { print rows " rows for " n " rank counts"; bad = 1 }
    exit bad
  }' "$work/large.csv"
echo "ocean_large_smoke: $(grep -vc '^#' "$work/large.csv") lines, ok"
