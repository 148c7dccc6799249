#!/usr/bin/env bash
# bench/ocean/run.sh: the ocean benchmark of issue 6 (bench/ocean/ocean.toml).
#
# Writes the pack (floesim pack, seed 1) beside ocean.toml, then for each
# stiffness K runs `floesim run` on a copy of ocean.toml with that K, to
# --until seconds, under /usr/bin/time -v, --repeats times; keeps the run
# with the least wall time of the loop (summary `wall_time`: the steps and
# the records, not the set-up) and writes one CSV row per K with: steps, mean
# dt, steps per wall second, simulated seconds per wall second, set-up time
# (elapsed minus the loop), CPU time, peak memory (maximum resident set of
# the process), collisions, energy drift, and the profile per phase
# (`--profile`, ms per step). The CSV starts with comment lines: the command,
# the commit, the machine and its load (uptime) before and after.
#
# With --integrator implicit the floe–sea spring is integrated implicitly
# ([coupling] integrator, docs/coupling.md) and the rows also give the Newton
# and conjugate-gradient iterations per step.
#
# usage: bench/ocean/run.sh [--until T=60] [--repeats R=1] [--stiffness "K..."="100"]
#                           [--integrator explicit|implicit=explicit]
#                           [--build DIR=build] [--csv FILE=bench/results/ocean_epyc-2core.csv | -]
#                           [--work DIR] [--note TEXT]
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
until_s=60
repeats=1
stiffness="100"
integrator="explicit"
build="$root/build"
csv="$root/bench/results/ocean_epyc-2core.csv"
work=""
note=""
command_line="bench/ocean/run.sh $*"
while [ $# -gt 0 ]; do
  case "$1" in
    --until) until_s="$2"; shift 2 ;;
    --repeats) repeats="$2"; shift 2 ;;
    --stiffness) stiffness="$2"; shift 2 ;;
    --build) build="$(cd "$2" && pwd)"; shift 2 ;;
    --csv) csv="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --note) note="$2"; shift 2 ;;
    --integrator) integrator="$2"; shift 2 ;;
    -h|--help) sed -n '2,24p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done

floesim="$build/bin/floesim"
[ -x "$floesim" ] || { echo "run.sh: no $floesim (build it: cmake --build $build --target floesim)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "run.sh: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
if [ -z "$work" ]; then
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work"

pack="$here/ocean_pack.h5"
"$floesim" pack --floes 1000 --concentration 0.3 --box 1000 1000 --seed 1 --min-size 10 --max-size 30 \
  --thickness 1 -o "$pack" > "$work/pack.txt"

load_before="$(uptime | sed 's/.*load average: //')"
rows="$work/rows.csv"
: > "$rows"
phases=""
for K in $stiffness; do
  toml="$work/ocean_K$K.toml"
  sed -e "s|^pack = .*|pack = \"$pack\"|" -e "s|^stiffness = .*|stiffness = $K\nintegrator = \"$integrator\"|" \
    "$here/ocean.toml" > "$toml"
  # The set-up alone (sea, waves, floes, static start): its CPU time is taken
  # from the whole run's to give the loop's.
  /usr/bin/time -v "$floesim" run "$toml" --until 0 -q -o "$work/setup.h5" > /dev/null 2> "$work/setup.time"
  setup_cpu="$(awk -F': ' '{ sub(/^[ \t]+/, "") } /^(User|System) time/ { t += $2 } END { print t }' "$work/setup.time")"
  best=""
  for r in $(seq 1 "$repeats"); do
    out="$work/K$K.run$r"
    /usr/bin/time -v "$floesim" run "$toml" --until "$until_s" --profile -q -o "$work/ocean_K$K.h5" \
      > "$out.txt" 2> "$out.time"
    wall="$(awk -F': ' '$1 == "wall_time" { print $2 + 0 }' "$out.txt")"
    echo "K = $K, run $r: loop $wall s" >&2
    if [ -z "$best" ] || awk -v a="$wall" -v b="$best_wall" 'BEGIN { exit !(a < b) }'; then
      best="$out"
      best_wall="$wall"
    fi
  done
  [ -n "$phases" ] || phases="$(awk -F': ' '$1 ~ /^profile\./ { sub(/^profile\./, "", $1); printf "%s%s", sep, $1; sep = " " }' "$best.txt")"
  awk -F': ' -v K="$K" -v integrator="$integrator" -v repeats="$repeats" -v phases="$phases" -v setup_cpu="$setup_cpu" '
    FNR == 1 { file++ }
    file == 1 { v[$1] = $2 }
    file == 2 {
      sub(/^[ \t]+/, "")
      if ($0 ~ /^Maximum resident set size/) rss = $2 / 1024
      if ($0 ~ /^User time/) user = $2
      if ($0 ~ /^System time/) sys = $2
      if ($0 ~ /^Elapsed \(wall clock\)/) {
        n = split($2, p, ":"); elapsed = 0
        for (i = 1; i <= n; i++) elapsed = elapsed * 60 + p[i]
      }
    }
    END {
      steps = v["steps"] + 0; sim = v["simulated"] + 0; wall = v["wall_time"] + 0
      split(v["energy.total"], e, " ")
      loop_cpu = user + sys - setup_cpu
      printf "%s,%s,%s,%d,%g,%d,%.5f,%.3f,%.1f,%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%.1f,%.2f,%d,%d,%.3g",
        v["status"], integrator, K, v["floes"], sim, steps, sim / steps, wall, steps / wall, sim / wall,
        elapsed - wall, loop_cpu, sim / loop_cpu, setup_cpu, rss, 1000 * wall / steps, 1000 * loop_cpu / steps,
        v["collisions.lcps"], v["collisions.contacts"], (e[3] - e[1]) / e[1]
      np = split(phases, ph, " ")
      for (i = 1; i <= np; i++) { split(v["profile." ph[i]], t, " "); printf ",%.3f", 1000 * t[1] / steps }
      printf ",%s,%s,%d\n", v["implicit.newton_per_step"] + 0, v["implicit.cg_per_step"] + 0, repeats
    }' "$best.txt" "$best.time" >> "$rows"
done
load_after="$(uptime | sed 's/.*load average: //')"

commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
git -C "$root" diff --quiet HEAD -- 2>/dev/null || commit="$commit+uncommitted"
cpu="$(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo)"
{
  echo "# command: $command_line"
  echo "# source: commit $commit; floesim: $floesim${note:+; $note}"
  echo "# machine: $cpu, $(nproc --all) cores (shared); load before: $load_before; after: $load_after; $(date -u +%Y-%m-%d)"
  echo "# case: bench/ocean/ocean.toml with [coupling] stiffness = K, run to $until_s s: $(tr '\n' ' ' < "$work/pack.txt" | sed 's/ *$//')"
  echo "# loop_s: summary wall_time (steps and records, not the set-up), least of 'repeats' runs; setup_s = elapsed - loop_s;"
  echo "#   loop_cpu_s: user + system time of the run minus that of a run to t = 0 (setup_cpu_s): the loop's CPU time, which"
  echo "#   other processes on a shared machine disturb less than its wall time; sim_s_per_cpu_s = simulated_s / loop_cpu_s;"
  echo "#   peak_rss_mb: maximum resident set of the run (MiB, /usr/bin/time -v); ms_per_step: loop_s / steps, cpu_ms_per_step likewise;"
  echo "#   energy_drift: (total at the end - total at t = 0) / total at t = 0; phase columns: wall ms per step (floesim run --profile)"
  printf "status,integrator,stiffness,floes,simulated_s,steps,mean_dt_s,loop_s,steps_per_s,sim_s_per_wall_s,setup_s,loop_cpu_s,sim_s_per_cpu_s,setup_cpu_s,peak_rss_mb,ms_per_step,cpu_ms_per_step,lcps,contacts,energy_drift"
  for p in $phases; do printf ",%s_ms" "$p"; done
  printf ",newton_per_step,cg_per_step,repeats\n"
  cat "$rows"
} > "$work/result.csv"
if [ "$csv" = "-" ]; then cat "$work/result.csv"; else cp "$work/result.csv" "$csv"; cat "$csv"; fi
