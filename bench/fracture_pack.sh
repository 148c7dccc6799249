#!/bin/sh
# Fracture checks on the multirate steps: wall time of packs with fracture
# off; on with strength 20 MPa ("strong": the screen lets impacts through and
# they are analysed, but nothing breaks); and on with the ice's 0.5 MPa
# ("ice": floes break and split), run alternately, REPEATS rounds, one
# thread. Writes CSV on stdout:
#   scenario,variant,round,wall_s,steps,checks,screened,bounded,sustained,initiations,splits,analysis_s,split_s,
#   cut_short,loop_steps,models,model_s,phase_s,mesh_s,bound_s,factor_s,lattice_meshes
# (bounded: cases skipped by the stress bound; analysis_s: wall time in the analyses and bounds, models included;
# split_s: in the splits, without the rebuild of the per-floe structures after them; cut_short: analyses whose time
# loop stopped once it could no longer initiate; loop_steps: time steps the analyses ran; models: floe models built,
# model_s their wall time; phase_s: the whole percussion phase, screen and splits included; mesh_s: of model_s, the
# meshing; bound_s: the stress bounds; factor_s: assembling K and factorising, in bounds or analyses; lattice_meshes:
# of models, meshed by the lattice mesher. A baseline binary older than these counters leaves them empty.)
# Scenarios: wall_100 (examples/pack_against_wall.h5, 15 m/s wind against the
# wall, 3000 s) and drift_500 (500 floes of 0.5 to 2 m at 50% in a periodic
# 2 km box, 15 m/s wind: floes of different thickness drift at different
# speeds and collide; 1000 s).
# Usage: bench/fracture_pack.sh BUILD_DIR [REPEATS] > bench/results/fracture_pack_<machine>.csv
# (SCENARIOS="drift_500" runs only those named, default both; VARIANTS="off strong"
# only those variants, default all three; BASELINE=path/to/an/older/floesim also runs
# each variant with fracture on with that binary, right after the current one, as
# variant NAME_base: an A/B comparison alternating in one run.)
set -eu
BIN=$(cd "$1" && pwd)/bin/floesim
REPEATS=${2:-3}
SRC=$(cd "$(dirname "$0")/.." && pwd)
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
"$BIN" pack --floes 500 --concentration 0.5 --box 2000 2000 --seed 1 --thickness-range 0.5 2.0 \
  -o "$DIR/drift_500.h5" > /dev/null
write() {  # name pack t_end extra fracture
  cat > "$DIR/$1_$5.toml" <<TOML
[run]
t_end = $3
dt_max = 10.0
output_interval = 100.0
threads = 1
[sea]
model = "none"
[floes]
pack = "$2"
[contact]
collision_distance = 0.01
$4
[forcing]
wind = [15.0, 0.0]
TOML
  case $5 in
    off) ;;
    strong) printf '[fracture]\nenabled = true\nstrength = 20e6\nsplit = true\nmesh_size = 20.0\n' >> "$DIR/$1_$5.toml" ;;
    ice) printf '[fracture]\nenabled = true\nstrength = 0.5e6\nsplit = true\nmesh_size = 20.0\n' >> "$DIR/$1_$5.toml" ;;
  esac
}
for v in off strong ice; do
  write wall_100 "$SRC/examples/pack_against_wall.h5" 3000 "" $v
  write drift_500 "$DIR/drift_500.h5" 1000 "domain = \"periodic\"
box = [0.0, 2000.0, 0.0, 2000.0]" $v
done
echo "scenario,variant,round,wall_s,steps,checks,screened,bounded,sustained,initiations,splits,analysis_s,split_s,cut_short,loop_steps,models,model_s,phase_s,mesh_s,bound_s,factor_s,lattice_meshes"
one() {  # scenario variant round binary name
  start=$(date +%s.%N)
  out=$(OMP_NUM_THREADS=1 "$4" run "$DIR/${1}_$2.toml" -q -o "$DIR/out.h5")
  end=$(date +%s.%N)
  get() { printf '%s\n' "$out" | awk -F': ' -v k="$1" '$1 == k { print $2 }'; }
  echo "$1,$5,$3,$(echo "$end - $start" | bc),$(get steps),$(get fracture.checks),$(get fracture.screened),$(get fracture.bounded),$(get fracture.sustained),$(get fracture.initiations),$(get fracture.splits),$(get fracture.seconds),$(get fracture.split_seconds),$(get fracture.cut_short),$(get fracture.loop_steps),$(get fracture.models),$(get fracture.model_seconds),$(get fracture.phase_seconds),$(get fracture.mesh_seconds),$(get fracture.bound_seconds),$(get fracture.factor_seconds),$(get fracture.lattice_meshes)"
}
for r in $(seq 1 "$REPEATS"); do
  for s in ${SCENARIOS:-wall_100 drift_500}; do
    for v in ${VARIANTS:-off strong ice}; do
      one "$s" "$v" "$r" "$BIN" "$v"
      if [ -n "${BASELINE:-}" ] && [ "$v" != off ]; then one "$s" "$v" "$r" "$BASELINE" "${v}_base"; fi
    done
  done
done
