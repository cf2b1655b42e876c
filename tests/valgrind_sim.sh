#!/bin/sh
# The simulator conformance run (and the fault matrix) under valgrind
# memcheck: any invalid access, uninitialised use or leak fails the run.
# Usage: tests/valgrind_sim.sh [BUILD]   (needs `make` first; plain build,
# not SANITIZE=1: valgrind and ASan do not mix)
build=${1:-build}
rc=0
for t in test_conformance test_sim test_faults; do
	bin=$build/tests/$t
	[ -x "$bin" ] || { echo "valgrind_sim: $bin missing (run make)"; exit 2; }
	echo "== valgrind $t"
	valgrind --tool=memcheck --error-exitcode=99 --leak-check=full \
		--errors-for-leak-kinds=definite,indirect --track-origins=yes -q "$bin" \
		> "$build/$t.valgrind.log" 2>&1
	r=$?
	tail -n 3 "$build/$t.valgrind.log"
	[ $r -eq 0 ] || { echo "valgrind_sim: $t failed ($r), see $build/$t.valgrind.log"; rc=1; }
done
exit $rc
