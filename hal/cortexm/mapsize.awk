# Flash and RAM of a GNU ld map file, grouped by origin: firmware/, proto/,
# the board (hal/cortexm) and each toolchain library.
#   awk -f mapsize.awk vehicle.map
function hex(s,    i, c, v) {
	v = 0
	s = tolower(s)
	sub(/^0x/, "", s)
	for (i = 1; i <= length(s); i++) {
		c = index("0123456789abcdef", substr(s, i, 1)) - 1
		v = v * 16 + c
	}
	return v
}
/^Linker script and memory map/ { on = 1 }
/^\/DISCARD\// { on = 0 }
!on { next }
/^ \.(text|rodata|data|bss|isr_vector|ARM)/ {
	sec = $1
	if (NF >= 4) { size = $3; file = $4 } else { getline; size = $2; file = $3 }
	if (size !~ /^0x/) next
	if (file ~ /libfirmware\.a/) g = "firmware/"
	else if (file ~ /libproto\.a/) g = "proto/"
	else if (file ~ /cortexm/) g = "hal/cortexm/ (board; RAM: unit, console, link)"
	else { g = file; sub(/.*\//, "", g); sub(/\(.*/, "", g) }
	if (sec ~ /^\.bss/) ram[g] += hex(size)
	else if (sec ~ /^\.data/) { ram[g] += hex(size); flash[g] += hex(size) }
	else flash[g] += hex(size)
	seen[g] = 1
}
END {
	for (g in seen)
		printf "  %-44s flash %6d  RAM %6d\n", g, flash[g], ram[g]
}
