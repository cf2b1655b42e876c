#!/bin/bash
# The figures in docs/figures: each made from the current build by running a
# script on vehicle-sim and drawing its trace with vehicle-plot, and each
# with a stamp beside it (FIGURE.stamp): the sha256 of every input that
# determines the figure, then of the figure itself. make check runs `check`,
# which fails naming a figure whose inputs changed since it was made.
#
#   tools/figures.sh make BUILD      make every figure from BUILD/vehicle-sim (make figures)
#   tools/figures.sh check           every stamp against the files as they are now
#   tools/figures.sh list            the figures' names
#   tools/figures.sh file NAME       NAME's figure
#   tools/figures.sh inputs NAME     the files NAME's stamp covers, before the figure
#   tools/figures.sh script NAME     the console lines NAME's run feeds vehicle-sim
#
# A figure's inputs: the firmware (firmware/), the simulated plant and its
# program (host_sim/, not devices/), the configuration files its run reads,
# this script, and vehicle-plot (tools/vehicle-plot, python/vehicleservice/plot.py).
set -u -o pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top" || exit 1
REMAKE="make figures"

FIGURES="cruise stops"

# figure NAME: sets file, configs (its run's vehicle.xml and io.xml), every
# (--trace-every), script (its console lines) and plot (vehicle-plot's options).
figure() {
	case $1 in
	cruise) # the README's example, drawn as it says
		file=docs/figures/cruise.png
		configs="config/vehicle.xml config/io.xml"
		every=20
		script='$watchdog 0\nsetPower true\nsetServo true\nmoveCruiseAbs 1000 0\nmoveCruiseAbs 1000 1000\nmoveCruiseAbs 0 1000\n$wait 11000\n'
		plot=(--config config/vehicle.xml --waypoint 0 0 --waypoint 1000 0
			--waypoint 1000 1000 --waypoint 0 1000
			--title "moveCruiseAbs 1000 0, 1000 1000, 0 1000 (blended corners)")
		;;
	stops) # stops and a turn at a lower set velocity
		file=docs/figures/stops.svg
		configs="config/vehicle.xml config/io.xml"
		every=20
		script='$watchdog 0\nsetPower true\nsetServo true\nsetVelocity 300 60\nmoveForward 600\n$wait 3000\nmoveTurn 90\n$wait 2500\nmoveLinearAbs 600 400 90\n$wait 2500\n'
		plot=(--config config/vehicle.xml --velocity 300 60
			--title "setVelocity 300 60; moveForward 600, moveTurn 90, moveLinearAbs 600 400 90")
		;;
	*)
		echo "figures: no figure $1" >&2
		exit 2
		;;
	esac
}

# inputs NAME: the input files of a figure, one per line, sorted.
inputs() {
	figure "$1"
	printf '%s\n' firmware/*.[ch] firmware/*.def host_sim/*.[ch] $configs tools/figures.sh \
		tools/vehicle-plot python/vehicleservice/plot.py | LC_ALL=C sort -u
}

# hashes NAME: "sha256  path" of each input, then of the figure.
hashes() {
	figure "$1"
	inputs "$1" | tr '\n' '\0' | xargs -0 sha256sum
	sha256sum "$file"
}

make_one() { # make_one NAME BUILD
	local name=$1 build=$2 tmp out vehicle io
	figure "$name"
	read -r vehicle io <<<"$configs"
	tmp=$(mktemp -d)
	# shellcheck disable=SC2059 # the script is a printf format, as in the README
	out=$(printf "$script" | "$build/vehicle-sim" --fast --config "$vehicle" --io "$io" \
		--trace "$tmp/run.csv" --trace-every "$every" 2>&1) || {
		printf '%s\n' "$out"
		echo "figures: $name: vehicle-sim failed" >&2
		return 1
	}
	# Every operation ran and every move was taken (a move refused while
	# the last one still ran answers ok false).
	if printf '%s\n' "$out" | grep -v '^vehicle-sim: ' | grep -qv '^ok ' ||
		printf '%s\n' "$out" | grep -q '^ok false'; then
		printf '%s\n' "$out"
		echo "figures: $name: a line of its script was not taken" >&2
		return 1
	fi
	# The run ends done: Ready with nothing queued.
	local last
	last=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
		{ s = $c["state"]; q = $c["queue_len"] } END { print s, q }' "$tmp/run.csv")
	if [ "$last" != "16 0" ]; then
		echo "figures: $name: the run ends in state and queue '$last', not '16 0' (Ready, empty): wait longer" >&2
		return 1
	fi
	/usr/bin/python3 tools/vehicle-plot "$tmp/run.csv" -o "$file" "${plot[@]}" |
		sed "s|^|$name: |" || return 1
	rm -rf "$tmp"
	{
		echo "# $file: made by tools/figures.sh ($REMAKE) from the files below, then the"
		echo "# figure itself (sha256); make check fails when one of them differs."
		hashes "$name"
	} >"$file.stamp"
	echo "figures: $file and $file.stamp"
}

check_one() { # check_one NAME: 0, or 1 with one line saying why
	local name=$1 want got changed added removed
	figure "$name"
	if [ ! -e "$file" ]; then
		echo "figures: $file is missing; remake it: $REMAKE"
		return 1
	fi
	if [ ! -e "$file.stamp" ]; then
		echo "figures: $file has no stamp ($file.stamp); remake it: $REMAKE"
		return 1
	fi
	want=$(grep -v '^#' "$file.stamp" | grep -v "  $file\$")
	got=$(hashes "$name" | grep -v "  $file\$")
	if [ "$want" != "$got" ]; then
		changed=$(LC_ALL=C join -j 2 <(printf '%s\n' "$want" | LC_ALL=C sort -k 2) \
			<(printf '%s\n' "$got" | LC_ALL=C sort -k 2) | awk '$2 != $3 { print $1 }')
		added=$(LC_ALL=C comm -13 <(printf '%s\n' "$want" | awk '{ print $2 }' | LC_ALL=C sort) \
			<(printf '%s\n' "$got" | awk '{ print $2 }' | LC_ALL=C sort))
		removed=$(LC_ALL=C comm -23 <(printf '%s\n' "$want" | awk '{ print $2 }' | LC_ALL=C sort) \
			<(printf '%s\n' "$got" | awk '{ print $2 }' | LC_ALL=C sort))
		local why=""
		[ -n "$changed" ] && why="changed: $(echo $changed | sed 's/ /, /g')"
		[ -n "$added" ] && why="${why:+$why; }added: $(echo $added | sed 's/ /, /g')"
		[ -n "$removed" ] && why="${why:+$why; }removed: $(echo $removed | sed 's/ /, /g')"
		echo "figures: $file is older than its inputs ($why); remake it: $REMAKE"
		return 1
	fi
	if [ "$(grep "  $file\$" "$file.stamp")" != "$(sha256sum "$file")" ]; then
		echo "figures: $file is not the figure its stamp was made with; remake it: $REMAKE"
		return 1
	fi
	return 0
}

case ${1-} in
make)
	[ $# -eq 2 ] || { echo "usage: tools/figures.sh make BUILD" >&2; exit 2; }
	[ -x "$2/vehicle-sim" ] || { echo "figures: $2/vehicle-sim missing: run make" >&2; exit 1; }
	for f in $FIGURES; do make_one "$f" "$2" || exit 1; done
	;;
check)
	rc=0
	for f in $FIGURES; do check_one "$f" || rc=1; done
	exit $rc
	;;
list)
	echo $FIGURES
	;;
file)
	[ $# -eq 2 ] || { echo "usage: tools/figures.sh file NAME" >&2; exit 2; }
	figure "$2"
	echo "$file"
	;;
inputs)
	[ $# -eq 2 ] || { echo "usage: tools/figures.sh inputs NAME" >&2; exit 2; }
	inputs "$2"
	;;
script)
	[ $# -eq 2 ] || { echo "usage: tools/figures.sh script NAME" >&2; exit 2; }
	figure "$2"
	printf '%s\n' "$script"
	;;
*)
	sed -n '2,/^$/s/^# \{0,1\}//p' "$0" >&2
	exit 2
	;;
esac
