#!/bin/sh
# The bench's side-by-side FloeDyn run (bench/collisions.cpp, --floedyn),
# checked with a stand-in for FloeDyn's FLOE program: a script that checks
# the command line FloeDyn would get (its input file, the end time, the extra
# argument, its folder, one thread), sleeps a known time and exits 0, or 3
# when told to fail. Asserted: the CSV's floedyn_s is at least the sleep and
# the speedup is floedyn_s / wall_s; a failing FloeDyn makes the bench exit 1
# and say so in its CSV, with no ratio.
# Usage: floedyn_side_by_side.sh BENCH WORKDIR
set -eu
bench=$1
work=$2
rm -rf "$work"
mkdir -p "$work/floedyn/build" "$work/floedyn/io/inputs"
fake="$work/floedyn/build/FLOE"
cat > "$fake" <<'FAKE'
#!/bin/sh
# stand-in for FloeDyn: FLOE -i INPUT -t TEND [extra]
[ "$1" = -i ] && [ -f "$2" ] && [ "$(basename "$2")" = in_example_100_floes.h5 ] || { echo "bad input: $*"; exit 2; }
[ "$3" = -t ] && [ "$4" = 10000 ] || { echo "bad end time: $*"; exit 2; }
[ "$5" = --obl=0 ] || { echo "extra argument missing: $*"; exit 2; }
[ -d io/inputs ] || { echo "not run in FloeDyn's folder: $(pwd)"; exit 2; }
[ "$OMP_NUM_THREADS" = 1 ] || { echo "OMP_NUM_THREADS=$OMP_NUM_THREADS"; exit 2; }
[ -f fail ] && exit 3
sleep 0.5
exit 0
FAKE
chmod +x "$fake"

csv="$work/ok.csv"
"$bench" --only floedyn_100 --repeats 2 --floedyn "$fake" --floedyn-arg=--obl=0 --csv "$csv" > "$work/ok.log"
grep -q "^# FloeDyn: $fake -i .*in_example_100_floes.h5 -t 10000 --obl=0 (in $work/floedyn)" "$csv" ||
  { echo "FAIL: FloeDyn command missing from the CSV header"; cat "$csv"; exit 1; }
awk -F, '
  /^#/ { next }
  $1 == "scenario" { for (i = 1; i <= NF; i++) col[$i] = i; next }
  $1 == "floedyn_100" {
    f = $col["floedyn_s"]; m = $col["floedyn_s_median"]; w = $col["wall_s"]; s = $col["speedup"]
    if (f == "" || f < 0.5 || m < f) { print "FAIL: floedyn_s " f ", median " m " (the stand-in sleeps 0.5 s)"; exit 1 }
    if (s == "" || (s - f / w) > 0.051 || (f / w - s) > 0.051) { print "FAIL: speedup " s " != " f " / " w; exit 1 }
    found = 1
  }
  END { if (!found) { print "FAIL: no floedyn_100 row"; exit 1 } }' "$csv"

touch "$work/floedyn/fail"
if "$bench" --only floedyn_100 --repeats 1 --floedyn "$fake" --floedyn-arg=--obl=0 --csv "$work/fail.csv" > "$work/fail.log"; then
  echo "FAIL: the bench exited 0 although FloeDyn failed"; exit 1
fi
grep -q "^# FloeDyn failed on floedyn_100: exit 3" "$work/fail.csv" ||
  { echo "FAIL: the failure is not in the CSV"; cat "$work/fail.csv"; exit 1; }
awk -F, '/^#/ { next } $1 == "scenario" { for (i = 1; i <= NF; i++) col[$i] = i; next }
  $1 == "floedyn_100" && ($col["floedyn_s"] != "" || $col["speedup"] != "") { print "FAIL: a ratio without FloeDyn"; exit 1 }' "$work/fail.csv"
echo "ok: FloeDyn stand-in timed side by side; failure reported"
