#!/bin/bash
# Guest test: the vehicle-fw process tests (tests/test_linux_fw.c --process,
# tests/test_linux_modbus.c: vehicle-fw on a pty, loopback drives, Modbus RTU
# drives and a BMS behind mbdrive-sim on a socat pty pair, pymodbus's
# cross-check) on the guest's instruction-counted clock. On the host these
# processes share the CPUs with whatever else runs there, and the loop's
# lateness, the drive timeouts and the battery's stale rule would all depend
# on that; here every process runs on guest time, which the host's load
# cannot hold up (run-guest.sh -i).
#
# The files sit under /g as they do in the source tree (the tests find
# vehicle-fw and mbdrive-sim beside their own build folder, and the
# cross-check script by its relative path). Each binary's cmocka lines are
# passed on; run_fw.sh counts them.
set -u
cd /g || exit 1
rc=0
build/tests/test_linux_fw --process || rc=1
build/tests/test_linux_modbus || rc=1
exit $rc
