#!/bin/sh
# Accuracy and cost of the fixed-point engine against the double reference.
# Runs the accuracy program once natively (its report) and once under
# callgrind (instructions per tick of each side, one dump per motion).
#   tools/bench/accuracy.sh BUILD_DIR/bench/accuracy
set -eu
prog=$1
"$prog" | grep -v '^  calls:'
command -v valgrind >/dev/null || { echo "accuracy: valgrind not installed (tools/deps.sh)"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
valgrind --tool=callgrind --collect-atstart=no --toggle-collect=eng_tick --toggle-collect=ref_tick \
	--callgrind-out-file="$tmp/cg.out" "$prog" >"$tmp/log" 2>"$tmp/err" || { cat "$tmp/err"; exit 1; }
echo "cost per tick (callgrind instructions, x86-64 -O2; reference: double with libm):"
printf '  %-8s %12s %12s %9s\n' motion engine reference ref/eng
for f in "$tmp"/cg.out.*; do
	label=$(sed -n 's/^desc: Trigger: Client Request: //p' "$f")
	calls=$(sed -n "s/^  calls: $label engine \([0-9]*\) reference \([0-9]*\)/\1 \2/p" "$tmp/log")
	callgrind_annotate --inclusive=yes --threshold=100 "$f" 2>/dev/null | awk -v calls="$calls" -v label="$label" '
		/file:function/ { on = 1; next }
		on && $1 ~ /^[0-9,]+$/ {
			c = $1; gsub(",", "", c)
			for (i = 2; i <= NF; i++) {
				if ($i ~ /:eng_tick$/ && c > e) e = c
				if ($i ~ /:ref_tick$/ && c > r) r = c
			}
		}
		END {
			split(calls, n, " ")
			ee = e / n[1]; rr = r / n[2]
			printf "  %-8s %12.0f %12.0f %7.2fx\n", label, ee, rr, rr / ee
		}'
done
