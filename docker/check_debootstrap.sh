#!/usr/bin/env bash
# Maintainer check of the Docker recipe without a Docker engine.
#
# Builds (or reuses) a Debian root filesystem equivalent to docker/Dockerfile:
# the same suite, the same package list (docker/packages.txt, installed by the
# same docker/apt_install.sh) and the same environment (the Dockerfile's
# `ENV KEY=VALUE` lines). Then, as root in a private mount namespace, it mounts
# /proc, /sys, /dev, /dev/pts and a fresh /dev/shm in the root, bind-mounts the
# checkout read-only at /src, copies it to /opt/slipjoint (the image's COPY, without
# what docker/Dockerfile.dockerignore leaves out), installs the project there as the
# image does (pip install --no-deps -e .) and runs the test suite (CTest: lint, serial and
# 2-rank tests, demo --quick runs). It prints the suite's result, its wall time
# and the installed versions of the listed packages.
#
# Usage (as root; needs debootstrap: apt-get update && apt-get install -y debootstrap):
#   docker/check_debootstrap.sh [--root DIR] [--source DIR] [--suite SUITE]
#                               [--mirror URL] [--demo] [-- CTEST_ARGS...]
#   --root DIR    root filesystem, kept and reused (default /var/tmp/slipjoint-sid)
#   --source DIR  checkout to test (default: the one holding this script)
#   --demo        afterwards also run the image's default command (full demo)
# Exit status: the test suite's (and the demo's, with --demo).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=/var/tmp/slipjoint-sid
source_dir=$(cd "$here/.." && pwd)
suite=sid
mirror=  # default: the Debian archive of the host's apt sources (debootstrap_base.sh)
run_demo=false
ctest_args=()

while [ $# -gt 0 ]; do
    case "$1" in
        --root) root=$2; shift 2 ;;
        --source) source_dir=$(cd "$2" && pwd); shift 2 ;;
        --suite) suite=$2; shift 2 ;;
        --mirror) mirror=$2; shift 2 ;;
        --demo) run_demo=true; shift ;;
        --) shift; ctest_args=("$@"); break ;;
        *) echo "check_debootstrap.sh: unknown argument '$1' (see the header of $0)" >&2; exit 2 ;;
    esac
done

packages=$source_dir/docker/packages.txt
dockerfile=$source_dir/docker/Dockerfile
[ "$(id -u)" = 0 ] || { echo "check_debootstrap.sh: must run as root (debootstrap, chroot, mounts)" >&2; exit 2; }
for f in "$packages" "$dockerfile" "$source_dir/CMakeLists.txt"; do
    [ -r "$f" ] || { echo "check_debootstrap.sh: $f not found: is $source_dir a slipjoint checkout?" >&2; exit 2; }
done
case "$root" in "$source_dir"|"$source_dir"/*)
    echo "check_debootstrap.sh: keep the root ($root) outside the checkout" >&2; exit 2 ;;
esac

# 1. Base system, once (the equivalent of `FROM debian:sid-DATE`).
"$here/debootstrap_base.sh" "$root" "$suite" "$mirror"
cp /etc/resolv.conf "$root/etc/resolv.conf"

# 2. The image's packages (idempotent: installs or upgrades to packages.txt).
echo "== apt packages from $packages"
mkdir -p "$root/tmp/slipjoint-docker"
cp "$packages" "$source_dir/docker/apt_install.sh" "$root/tmp/slipjoint-docker/"
chroot "$root" sh /tmp/slipjoint-docker/apt_install.sh /tmp/slipjoint-docker/packages.txt >"$root/tmp/slipjoint-docker/apt.log" 2>&1 ||
    { tail -n 30 "$root/tmp/slipjoint-docker/apt.log"; echo "check_debootstrap.sh: package installation failed" >&2; exit 1; }

# 3. The image's environment: the Dockerfile's single-line `ENV KEY=VALUE` entries.
mapfile -t image_env < <(sed -nE 's/^ENV ([A-Za-z_][A-Za-z0-9_]*=[^ ]*)$/\1/p' "$dockerfile")
[ "${#image_env[@]}" -gt 0 ] || { echo "check_debootstrap.sh: no ENV KEY=VALUE lines in $dockerfile" >&2; exit 1; }

# 4. The suite, inside the root, in a private mount namespace.
cat >"$root/tmp/slipjoint-docker/run_suite.sh" <<'EOF'
#!/bin/sh
# Runs inside the root: the Dockerfile's test stage, then optionally its CMD.
set -u
rm -rf "${XDG_CACHE_HOME:-/root/.cache}/fenics" /tmp/slipjoint-build /tmp/slipjoint-output /opt/slipjoint
mkdir -p /opt/slipjoint
(cd /src && tar --exclude=./.git --exclude=./.venv --exclude=./build --exclude=./output \
    --exclude='*.egg-info' --exclude=__pycache__ --exclude='*.pyc' \
    --exclude=.mypy_cache --exclude=.ruff_cache --exclude=.pytest_cache -cf - .) | tar -C /opt/slipjoint -xf - || exit 1
(cd /opt/slipjoint && python3 -m pip install --quiet --no-deps --no-build-isolation --break-system-packages -e .) || exit 1
python3 -m pip install --quiet --no-deps --break-system-packages "$(grep '^ruff==' /opt/slipjoint/requirements.txt)" || exit 1
cmake -S /opt/slipjoint -B /tmp/slipjoint-build -DPYTHON=/usr/bin/python3 -DMPIEXEC=/usr/bin/mpirun >/dev/null || exit 1
start=$(date +%s)
(cd /tmp/slipjoint-build && ctest --output-on-failure --timeout 3600 "$@")
status=$?
echo "== suite wall time: $(( $(date +%s) - start )) s (exit status $status)"
echo "== pytest counts per CTest test (first rank's line for _mpi2; skips show only here)"
sed 's/\x1b\[[0-9;]*m//g' /tmp/slipjoint-build/Testing/Temporary/LastTest.log | awk '
    / Testing: / { name = $3; shown = 0 }
    /^=* ?[0-9]+ (passed|failed|skipped|error|deselected).* in [0-9.]+s/ && !shown { printf "  %-34s %s\n", name, $0; shown = 1 }'
if [ "${RUN_DEMO:-false}" = true ]; then
    start=$(date +%s)
    (cd /opt/slipjoint && mpirun -n 2 python3 demos/install.py --output /tmp/slipjoint-output)
    demo_status=$?
    echo "== demo wall time: $(( $(date +%s) - start )) s (exit status $demo_status)"
    ls -l /tmp/slipjoint-output
    [ "$status" -ne 0 ] || status=$demo_status
fi
exit "$status"
EOF

echo "== test suite of $source_dir in $root ($(git -C "$source_dir" describe --always --dirty 2>/dev/null || echo 'no git'))"
status=0
unshare --mount --propagation private bash -euo pipefail -s -- \
    "$root" "$source_dir" "$run_demo" "${image_env[@]}" -- "${ctest_args[@]}" <<'EOF' || status=$?
root=$1 source_dir=$2 run_demo=$3; shift 3
env_vars=(); while [ "$1" != -- ]; do env_vars+=("$1"); shift; done; shift
mount -t proc proc "$root/proc"
mount -t sysfs sysfs "$root/sys"
mount --bind /dev "$root/dev"
mount --bind /dev/pts "$root/dev/pts"
mount -t tmpfs -o mode=1777,nosuid,nodev shm "$root/dev/shm"
mkdir -p "$root/src"
mount --bind "$source_dir" "$root/src"
mount -o remount,bind,ro "$root/src"
exec chroot "$root" env -i PATH=/usr/local/bin:/usr/bin:/bin HOME=/root LANG=C.UTF-8 \
    RUN_DEMO="$run_demo" "${env_vars[@]}" sh /tmp/slipjoint-docker/run_suite.sh "$@"
EOF

# 5. What was tested with.
echo "== packages (docker/packages.txt and the stack below them)"
names=$(sed -nE 's/^([a-z0-9][a-z0-9.+-]*).*/\1/p' "$packages")
chroot "$root" dpkg-query -W -f '${Package} ${Version}\n' $names \
    python3 python3.14 libpetsc-real3.25 libslepc-real3.25 libopenmpi40 \
    python3-basix python3-ffcx python3-ufl python3-vtk9 libegl-mesa0 2>/dev/null || true
chroot "$root" dpkg-query -W -f '${Package} ${Version}\n' >"$root/tmp/slipjoint-docker/installed.txt"
echo "(all $(wc -l <"$root/tmp/slipjoint-docker/installed.txt") installed packages: $root/tmp/slipjoint-docker/installed.txt)"
echo "== result: $([ "$status" = 0 ] && echo PASSED || echo "FAILED (exit status $status)")"
exit "$status"
