#!/bin/sh
# Tick cost in instructions: runs tickcost under callgrind for each scenario,
# one dump per measured call, and prints count, mean, median and max of the
# instructions per call. Also the split of an average cruise tick between
# the firmware's parts (callgrind inclusive costs).
#   tools/bench/tickcost.sh BUILD_DIR/bench/tickcost [scenario...]
set -eu
prog=$1; shift
all=$("$prog" --list) # every scenario (BENCH_SCENARIOS, tools/bench/scenario.h)
[ $# -gt 0 ] || set -- $all
command -v valgrind >/dev/null || { echo "tickcost: valgrind not installed (tools/deps.sh)"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
cg="valgrind --tool=callgrind --collect-atstart=no --toggle-collect=bench_tick --toggle-collect=bench_cmd_retarget --toggle-collect=bench_plan"
for sc in "$@"; do
	find "$tmp" -name "cg.*" -delete
	$cg --callgrind-out-file="$tmp/cg.out" "$prog" "$sc" >"$tmp/log" 2>&1 || { cat "$tmp/log"; exit 1; }
	# Each dump: "desc: Trigger: Client Request: LABEL" and "summary: IR".
	find "$tmp" -name 'cg.out.*' -exec awk '
		/^desc: Trigger: Client Request: / { label = $5 }
		/^summary: / { print label, $2 }' {} + | sort -k1,1 -k2,2n >"$tmp/costs"
	awk -v sc="$sc" '
		{ n[$1]++; v[$1, n[$1]] = $2; s[$1] += $2; if ($2 > 1000) over[$1]++ }
		END {
			for (l in n) {
				med = v[l, int((n[l] + 1) / 2)]
				p99 = v[l, int((n[l] * 99 + 99) / 100)]
				printf "  %-9s %-15s %6d calls  mean %6.0f  median %6d  min %6d  max %6d  p99 %6d  over1000 %5.2f%%\n",
					sc, l, n[l], s[l] / n[l], med, v[l, 1], v[l, n[l]], p99, 100 * over[l] / n[l]
			}
		}' "$tmp/costs" | sort
done
# The black box's recording, in the vehicle tick after the motion tick
# (BENCH_RECORD=1 with a scenario list):
# its own instructions in each cruise tick, every tick recorded (2 s ring).
if [ "$*" = "$all" ] || [ "${BENCH_RECORD:-0}" = 1 ]; then
	find "$tmp" -name "cg.*" -delete
	BENCH_BBOX=1 valgrind --tool=callgrind --collect-atstart=no \
		--toggle-collect=vehicle_bbox_record --callgrind-out-file="$tmp/cg.out" \
		"$prog" cruise >"$tmp/log" 2>&1 || { cat "$tmp/log"; exit 1; }
	find "$tmp" -name 'cg.out.*' -exec awk '
		/^desc: Trigger: Client Request: / { label = $5 }
		/^summary: / && label == "tick" { print $2 }' {} + | sort -n >"$tmp/costs"
	awk '{ v[++n] = $1; s += $1 }
		END {
			printf "  %-9s %-15s %6d calls  mean %6.0f  median %6d  min %6d  max %6d  (the ring'"'"'s recording alone, out of the motion tick)\n",
				"cruise", "bbox-record", n, s / n, v[int((n + 1) / 2)], v[1], v[n]
		}' "$tmp/costs"
fi
if [ "$*" = "$all" ] || [ "${BENCH_SPLIT:-0}" = 1 ]; then
	find "$tmp" -name "cg.*" -delete
	BENCH_NODUMP=1 $cg --callgrind-out-file="$tmp/cg.out" "$prog" cruise >"$tmp/log" 2>&1
	echo "  split of the cruise ticks (inclusive instructions per tick, callees counted in callers):"
	n=$(sed -n 's/^cruise: \([0-9]*\) measured.*/\1/p' "$tmp/log")
	callgrind_annotate --inclusive=yes --threshold=100 "$tmp/cg.out" 2>/dev/null |
		awk -v n="$n" '
		# "1,234 (12.3%)  file.c:function [object]"
		/file:function/ { on = 1; next }
		on && /^-+$/ && seen { exit }
		on && $1 ~ /^[0-9,]+$/ {
			seen = 1; p = ""
			for (i = 2; i <= NF; i++) if ($i ~ /:/) { p = $i; break }
			if (p !~ /(^|\/)(firmware|hal)\// || p ~ /\.h:/) next
			c = $1; gsub(",", "", c); k = split(p, f, ":"); name = f[k]
			# The same function may be listed twice (absolute and relative path).
			if (!(name in best)) order[++m] = name
			if (c > best[name]) best[name] = c
		}
		END {
			for (i = 1; i <= m; i++)
				if (best[order[i]] / n >= 5)
					printf "    %-22s %7.1f\n", order[i], best[order[i]] / n
		}'
fi
