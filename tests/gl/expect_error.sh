#!/bin/sh
# usage: expect_error.sh EXPECTED_EXIT PATTERN COMMAND...
# Passes when COMMAND exits with EXPECTED_EXIT and its output (stdout + stderr) contains PATTERN.
want=$1 pattern=$2
shift 2
out=$("$@" 2>&1)
rc=$?
echo "$out"
[ "$rc" -eq "$want" ] || { echo "FAIL: exit code $rc, expected $want"; exit 1; }
printf '%s\n' "$out" | grep -F -q -e "$pattern" || { echo "FAIL: no message containing '$pattern'"; exit 1; }
