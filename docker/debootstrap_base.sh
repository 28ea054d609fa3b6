#!/bin/sh
# Create (once) a minimal Debian root filesystem: the stand-in for `debian:SUITE`.
#
# Usage: debootstrap_base.sh ROOT [SUITE [MIRROR]]   (as root; defaults: sid, and the
# Debian archive this host's apt already uses)
# Reuses ROOT if a previous run completed it. apt inside is told to accept an
# expired Release file: the reachable archive can serve one.
set -eu

root=${1:?usage: debootstrap_base.sh ROOT [SUITE [MIRROR]]}
suite=${2:-sid}
host_mirror() {  # first Debian archive URI of the host's apt sources (deb822 or one-line)
    { grep -hs '^URIs:' /etc/apt/sources.list.d/*.sources | awk '{print $2}'
      grep -hs '^deb ' /etc/apt/sources.list /etc/apt/sources.list.d/*.list | awk '{print $2}'
    } | grep -v -- '-security' | grep '/debian/*$' | head -n 1
}
mirror=${3:-$(host_mirror)}
[ -n "$mirror" ] || { echo "debootstrap_base.sh: no Debian archive in the host's apt sources; pass MIRROR" >&2; exit 2; }
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
