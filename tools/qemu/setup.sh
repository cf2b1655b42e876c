#!/bin/bash
# Prepares the host for QEMU guest tests: installs the Debian guest kernel with
# matching headers, qemu and the userspace tools copied into the guest, then
# builds the gpio test chip module. Idempotent: a second run only re-checks.
#
#   tools/qemu/setup.sh            (run as root; BUILD= overrides build/)
#
# Writes build/qemu/kver (guest kernel release) and build/qemu/gpio_testchip.ko.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/../.." && pwd)
build=${BUILD:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
out=$build/qemu

# The guest kernel and its headers come from the same metapackage series, so
# one apt transaction always yields an image and headers of the same version.
kmeta_image=linux-image-6.12-amd64
kmeta_headers=linux-headers-6.12-amd64
packages=(qemu-system-x86 "$kmeta_image" "$kmeta_headers" busybox-static can-utils gpiod
	libgpiod-dev iproute2 cpio kmod xz-utils zstd gzip build-essential python3-can)

t0=$(date +%s)
log() { printf 'qemu-setup: %s\n' "$*"; }
die() { printf 'qemu-setup: error: %s\n' "$*" >&2; exit 1; }

missing=()
for p in "${packages[@]}"; do
	st=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
	[ "$st" = "install ok installed" ] || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
	[ "$(id -u)" -eq 0 ] || die "packages missing (${missing[*]}); run once as root"
	log "installing: ${missing[*]}"
	export DEBIAN_FRONTEND=noninteractive
	# A retry after 'apt-get update' covers a stale package index.
	if ! apt-get install -y -q --no-install-recommends "${missing[@]}"; then
		apt-get update -q
		apt-get install -y -q --no-install-recommends "${missing[@]}"
	fi
else
	log "packages already installed"
fi

vi=$(dpkg-query -W -f='${Version}' "$kmeta_image")
vh=$(dpkg-query -W -f='${Version}' "$kmeta_headers")
[ "$vi" = "$vh" ] || die "$kmeta_image $vi and $kmeta_headers $vh differ: apt-get install both again"

# The metapackage depends on exactly one versioned image package; its name
# carries the kernel release (linux-image-<release>).
dep=$(dpkg-query -W -f='${Depends}' "$kmeta_image")
kver=$(printf '%s\n' "$dep" | sed -n 's/^linux-image-\([^ ,]*\).*/\1/p')
[ -n "$kver" ] || die "cannot derive the kernel release from '$kmeta_image' ($dep)"
[ -r "/boot/vmlinuz-$kver" ] || die "/boot/vmlinuz-$kver missing"
[ -d "/lib/modules/$kver/kernel" ] || die "/lib/modules/$kver missing"
kdir=/usr/src/linux-headers-$kver
[ -f "$kdir/Makefile" ] || die "$kdir missing: linux-headers-$kver not installed"
mkdir -p "$out"
printf '%s\n' "$kver" >"$out/kver"
log "guest kernel $kver"

# Out-of-tree build in a copy under build/ so the source folder stays clean.
modsrc=$here/gpio-testchip
modbuild=$out/gpio-testchip
mkdir -p "$modbuild"
for f in gpio_testchip.c Kbuild; do
	cmp -s "$modsrc/$f" "$modbuild/$f" || cp "$modsrc/$f" "$modbuild/$f"
done
# A kernel change invalidates the old object.
if [ "$(cat "$modbuild/.kver" 2>/dev/null)" != "$kver" ]; then
	rm -f "$modbuild"/*.o "$modbuild"/*.ko "$modbuild"/*.mod*
	printf '%s\n' "$kver" >"$modbuild/.kver"
fi
make -s -C "$kdir" M="$modbuild" modules >"$modbuild/build.log" 2>&1 || {
	cat "$modbuild/build.log" >&2
	die "gpio_testchip module build failed"
}
cp "$modbuild/gpio_testchip.ko" "$out/gpio_testchip.ko"
vermagic=$(modinfo -F vermagic "$out/gpio_testchip.ko")
case $vermagic in "$kver "*) ;; *) die "module vermagic '$vermagic' does not match $kver" ;; esac

log "ready in $(($(date +%s) - t0)) s: kernel /boot/vmlinuz-$kver, module $out/gpio_testchip.ko"
