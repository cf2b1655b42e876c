#!/bin/bash
# Runs a test script inside a QEMU guest (Debian kernel, TCG, no KVM needed)
# with vcan0 up, the gpio test chip and uinput loaded. The guest console is
# streamed to stdout; the exit status is the script's.
#
#   tools/qemu/run-guest.sh [-t SECONDS] [-m MODULE]... [-i] SCRIPT [FILE[=GUESTPATH]]...
#
#   -t SECONDS   host-side limit for the whole boot (default 120); the script
#                itself gets SECONDS-30 inside the guest
#   -m MODULE    extra kernel module to load (see mkinitramfs.sh)
#   -i           guest clock from the instruction count (-icount shift=0,
#                sleep=off): 1 ns per instruction, idle time skipped, so the
#                host's load cannot make a guest timer late (for timing
#                checks inside the guest, e.g. vehicle-fw's tick overrun)
#   FILE         copied into the guest, see mkinitramfs.sh
#
# Exit status: the script's; 124 when a limit was hit; 125 when the guest
# could not be set up; 1 when the guest ended without reporting a result.
# The console log is kept in build/qemu/logs/<script>.log.
set -euo pipefail
# A command that fails under set -e says where (else the run ends silently).
on_err() { echo "run-guest: line $1: \"$2\" failed (status $3)" >&2; }
trap 'on_err $LINENO "$BASH_COMMAND" $?' ERR

here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/../.." && pwd)
build=${BUILD:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
qdir=$build/qemu

die() { printf 'run-guest: error: %s\n' "$*" >&2; exit 1; }
usage() { sed -n '6,15s/^# \{0,1\}//p' "$0" >&2; exit 2; }

limit=120
mkargs=()
clock=()
while getopts "t:m:ih" opt; do
	case $opt in
	t) limit=$OPTARG ;;
	m) mkargs+=(-m "$OPTARG") ;;
	i) clock=(-icount shift=0,sleep=off) ;;
	*) usage ;;
	esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || usage
script=$1; shift
case $limit in '' | *[!0-9]*) die "-t wants whole seconds, got '$limit'" ;; esac
[ "$limit" -ge 40 ] || die "-t below 40 s leaves no time to boot under TCG"
command -v qemu-system-x86_64 >/dev/null || die "qemu-system-x86_64 missing: run tools/qemu/setup.sh"
[ -f "$qdir/kver" ] || die "$qdir/kver missing: run tools/qemu/setup.sh"
kver=$(cat "$qdir/kver")
kernel=/boot/vmlinuz-$kver
[ -r "$kernel" ] || die "$kernel missing: run tools/qemu/setup.sh"

name=$(basename "$script")
name=${name%.sh}
mkdir -p "$qdir/logs"
log=$qdir/logs/$name.log
img=$(mktemp "$qdir/initramfs-$name.XXXXXX.cpio.gz")
# A fresh token per run: output that merely quotes the marker cannot pass.
token=$(od -An -N6 -tx1 /dev/urandom | tr -d ' \n')
# Parallel runs of one script each write their own log; the last one to
# finish is kept under the script's name.
runlog=$log.$token
trap 'rm -f "$img"; [ -f "$runlog" ] && mv -f "$runlog" "$log"' EXIT

t0=$(date +%s.%N)
"$here/mkinitramfs.sh" -o "$img" -t $((limit - 30)) -k "$token" "${mkargs[@]}" "$script" "$@"
t1=$(date +%s.%N)

echo "run-guest: booting $kernel for $script (limit $limit s)"
set +e
trap - ERR
# -nodefaults: no VGA, NIC or option ROMs to set up; the serial port is the
# console. stdin is closed so a run never waits on, or alters, a terminal.
timeout -k 5 "$limit" qemu-system-x86_64 \
	-accel tcg "${clock[@]}" -cpu max -m 512 -smp 1 -nodefaults -no-user-config -no-reboot \
	-display none -serial stdio -monitor none \
	-kernel "$kernel" -initrd "$img" \
	-append "console=ttyS0 quiet panic=-1 oops=panic" </dev/null 2>&1 |
	tr -d '\r' | tee "$runlog"
qrc=${PIPESTATUS[0]}
set -e
trap 'on_err $LINENO "$BASH_COMMAND" $?' ERR
t2=$(date +%s.%N)

result=$(sed -n "s/^.*@@vs-qemu-exit@@ $token rc=\([0-9]*\) uptime=\([0-9.]*\).*/\1 \2/p" "$runlog" | tail -n 1)
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
if [ -z "$result" ]; then
	if [ "$qrc" -eq 124 ] || [ "$qrc" -eq 137 ]; then
		echo "run-guest: FAIL $script: no result within $limit s (guest hung or too slow); log $log"
		exit 124
	fi
	echo "run-guest: FAIL $script: guest ended (qemu status $qrc) without a result marker;" \
		"kernel panic or broken init? log $log"
	exit 1
fi
rc=${result% *}
uptime=${result#* }
echo "run-guest: $script rc=$rc; initramfs $(secs "$t0" "$t1") s, boot-to-result" \
	"$(secs "$t1" "$t2") s wall (guest uptime $uptime s)"
[ "$rc" -eq 125 ] && echo "run-guest: FAIL $script: guest setup failed, see above"
exit "$rc"
