#!/bin/sh
# Create (once) a minimal Debian root filesystem: the stand-in for `debian:SUITE`.
#
# Usage: debootstrap_base.sh ROOT [SUITE [MIRROR]]   (as root; defaults: sid, deb.debian.org)
# Reuses ROOT if a previous run completed it. apt inside is told to accept an
# expired Release file: the reachable archive can serve one.
set -eu

root=${1:?usage: debootstrap_base.sh ROOT [SUITE [MIRROR]]}
suite=${2:-sid}
mirror=${3:-http://deb.debian.org/debian}
marker=$root/.slipjoint-debootstrap-done

[ -e "$marker" ] && exit 0
command -v debootstrap >/dev/null ||
    { echo "debootstrap_base.sh: debootstrap missing: apt-get update && apt-get install -y debootstrap" >&2; exit 2; }
echo "== debootstrap $suite into $root"
rm -rf "$root"
debootstrap --variant=minbase "$suite" "$root" "$mirror"
echo 'Acquire::Check-Valid-Until "false";' >"$root/etc/apt/apt.conf.d/99slipjoint-check-valid-until"
rm -f "$root"/var/cache/apt/archives/*.deb
touch "$marker"
