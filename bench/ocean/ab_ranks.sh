#!/usr/bin/env bash
# bench/ocean/ab_ranks.sh: two floesim binaries (A and B, say two commits'
# builds) on the same configuration on 2 ranks, alternating A, B for each
# round so that load changes on a shared machine hit both. Per run: the
# loop's wall time (summary wall_time), rank 0's collective calls, bytes
# received and seconds in them, and the 1-minute load. CSV on stdout.
#
# usage: bench/ocean/ab_ranks.sh A_BINARY B_BINARY UNTIL ROUNDS CONFIG
#   (CONFIG: bench/ocean/ocean.toml with its pack path made absolute, as
#   bench/ocean/ranks.py writes it)
set -euo pipefail
[ $# -eq 5 ] || { sed -n '2,10p' "$0"; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "binary,round,wall_s,collectives,bytes_received,collective_s,load1"
for r in $(seq 1 "$4"); do
  for label in A B; do
    bin="$1"; [ "$label" = B ] && bin="$2"
    out=$(mpirun --oversubscribe -np 2 "$bin" run "$5" --until "$3" --threads 1 -q -o "$work/$label.h5")
    field() { echo "$out" | awk -F': ' -v k="$1" '$1 == k { print $2 + 0 }'; }
    echo "$label,$r,$(field wall_time),$(field parallel.collectives),$(field parallel.bytes_received),$(field parallel.collective_seconds),$(cut -d' ' -f1 /proc/loadavg)"
  done
done
