#!/bin/bash
# The figures in docs/figures are those of the code as it is (tools/figures.sh
# check); first, on a copy of their inputs, that the check fails, naming the
# figure and the command that remakes it, for each way a figure goes stale.
# Then the README's plot example is the cruise figure's run, and every
# figure's run ends Ready with nothing queued on this build.
# Last line: "figures: N passed, M failed".
#   tests/run_figures_tests.sh [BUILD]     (after make)
set -u
top=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-build}
case $build in /*) ;; *) build=$top/$build ;; esac
passed=0 failed=0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

same() { # same NAME EXPECTED GOT
	if [ "$2" = "$3" ]; then
		echo "figures: PASS $1"
		passed=$((passed + 1))
	else
		echo "figures: FAIL $1"
		printf '  expected:\n%s\n  got:\n%s\n' "$2" "$3"
		failed=$((failed + 1))
	fi
}

# A copy of the checkout's figures and their inputs, each stamped here as
# make figures would (so that the self-test does not hang on whether the
# checkout's own figures are fresh: the last check below says that), and
# the check run there.
copy=$tmp/copy
fresh() {
	rm -rf "$copy"
	mkdir -p "$copy/tools" "$copy/python/vehicleservice" "$copy/host_sim" "$copy/docs"
	cp -r "$top/firmware" "$top/config" "$copy/"
	cp "$top"/host_sim/*.[ch] "$copy/host_sim/"
	cp -r "$top/docs/figures" "$copy/docs/"
	cp "$top/tools/figures.sh" "$top/tools/vehicle-plot" "$copy/tools/"
	cp "$top/python/vehicleservice/plot.py" "$copy/python/vehicleservice/"
	local name file
	for name in $("$copy/tools/figures.sh" list); do
		file=$("$copy/tools/figures.sh" file "$name")
		(cd "$copy" && { echo "# $file: stamped by the self-test"
			tools/figures.sh inputs "$name" | xargs sha256sum
			sha256sum "$file"; } >"$file.stamp")
	done
}
check() { # rc and output of the copy's check
	out=$("$copy/tools/figures.sh" check 2>&1)
	printf 'rc %s\n%s' $? "$out"
}
stale() { # stale FIGURE WHY: the line the check prints
	printf 'figures: docs/figures/%s is older than its inputs (%s); remake it: make figures' "$1" "$2"
}

fresh
same "the copy passes as the checkout does" "rc 0" "$(check)"

echo '/* changed */' >>"$copy/firmware/vehicle.c"
same "a changed firmware file makes both figures stale" "rc 1
$(stale cruise.png "changed: firmware/vehicle.c")
$(stale stops.svg "changed: firmware/vehicle.c")" "$(check)"

fresh
: >"$copy/firmware/motion_new.c"
rm "$copy/host_sim/trace.h"
echo '<!-- changed -->' >>"$copy/config/vehicle.xml"
same "added, removed and changed inputs are named" "rc 1
$(stale cruise.png "changed: config/vehicle.xml; added: firmware/motion_new.c; removed: host_sim/trace.h")
$(stale stops.svg "changed: config/vehicle.xml; added: firmware/motion_new.c; removed: host_sim/trace.h")" \
	"$(check)"

fresh
echo '# changed' >>"$copy/tools/figures.sh"
echo '# changed' >>"$copy/python/vehicleservice/plot.py"
same "the script and the plotter are inputs" "rc 1
$(stale cruise.png "changed: python/vehicleservice/plot.py, tools/figures.sh")
$(stale stops.svg "changed: python/vehicleservice/plot.py, tools/figures.sh")" "$(check)"

fresh
echo '<!-- changed -->' >>"$copy/config/vehicle-omni.xml"
echo 'notes' >"$copy/firmware/notes.txt"
same "a file no figure reads changes nothing" "rc 0" "$(check)"

fresh
echo ' ' >>"$copy/docs/figures/stops.svg"
rm "$copy/docs/figures/cruise.png.stamp"
same "an edited figure and a missing stamp" "rc 1
figures: docs/figures/cruise.png has no stamp (docs/figures/cruise.png.stamp); remake it: make figures
figures: docs/figures/stops.svg is not the figure its stamp was made with; remake it: make figures" \
	"$(check)"

fresh
rm "$copy/docs/figures/cruise.png"
same "a missing figure" "rc 1
figures: docs/figures/cruise.png is missing; remake it: make figures" "$(check)"

out=$("$top/tools/figures.sh" check 2>&1)
same "docs/figures are the figures of the code as it is" "rc 0" "$(printf 'rc %s\n%s' $? "$out")"

# The README shows the cruise figure's run; each figure's run finishes.
script=$("$top/tools/figures.sh" script cruise)
same "the README's plot example is the cruise figure's run" "1" \
	"$(grep -cxF "printf '$script' |" "$top/README.md")"
for name in $("$top/tools/figures.sh" list); do
	script=$("$top/tools/figures.sh" script "$name")
	# shellcheck disable=SC2059 # the script is a printf format, as in the README
	printf "$script" | (cd "$tmp" && "$build/vehicle-sim" --fast --trace "$tmp/$name.csv" \
		--trace-every 20 >"$tmp/$name.out" 2>&1)
	same "$name's run is taken whole and ends Ready with nothing queued" "rc 0
taken
16 0" "rc $?
$(grep -v '^vehicle-sim: ' "$tmp/$name.out" | grep -qv '^ok true\|^ok wait\|^ok watchdog' || echo taken)
$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
	{ s = $c["state"]; q = $c["queue_len"] } END { print s, q }' "$tmp/$name.csv")"
done

echo "figures: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
