#!/bin/bash
# make install and the configuration search of the installed and the built
# programs: vehicle-sim started from another folder finds its configuration
# (the checkout's config/ from the build folder, PREFIX/share/vehicle once
# installed), make install into a DESTDIR writes exactly the listed files,
# and a second install keeps an edited SYSCONFDIR/vehicle/vehicle.xml.
# Last line: "install: N passed, M failed".
#   tests/run_install_tests.sh [BUILD]     (after make)
set -u
top=$(cd "$(dirname "$0")/.." && pwd -P)
build=${1:-build}
case $build in /*) abs=$build ;; *) abs=$top/$build ;; esac
abs=$(cd "$abs" && pwd -P) || exit 1
passed=0 failed=0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

ok() { echo "install: PASS $1"; passed=$((passed + 1)); }
bad() {
	echo "install: FAIL $1"
	shift
	printf '  %s\n' "$@"
	failed=$((failed + 1))
}
# same NAME EXPECTED GOT
same() {
	if [ "$2" = "$3" ]; then ok "$1"; else bad "$1" "expected:" "$2" "got:" "$3"; fi
}

# vehicle-sim PROGRAM from an empty folder, one getState: stdout, then stderr.
run_sim() {
	mkdir -p "$tmp/elsewhere"
	(cd "$tmp/elsewhere" && printf 'getState\n' | "$1" --fast >"$tmp/out" 2>"$tmp/err")
	printf 'rc %s\n' $?
	cat "$tmp/out" "$tmp/err"
}

got=$(run_sim "$abs/vehicle-sim")
same "build folder's vehicle-sim started elsewhere reads the checkout's config/" "rc 0
ok true 25 \"Unpowered\"
vehicle-sim: differential base, 2 axes, 1000 Hz, fast mode ($top/config/vehicle.xml, $top/config/io.xml)" \
	"$got"

# The folders in order: the installed layout beside the program, the way
# back to the checkout, the data folder of PREFIX (make's default).
mapfile -t dirs < <("$abs/vehicle-sim" --help | sed -n '/^Configuration folders, in order:$/,$p')
same "--help lists the configuration folders" "Configuration folders, in order:
  $abs/../share/vehicle
$top/config
  /usr/local/share/vehicle" "${dirs[0]-}
${dirs[1]-}
$(realpath -m "${dirs[2]#  }")
${dirs[3]-}"

dest=$tmp/dest
if ! make -C "$top" --no-print-directory BUILD="$build" DESTDIR="$dest" PREFIX=/usr/local \
	SYSCONFDIR=/etc install >"$tmp/install.log" 2>&1; then
	bad "make install" "$(tail -n 20 "$tmp/install.log")"
	echo "install: $passed passed, $failed failed"
	exit 1
fi
pyver=$(/usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])')
py=usr/local/lib/python$pyver/dist-packages/vehicleservice
same "make install DESTDIR=... writes exactly these files" "etc/vehicle/io.xml 644
etc/vehicle/vehicle.xml 644
usr/local/bin/vehicle-corba 755
usr/local/bin/vehicle-fw 755
usr/local/bin/vehicle-plot 755
usr/local/bin/vehicle-sim 755
usr/local/bin/vehiclectl 755
$py/__init__.py 644
$py/bbox.py 644
$py/client.py 644
$py/errors.py 644
$py/ops.py 644
$py/plot.py 644
$py/stream.py 644
$py/transport.py 644
usr/local/lib/systemd/system/vehicle-fw.service 644
usr/local/share/vehicle/examples/io.xml 644
usr/local/share/vehicle/examples/vehicle-jerk.xml 644
usr/local/share/vehicle/examples/vehicle-linux.xml 644
usr/local/share/vehicle/examples/vehicle-omni-jerk.xml 644
usr/local/share/vehicle/examples/vehicle-omni.xml 644
usr/local/share/vehicle/examples/vehicle.xml 644
usr/local/share/vehicle/io.xml 644
usr/local/share/vehicle/vehicle.xml 644" \
	"$(cd "$dest" && find . ! -type d -printf '%P %m\n' | LC_ALL=C sort)"

same "the installed files are the checkout's" "" "$(
	cd "$top" || exit
	for f in vehicle-sim vehiclectl vehicle-fw vehicle-corba; do
		cmp -s "$abs/$f" "$dest/usr/local/bin/$f" || echo "bin/$f differs"
	done
	cmp -s tools/vehicle-plot "$dest/usr/local/bin/vehicle-plot" || echo "vehicle-plot differs"
	for f in python/vehicleservice/*.py; do
		cmp -s "$f" "$dest/$py/${f##*/}" || echo "$f differs"
	done
	cmp -s config/vehicle.xml "$dest/usr/local/share/vehicle/vehicle.xml" || echo "sim vehicle.xml"
	cmp -s config/io.xml "$dest/usr/local/share/vehicle/io.xml" || echo "sim io.xml"
	cmp -s config/vehicle-linux.xml "$dest/etc/vehicle/vehicle.xml" || echo "etc vehicle.xml"
	grep -qx 'ExecStart=/usr/local/bin/vehicle-fw --config /etc/vehicle/vehicle.xml --port /dev/ttyS0 --log syslog' \
		"$dest/usr/local/lib/systemd/system/vehicle-fw.service" || echo "unit's ExecStart"
)"

got=$(run_sim "$dest/usr/local/bin/vehicle-sim")
same "installed vehicle-sim started elsewhere reads PREFIX/share/vehicle" "rc 0
ok true 25 \"Unpowered\"
vehicle-sim: differential base, 2 axes, 1000 Hz, fast mode ($dest/usr/local/share/vehicle/vehicle.xml, $dest/usr/local/share/vehicle/io.xml)" \
	"$got"

same "installed vehicle-fw's default configuration is SYSCONFDIR's" \
	"                  (default /etc/vehicle/vehicle.xml)" \
	"$("$dest/usr/local/bin/vehicle-fw" --help | sed -n '3p')"

# vehicle-plot and the client from the installed package, not the checkout's.
got=$(cd "$tmp/elsewhere" && PYTHONPATH=$dest/${py%/vehicleservice} PYTHONDONTWRITEBYTECODE=1 \
	/usr/bin/python3 -c 'import vehicleservice.plot as p; print(p.__file__)' 2>&1
	PYTHONPATH=$dest/${py%/vehicleservice} PYTHONDONTWRITEBYTECODE=1 \
		"$dest/usr/local/bin/vehicle-plot" --help 2>&1 | head -n 1)
same "installed vehicle-plot runs on the installed package" "$dest/$py/plot.py
usage: vehicle-plot [-h] [-o OUTPUT] [--describe] [--config CONFIG]" "$got"

echo '<!-- edited on the vehicle -->' >>"$dest/etc/vehicle/vehicle.xml"
echo '<!-- stale -->' >>"$dest/usr/local/share/vehicle/vehicle.xml"
make -C "$top" --no-print-directory BUILD="$build" DESTDIR="$dest" PREFIX=/usr/local \
	SYSCONFDIR=/etc install >"$tmp/install.log" 2>&1
same "a second install keeps SYSCONFDIR's configuration, renews the rest" \
	"rc 0
<!-- edited on the vehicle -->
same" "rc $?
$(tail -n 1 "$dest/etc/vehicle/vehicle.xml")
$(cmp -s "$top/config/vehicle.xml" "$dest/usr/local/share/vehicle/vehicle.xml" && echo same)"

echo "install: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
