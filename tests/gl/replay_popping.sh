#!/bin/sh
# `scenelod replay --popping` on a fixed small replay: a bumpy sphere (written here) approached from
# 40 radii at 160 x 120, X = 4, so that it switches levels 4 -> 3 -> 2 -> 1 -> 0. Checks that frames
# whose levels did not change have popping 0, every hard switch has popping > 0, and cross-fades
# lower the worst popping. Exit code 77 (CTest SKIP_RETURN_CODE) where EGL cannot start.
# usage: replay_popping.sh SCENELOD SCRATCH_DIR
tool=$1 dir=$2
rm -rf "$dir" && mkdir -p "$dir" || exit 1
awk 'BEGIN { n = 48; m = 24; pi = 3.14159265358979
  for (j = 0; j <= m; j++) for (i = 0; i < n; i++) {
    th = pi * j / m; ph = 2 * pi * i / n; r = 1 + 0.08 * sin(5 * ph) * sin(4 * th)
    printf "v %.6f %.6f %.6f\n", r * sin(th) * cos(ph), r * cos(th), r * sin(th) * sin(ph) }
  for (j = 0; j < m; j++) for (i = 0; i < n; i++) {
    a = j * n + i + 1; b = j * n + (i + 1) % n + 1; c = (j + 1) * n + (i + 1) % n + 1; d = (j + 1) * n + i + 1
    if (j > 0) printf "f %d %d %d\n", a, c, b
    if (j < m - 1) printf "f %d %d %d\n", a, d, c } }' > "$dir/blob.obj"
"$tool" record "$dir/blob.obj" --path approach --from 40 --frames 60 --viewport 160 120 --pixels-per-cell 4 \
  -o "$dir/blob.jsonl" || { echo "FAIL: scenelod record"; exit 1; }
for t in none fade; do
  "$tool" replay "$dir/blob.jsonl" -o "$dir/$t.log" --distance --transitions $t --popping --report "$dir/$t.md" > "$dir/$t.out" 2>&1
  rc=$?
  cat "$dir/$t.out"
  if [ $rc -eq 77 ]; then
    echo "SKIP: headless OpenGL (EGL) cannot start on this machine"
    exit 77
  fi
  [ $rc -eq 0 ] || { echo "FAIL: scenelod replay --transitions $t --popping exited with $rc"; exit 1; }
  grep -q "^popping: max" "$dir/$t.out" || { echo "FAIL: no popping summary ($t)"; exit 1; }
  grep -q "^## Popping" "$dir/$t.md" || { echo "FAIL: the report has no popping section ($t)"; exit 1; }
done
# per frame: levels and popping; frames without a change of level pop 0, every switch pops
awk '{
  match($0, /"levels": \[[^]]*\]/); levels = substr($0, RSTART, RLENGTH)
  if (!match($0, /"popping": [0-9.]+/)) { print "FAIL: frame " NR - 1 " has no popping"; bad = 1; next }
  p = substr($0, RSTART + 11, RLENGTH - 11) + 0
  if (NR > 1 && levels == last && p != 0) { print "FAIL: frame " NR - 1 " kept its levels but pops " p; bad = 1 }
  if (NR > 1 && levels != last) { switches++; if (p <= 0) { print "FAIL: frame " NR - 1 " switched but pops 0"; bad = 1 } }
  last = levels
} END {
  if (switches < 2) { print "FAIL: only " switches + 0 " switches on the replay"; bad = 1 }
  print switches " switches checked"
  exit bad }' "$dir/none.log" || exit 1
max() { sed -n 's/^popping: max \([0-9.]*\).*/\1/p' "$1"; }
none=$(max "$dir/none.out") fade=$(max "$dir/fade.out")
echo "worst popping: hard switches $none, cross-fades $fade"
awk -v n="$none" -v f="$fade" 'BEGIN { exit !(n > 0 && f < n) }' || { echo "FAIL: fades do not lower the worst popping"; exit 1; }
# geomorphs on nested chains with the camera's own popping beside: every drawn frame logs a
# camera_popping in [0, 1], the others none; a moving camera changes pixels on some frame
"$tool" replay "$dir/blob.jsonl" -o "$dir/morph.log" --distance --transitions morph --nested --popping --popping-camera \
  > "$dir/morph.out" 2>&1 || { cat "$dir/morph.out"; echo "FAIL: scenelod replay --popping-camera"; exit 1; }
awk '{
  has = match($0, /"camera_popping": [0-9.]+/); c = has ? substr($0, RSTART + 18, RLENGTH - 18) + 0 : -1
  match($0, /"popping": [0-9.]+/); p = substr($0, RSTART + 11, RLENGTH - 11) + 0
  if (has) { drawn++; if (c < 0 || c > 1) { print "FAIL: frame " NR - 1 " camera_popping " c; bad = 1 }; if (c > 0) moving++ }
  if (!has && p > 0) { print "FAIL: frame " NR - 1 " pops " p " but has no camera_popping"; bad = 1 }
} END {
  if (drawn < 2 || moving < 1) { print "FAIL: " drawn + 0 " frames with camera_popping, " moving + 0 " above 0"; bad = 1 }
  print drawn " frames with the camera popping beside"
  exit bad }' "$dir/morph.log" || exit 1
# scenelod view follows the same replay with cross-fades: some frames draw objects fading
out=$("$tool" view --replay "$dir/blob.jsonl" --headless --distance --pixels 4 --transitions fade --size 160 120 2>&1)
rc=$?
[ $rc -eq 0 ] || { echo "$out"; echo "FAIL: scenelod view --transitions fade exited with $rc"; exit 1; }
printf '%s\n' "$out" | grep -q "fading [1-9]" || { echo "$out"; echo "FAIL: scenelod view --transitions fade shows no fading object"; exit 1; }
out=$("$tool" view --replay "$dir/blob.jsonl" --headless --distance --pixels 4 --size 160 120 2>&1)
printf '%s\n' "$out" | grep -q "fading" && { echo "FAIL: without --transitions the frame lines mention fading"; exit 1; }
echo "view: fading objects printed with --transitions fade"
