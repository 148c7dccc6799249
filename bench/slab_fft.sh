#!/usr/bin/env bash
# bench/slab_fft.sh: the spectral sea's 2D transform in slabs (fluid/slab_fft.hpp)
# on 1 and 2 ranks, alternating, --rounds times (floesim_bench_slab_fft: per
# rank and grid, the least time of 20 forward + backward pairs, whole and in
# slabs, the time inside the two transposes and the bytes received). Writes
# the CSV with the command, the commit and the load before and after.
#
# usage: bench/slab_fft.sh [--build DIR=build] [--rounds R=3] [--csv FILE | -]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
rounds=3
csv=-
command="bench/slab_fft.sh $*"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --csv) csv="$2"; shift 2 ;;
    *) echo "usage: bench/slab_fft.sh [--build DIR] [--rounds R] [--csv FILE | -]" >&2; exit 2 ;;
  esac
done
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
bench="$build/bin/floesim_bench_slab_fft"
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
rows=""
for ((r = 0; r < rounds; r++)); do
  for ranks in 1 2; do
    out="$(mpirun --oversubscribe -np "$ranks" "$bench" --cells 512 --cells 2048 --pairs 20 | grep -v '^cells')"
    rows+="$(echo "$out" | sed "s/^/$r,/")"$'\n'
  done
done
{
  echo "# command: $command"
  echo "# commit: $(git -C "$root" rev-parse --short HEAD) (Release build)"
  echo "# machine: $(uname -m), $(nproc) cores (shared); load before $load_before, after $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "# a pair = one forward and one backward transform of a cells^2 field; whole_pair_s: the whole transform on the rank alone; slab_pair_s: the rank's slabs with the two transposes; transposes_s: inside MPI_Alltoallv (waits included); speedup_of_passes = whole / (slab - transposes); least of 20 pairs"
  echo "round,cells,ranks,rank,whole_pair_s,slab_pair_s,transposes_s,received_bytes_per_pair,speedup_of_passes"
  printf "%s" "$rows" | sort -t, -k2,2n -k3,3n -k1,1n -k4,4n
} > "${csv/#-//dev/stdout}"
