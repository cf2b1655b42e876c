#!/bin/sh
# The Python client's tests (tests/python, python/vehicleservice) against
# vehicle-sim --pty, under Debian's /usr/bin/python3 (python3-serial,
# python3-matplotlib import only there). Last line: "python: N passed, M failed".
#   tests/run_python_tests.sh [BUILD]
top=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
out=$(cd "$top" && VEHICLE_BUILD=$build PYTHONPATH=$top/python:$top/tests/python \
	PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg timeout 600 /usr/bin/python3 -m unittest discover -v \
	-s tests/python -p 'test_*.py' 2>&1)
rc=$?
printf '%s\n' "$out"
ran=$(printf '%s\n' "$out" | sed -n 's/^Ran \([0-9]*\) test.*/\1/p')
bad=$(printf '%s\n' "$out" | grep -cE '^(FAIL|ERROR): ')
ran=${ran:-0}
[ $rc -ne 0 ] && [ "$bad" -eq 0 ] && bad=1
echo "python: $((ran - bad < 0 ? 0 : ran - bad)) passed, $bad failed"
[ $rc -eq 0 ]
