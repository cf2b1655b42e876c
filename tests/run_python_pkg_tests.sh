#!/bin/sh
# The Python client installed as a package, and the Debian route, each with
# one exchange against vehicle-sim --pty (make check):
#   1. /usr/bin/python3 -m venv --system-site-packages in a temporary folder
#   2. pip install --no-index --no-build-isolation ./python, offline, the line
#      README.md gives (run on a copy, so the checkout gets no build files)
#   3. the package imports from the venv, pyserial and python-can from
#      Debian's python3-serial and python3-can
#   4. getVersion and getState over binary frames, from the venv and from
#      PYTHONPATH=python under /usr/bin/python3
# Last line: "python-pkg: N passed, M failed".
#   tests/run_python_pkg_tests.sh [BUILD]
top=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vs-pkg.XXXXXX")
passed=0
failed=0
sim=
ok() { passed=$((passed + 1)); echo "ok   $*"; }
fail() { failed=$((failed + 1)); echo "FAIL $*"; }
cleanup() {
	[ -n "$sim" ] && kill "$sim" 2>/dev/null && wait "$sim" 2>/dev/null
	rm -rf "$tmp"
}
trap cleanup EXIT
finish() {
	echo "python-pkg: $passed passed, $failed failed"
	[ "$failed" -eq 0 ]
	exit
}
# expect WHAT WANT GOT
expect() {
	if [ "$2" = "$3" ]; then ok "$1"; else fail "$1: got '$3', want '$2'"; fi
}

export PYTHONDONTWRITEBYTECODE=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
unset PYTHONPATH PYTHONHOME VIRTUAL_ENV PIP_INDEX_URL PIP_EXTRA_INDEX_URL

# 1. The virtual environment, over Debian's packages.
venv=$tmp/venv
if /usr/bin/python3 -m venv --system-site-packages "$venv" >"$tmp/venv.log" 2>&1; then
	ok "python3 -m venv --system-site-packages"
else
	fail "python3 -m venv --system-site-packages (python3-venv)"
	cat "$tmp/venv.log"
	finish
fi

# 2. The README's line, offline, on a copy of python/.
mkdir "$tmp/src" "$tmp/elsewhere"
cp -R "$top/python" "$tmp/src/python"
rm -rf "$tmp/src/python/build" "$tmp/src/python/"*.egg-info
if (cd "$tmp/src" && "$venv/bin/pip" install --no-index --no-build-isolation ./python) \
	>"$tmp/pip.log" 2>&1; then
	ok "pip install --no-index --no-build-isolation ./python"
else
	fail "pip install --no-index --no-build-isolation ./python"
	cat "$tmp/pip.log"
	finish
fi
expect "installed version" "Version: 1.0.0" \
	"$("$venv/bin/pip" show vehicleservice 2>&1 | grep '^Version:')"

# 3. Where each module comes from (outside the checkout and the copy).
where='import sys, can, serial, vehicleservice
for m in (vehicleservice, serial, can):
    print(m.__name__, m.__file__)'
site=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
got=$(cd "$tmp/elsewhere" && "$venv/bin/python" -c "$where" 2>&1)
expect "the venv imports the installed package and Debian's pyserial, python-can" \
	"vehicleservice $site/vehicleservice/__init__.py
serial /usr/lib/python3/dist-packages/serial/__init__.py
can /usr/lib/python3/dist-packages/can/__init__.py" "$got"
got=$(cd "$top" && PYTHONPATH=python /usr/bin/python3 -c "$where" 2>&1)
expect "PYTHONPATH=python /usr/bin/python3 imports the checkout's package" \
	"vehicleservice $top/python/vehicleservice/__init__.py
serial /usr/lib/python3/dist-packages/serial/__init__.py
can /usr/lib/python3/dist-packages/can/__init__.py" "$got"

# 4. One exchange each with the simulator on a pty.
"$build/vehicle-sim" --pty --config "$top/config/vehicle.xml" --io "$top/config/io.xml" \
	</dev/null >"$tmp/sim.out" 2>"$tmp/sim.err" &
sim=$!
pty=
i=0
while [ $i -lt 600 ] && [ -z "$pty" ] && kill -0 "$sim" 2>/dev/null; do
	pty=$(head -1 "$tmp/sim.out")
	[ -z "$pty" ] && sleep 0.05
	i=$((i + 1))
done
case $pty in
/dev/*) ok "vehicle-sim --pty on $pty" ;;
*)
	fail "vehicle-sim --pty gave no pty"
	cat "$tmp/sim.err"
	finish
	;;
esac
exchange='import sys, vehicleservice as vs
with vs.open_frames(sys.argv[1], timeout=5.0, retries=2) as v:
    print(v.getVersion())
    print(v.getState())'
want="Reply(result=True, value='Ver.1.0.0')
Reply(result=True, value=State(code=25, message='Unpowered'))"
got=$(cd "$tmp/elsewhere" && "$venv/bin/python" -c "$exchange" "$pty" 2>&1)
expect "getVersion, getState through the installed package" "$want" "$got"
got=$(cd "$top" && PYTHONPATH=python /usr/bin/python3 -c "$exchange" "$pty" 2>&1)
expect "getVersion, getState through PYTHONPATH=python /usr/bin/python3" "$want" "$got"

finish
