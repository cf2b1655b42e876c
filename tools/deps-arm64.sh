#!/bin/sh
# Cross toolchain and arm64 -dev packages for CROSS_COMPILE=aarch64-linux-gnu-.
# Idempotent; as yourself or as root (sudo is asked only for what needs root).
set -e
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
dpkg --print-foreign-architectures | grep -qx arm64 ||
	{ as_root dpkg --add-architecture arm64; as_root apt-get update -qq; }
PKGS="gcc-aarch64-linux-gnu libc6-dev-arm64-cross libexpat1-dev:arm64 libgpiod-dev:arm64 \
libmodbus-dev:arm64 libevdev-dev:arm64 file"
missing=""
for p in $PKGS; do
	dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
	echo "installing:$missing"
	as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
		$missing >/dev/null
fi
