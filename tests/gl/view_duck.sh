#!/bin/sh
# Runs `scenelod view` headless on the Duck for 10 frames and checks a screenshot shows it (a
# budget of 1 s: on a loaded machine a tight budget may drop the Duck, which is not under test).
# Exit code 77 (CTest SKIP_RETURN_CODE) when the shared models are absent or EGL cannot start.
# usage: view_duck.sh SCENELOD PNG_CHECK MODEL.glb SCRATCH_DIR
tool=$1 check=$2 model=$3 dir=$4
if [ ! -f "$model" ]; then
  echo "SKIP: $model is absent (the shared glTF models live beside the checkout in ../shared/models)"
  exit 77
fi
rm -rf "$dir"
"$tool" view "$model" --headless --frames 10 --every 5 --size 160 120 --budget 1000 --png "$dir"
rc=$?
if [ $rc -eq 77 ]; then
  echo "SKIP: headless OpenGL (EGL) cannot start on this machine"
  exit 77
fi
[ $rc -eq 0 ] || { echo "FAIL: scenelod view exited with $rc"; exit 1; }
for f in frame_0000.png frame_0005.png frame_0009.png; do
  [ -f "$dir/$f" ] || { echo "FAIL: $dir/$f was not written"; exit 1; }
done
"$check" "$dir/frame_0000.png" 160 120 2 || { echo "FAIL: the screenshot shows (almost) only background"; exit 1; }
"$check" "$dir/frame_0009.png" 160 120 2 || { echo "FAIL: the last screenshot shows (almost) only background"; exit 1; }
# the same with a shadow map: the shadow view selects the casters' levels and the frame reports them
out=$("$tool" view "$model" --headless --frames 3 --size 160 120 --shadows --shadow-map 256 --budget 1000 --png "$dir/shadows" 2>&1)
rc=$?
echo "$out"
[ $rc -eq 0 ] || { echo "FAIL: scenelod view --shadows exited with $rc"; exit 1; }
printf '%s\n' "$out" | grep -q "shadow map: [1-9][0-9]* triangles" || { echo "FAIL: no triangles drawn into the shadow map"; exit 1; }
"$check" "$dir/shadows/frame_0002.png" 160 120 2 || { echo "FAIL: the shadowed screenshot shows (almost) only background"; exit 1; }
[ -f "$dir/shadows/light_0002.png" ] || { echo "FAIL: the light's view of the shadow levels was not written"; exit 1; }
