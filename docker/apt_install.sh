#!/bin/sh
# Install the packages of a package list (docker/packages.txt) with apt.
#
# Usage: apt_install.sh PACKAGES_TXT
#
# Each non-comment line is `NAME [VERSION-GLOB]`. For a glob, the newest
# archive version matching it is installed as NAME=VERSION; no match is an
# error naming the package, raised before anything is installed.
set -eu

list=${1:?usage: apt_install.sh PACKAGES_TXT}
[ -r "$list" ] || { echo "apt_install.sh: cannot read package list $list" >&2; exit 2; }

export DEBIAN_FRONTEND=noninteractive
apt-get update

specs=""
while read -r name glob _rest; do
    case "$name" in ''|'#'*) continue ;; esac
    if [ -z "$glob" ]; then
        specs="$specs $name"
        continue
    fi
    version=""
    for candidate in $(apt-cache madison "$name" | awk '{print $3}'); do
        # madison lists newest first; $glob is deliberately unquoted (a pattern)
        case "$candidate" in $glob) version=$candidate; break ;; esac
    done
    if [ -z "$version" ]; then
        echo "apt_install.sh: no version of $name matching '$glob' in the archive" >&2
        exit 1
    fi
    specs="$specs $name=$version"
done < "$list"

# shellcheck disable=SC2086  # word splitting of the package specs is intended
apt-get install -y --no-install-recommends $specs
