#!/bin/bash
# Builds the guest initramfs: busybox, the CAN/GPIO/input kernel modules with
# their dependencies, can-utils, libgpiod tools, iproute2's ip, a test script
# and any extra files, each dynamic executable with the libraries it needs.
#
#   tools/qemu/mkinitramfs.sh [-o OUT] [-t SECONDS] [-m MODULE]... [-k TOKEN]
#                             SCRIPT [FILE[=GUESTPATH]]...
#
#   -o OUT       output (default build/qemu/initramfs.cpio.gz)
#   -t SECONDS   guest-side time limit for SCRIPT (default 90; exit 124 when hit)
#   -m MODULE    load one more kernel module (with its dependencies) at boot
#   -k TOKEN     marker token, see below (default "local")
#   FILE         copied to /test/<name>, or to GUESTPATH when given; an ELF
#                executable brings its shared libraries and ELF loader along
#
# In the guest /init mounts proc, sys, dev and tmp, loads the modules, brings
# up lo and vcan0, runs SCRIPT with bash in /test (on PATH), then prints
#   @@vs-qemu-exit@@ TOKEN rc=<status> uptime=<seconds>
# and powers off. A setup failure prints the marker with rc=125.
set -euo pipefail
# A command that fails under set -e says where (else the run ends silently).
trap 'echo "mkinitramfs: line $LINENO: \"$BASH_COMMAND\" failed (status $?)" >&2' ERR

here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/../.." && pwd)
build=${BUILD:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
qdir=$build/qemu

die() { printf 'mkinitramfs: error: %s\n' "$*" >&2; exit 1; }
usage() { sed -n '6,14s/^# \{0,1\}//p' "$0" >&2; exit 2; }

out=$qdir/initramfs.cpio.gz
limit=90
token=local
extra_modules=()
while getopts "o:t:m:k:h" opt; do
	case $opt in
	o) out=$OPTARG ;;
	t) limit=$OPTARG ;;
	m) extra_modules+=("$OPTARG") ;;
	k) token=$OPTARG ;;
	*) usage ;;
	esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || usage
script=$1; shift
[ -f "$script" ] || die "test script '$script' not found"
case $limit in '' | *[!0-9]*) die "-t wants whole seconds, got '$limit'" ;; esac
case $token in *[!A-Za-z0-9_-]* | '') die "-k wants [A-Za-z0-9_-]+" ;; esac

[ -f "$qdir/kver" ] || die "$qdir/kver missing: run tools/qemu/setup.sh first"
kver=$(cat "$qdir/kver")
moddir=/lib/modules/$kver
[ -d "$moddir" ] || die "$moddir missing: run tools/qemu/setup.sh"
testchip=$qdir/gpio_testchip.ko
[ -f "$testchip" ] || die "$testchip missing: run tools/qemu/setup.sh"
for tool in busybox cpio gzip modprobe ldd; do
	command -v "$tool" >/dev/null || die "'$tool' not installed: run tools/qemu/setup.sh"
done

mkdir -p "$qdir"
root=$(mktemp -d "$qdir/root.XXXXXX")
trap 'rm -rf "$root"' EXIT

# Merged-/usr layout, so every conventional path resolves.
mkdir -p "$root"/usr/{bin,sbin,lib/x86_64-linux-gnu,lib64} "$root"/{proc,sys,dev,tmp,run,etc,test}
ln -s usr/bin "$root/bin"
ln -s usr/sbin "$root/sbin"
ln -s usr/lib "$root/lib"
ln -s usr/lib64 "$root/lib64"
mkdir -p "$root/lib/modules/$kver"

is_elf() { [ "$(head -c 4 "$1" | od -An -tx1 | tr -d ' \n')" = 7f454c46 ]; }

# Copies an ELF file's shared libraries (as ldd resolves them on this host)
# into /usr/lib/x86_64-linux-gnu under their sonames, and its loader to the
# exact interpreter path the binary names.
declare -A have_lib=()
add_libs() {
	local src=$1 line name path
	local deps
	if ! deps=$(ldd "$src" 2>&1); then
		# Static executables and non-ELF data need nothing.
		case $deps in *"not a dynamic executable"* | *"statically linked"*) return 0 ;; esac
		die "ldd $src failed: $deps"
	fi
	while IFS= read -r line; do
		line=${line#"${line%%[![:space:]]*}"}
		case $line in
		*"=> not found"*) die "$src needs ${line%% *}, which is not installed" ;;
		*" => /"*)
			name=${line%% =>*}
			path=${line#*=> }; path=${path%% (*}
			[ -n "${have_lib[$name]:-}" ] && continue
			cp -L "$path" "$root/usr/lib/x86_64-linux-gnu/$name"
			have_lib[$name]=1
			;;
		/*)
			path=${line%% (*}
			[ -n "${have_lib[$path]:-}" ] && continue
			mkdir -p "$root$(dirname "$path")"
			cp -L "$path" "$root$path"
			have_lib[$path]=1
			;;
		esac
	done <<<"$deps"
}

# Installs one file at a guest path; ELF files bring their libraries.
add_file() {
	local src=$1 dest=$2
	[ -f "$src" ] || die "'$src' not found"
	mkdir -p "$root$(dirname "$dest")"
	cp -L "$src" "$root$dest"
	if is_elf "$src"; then
		add_libs "$src"
	fi
}

# Host tools by name, installed into /usr/bin (or sbin) of the guest.
add_tool() {
	local name=$1 required=$2 path
	path=$(command -v "$name" || true)
	if [ -z "$path" ]; then
		[ "$required" = optional ] && return 0
		die "'$name' not found on the host: run tools/qemu/setup.sh"
	fi
	add_file "$path" "/usr/bin/$name"
}

# busybox provides the shell and base utilities; real tools installed later
# replace its applet links.
bb=$(command -v busybox)
if ! is_elf "$bb" || ldd "$bb" >/dev/null 2>&1; then
	die "$bb is not a static ELF: install busybox-static"
fi
cp "$bb" "$root/usr/bin/busybox"
for applet in $("$bb" --list); do
	[ -e "$root/usr/bin/$applet" ] || ln -s busybox "$root/usr/bin/$applet"
done

replace_tool() {
	rm -f "$root/usr/bin/$1"
	add_tool "$1" "$2"
}
# Test scripts run under bash: busybox sh runs its own applets ahead of PATH,
# which would hide the real tools below behind their busybox namesakes.
replace_tool bash required
# iproute2's ip: busybox ip lacks -details, CAN options and most link kinds.
replace_tool ip required
# isotpsend/isotprecv: the kernel ISO-TP peer of tests/qemu/can_isotp.sh.
for t in cansend candump cangen isotpsend isotprecv; do replace_tool "$t" required; done
for t in isotpdump cansequence canplayer; do replace_tool "$t" optional; done
for t in gpioget gpioset gpiodetect gpioinfo gpiofind gpiomon; do replace_tool "$t" required; done

# Kernel modules, decompressed here (busybox insmod passes the file as is)
# and listed in load order, each once.
: >"$root/etc/modules.order"
declare -A have_mod=()
add_module_file() {
	local src=$1 base
	base=$(basename "$src")
	base=${base%.xz}; base=${base%.zst}; base=${base%.gz}
	[ -n "${have_mod[$base]:-}" ] && return 0
	case $src in
	*.xz) xz -dc "$src" >"$root/lib/modules/$kver/$base" ;;
	*.zst) zstd -qdc "$src" >"$root/lib/modules/$kver/$base" ;;
	*.gz) gzip -dc "$src" >"$root/lib/modules/$kver/$base" ;;
	*) cp "$src" "$root/lib/modules/$kver/$base" ;;
	esac
	have_mod[$base]=1
	printf '%s\n' "$base" >>"$root/etc/modules.order"
}
add_module() {
	local name=$1 required=$2 deps line
	if ! deps=$(modprobe -S "$kver" --show-depends "$name" 2>&1); then
		[ "$required" = optional ] && { echo "mkinitramfs: note: module $name not available, skipped" >&2; return 0; }
		die "module $name: $deps"
	fi
	while IFS= read -r line; do
		case $line in
		"insmod "*)
			line=${line#insmod }
			add_module_file "${line%% *}"
			;;
		"builtin "*) ;;
		*) die "module $name: unexpected modprobe output '$line'" ;;
		esac
	done <<<"$deps"
}
for m in can can-raw can-dev vcan uinput evdev can-isotp; do add_module "$m" required; done
for m in "${extra_modules[@]}"; do add_module "$m" required; done
add_module_file "$testchip"

# The test script and the extra files.
cp "$script" "$root/test/$(basename "$script")"
for f in "$@"; do
	case $f in
	*=/*) add_file "${f%%=*}" "${f#*=}" ;;
	*=*) die "'$f': GUESTPATH must be absolute" ;;
	*) add_file "$f" "/test/$(basename "$f")" ;;
	esac
done

cat >"$root/init" <<EOF
#!/bin/sh
# Guest init, generated by tools/qemu/mkinitramfs.sh.
export PATH=/test:/usr/sbin:/usr/bin HOME=/tmp
token=$token
script=/test/$(basename "$script")
limit=$limit
EOF
cat >>"$root/init" <<'EOF'
finish() {
	up=$(cut -d' ' -f1 /proc/uptime)
	echo "@@vs-qemu-exit@@ $token rc=$1 uptime=$up"
	sync
	poweroff -f
	sleep 10
}
setup_failed() {
	echo "vs-qemu: guest setup failed: $*"
	finish 125
}
mount -t proc proc /proc || setup_failed "mount /proc"
mount -t sysfs sysfs /sys || setup_failed "mount /sys"
mount -t devtmpfs devtmpfs /dev || setup_failed "mount /dev"
mkdir -p /dev/pts /dev/shm
mount -t devpts devpts /dev/pts
mount -t tmpfs tmpfs /tmp || setup_failed "mount /tmp"
mount -t tmpfs tmpfs /run
while read -r mod; do
	insmod "/lib/modules/$(uname -r)/$mod" || setup_failed "insmod $mod"
done </etc/modules.order
/usr/bin/ip link set lo up || setup_failed "lo up"
/usr/bin/ip link add dev vcan0 type vcan || setup_failed "ip link add vcan0"
/usr/bin/ip link set up vcan0 || setup_failed "vcan0 up"
echo "vs-qemu: guest ready at $(cut -d' ' -f1 /proc/uptime) s, running $script (limit $limit s)"
cd /test
timeout "$limit" /usr/bin/bash "$script"
rc=$?
[ $rc -eq 143 ] && echo "vs-qemu: $script hit the $limit s guest limit" && rc=124
finish $rc
EOF
chmod 755 "$root/init"

mkdir -p "$(dirname "$out")"
(cd "$root" && find . -mindepth 1 | LC_ALL=C sort | cpio -o -H newc --quiet -R 0:0) |
	gzip -1 >"$out.tmp"
mv "$out.tmp" "$out"
