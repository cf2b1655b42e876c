#!/bin/sh
# Runs each cmocka test binary, then each suite script given after "--"
# (scripts whose last line reads "NAME: N passed, M failed"), shows their
# output, and closes with one summary line: "check: N passed, M failed".
build=$1; shift
passed=0; failed=0; broken=""
count() { # $1 = output, $2 = cmocka|suite
	if [ "$2" = cmocka ]; then
		p=$(printf '%s\n' "$1" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
		f=$(printf '%s\n' "$1" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
	else
		last=$(printf '%s\n' "$1" | grep -E '^[a-z-]+: [0-9]+ passed, [0-9]+ failed$' | tail -1)
		p=$(printf '%s\n' "$last" | sed -n 's/^[a-z-]*: \([0-9]*\) passed.*/\1/p'); p=${p:-0}
		f=$(printf '%s\n' "$last" | sed -n 's/.* \([0-9]*\) failed$/\1/p'); f=${f:-0}
	fi
}
mode=cmocka
for t in "$@"; do
	if [ "$t" = "--" ]; then mode=suite; continue; fi
	if [ $mode = cmocka ]; then out=$("$t" 2>&1); rc=$?; else out=$("$t" "$build" 2>&1); rc=$?; fi
	printf '%s\n' "$out"
	count "$out" $mode
	passed=$((passed + p)); failed=$((failed + f))
	if [ $rc -ne 0 ] && [ "$f" -eq 0 ]; then failed=$((failed + 1)); broken="$broken $t"; fi
done
[ -n "$broken" ] && echo "crashed or exited non-zero:$broken"
echo "check: $passed passed, $failed failed"
[ $failed -eq 0 ]
