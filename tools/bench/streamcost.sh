#!/bin/sh
# The telemetry stream's cost per tick: streamcost under callgrind, one dump
# per poll of the serial server after each tick of the blended cruise, with
# no subscription and with three; the stream's own cost is the difference.
#   tools/bench/streamcost.sh BUILD_DIR/bench/streamcost
set -eu
prog=$1
command -v valgrind >/dev/null || { echo "streamcost: valgrind not installed (tools/deps.sh)"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
for mode in none pose_state_10 all_7 all_1; do
	find "$tmp" -name "cg.*" -delete
	valgrind --tool=callgrind --collect-atstart=no --toggle-collect=bench_poll \
		--callgrind-out-file="$tmp/cg.out" "$prog" "$mode" >"$tmp/log" 2>&1 ||
		{ cat "$tmp/log"; exit 1; }
	frames=$(sed -n 's/.* \([0-9]*\) stream frames.*/\1/p' "$tmp/log")
	find "$tmp" -name 'cg.out.*' -exec awk '/^summary: / { print $2 }' {} + | sort -n >"$tmp/$mode"
	awk -v m="$mode" -v f="$frames" '{ v[++n] = $1; s += $1 }
		END { printf "%s %d %.1f %d %d %d\n", m, n, s / n, v[int((n + 1) / 2)], v[n], f }' \
		"$tmp/$mode" >>"$tmp/sum"
done
awk '
	$1 == "none" { base = $3 }
	{ name[NR] = $1; n[NR] = $2; mean[NR] = $3; med[NR] = $4; max[NR] = $5; fr[NR] = $6 }
	END {
		for (i = 1; i <= NR; i++) {
			extra = mean[i] - base
			printf "  %-14s %5d polls  mean %6.1f  median %5d  max %5d  stream frames %5d", name[i], n[i], mean[i], med[i], max[i], fr[i]
			if (fr[i] > 0)
				printf "  stream: %5.1f a tick, %5.0f a frame", extra, extra * n[i] / fr[i]
			printf "\n"
		}
	}' "$tmp/sum"
