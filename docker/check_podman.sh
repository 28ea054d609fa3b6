#!/usr/bin/env bash
# Maintainer check that builds docker/Dockerfile itself, without a Docker
# engine or Docker Hub: Debian's podman builds it on a stand-in for the
# `debian:DEBIAN_TAG` base (a debootstrap minbase root of the same suite,
# imported under that name), which runs the test stage; then the image's
# default command runs with a mounted output folder.
#
# Usage (as root; needs: apt-get install -y debootstrap podman runc):
#   docker/check_podman.sh [--base DIR] [--source DIR] [--output DIR] [--target runtime]
#   --base DIR       minbase root, kept and reused (default /var/tmp/slipjoint-sid-base)
#   --source DIR     checkout to build (default: the one holding this script)
#   --output DIR     folder mounted at /output (default: a new temporary folder)
#   --target runtime build without the test stage
# Exit status: the build's, then the default command's.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
base=/var/tmp/slipjoint-sid-base
source_dir=$(cd "$here/.." && pwd)
output=""
target=()

while [ $# -gt 0 ]; do
    case "$1" in
        --base) base=$2; shift 2 ;;
        --source) source_dir=$(cd "$2" && pwd); shift 2 ;;
        --output) output=$2; shift 2 ;;
        --target) target=(--target "$2"); shift 2 ;;
        *) echo "check_podman.sh: unknown argument '$1' (see the header of $0)" >&2; exit 2 ;;
    esac
done
[ "$(id -u)" = 0 ] || { echo "check_podman.sh: must run as root" >&2; exit 2; }
command -v podman >/dev/null && command -v runc >/dev/null ||
    { echo "check_podman.sh: podman/runc missing: apt-get update && apt-get install -y podman runc" >&2; exit 2; }
dockerfile=$source_dir/docker/Dockerfile
tag=$(sed -nE 's/^ARG DEBIAN_TAG=(.+)$/\1/p' "$dockerfile")
[ -n "$tag" ] || { echo "check_podman.sh: no 'ARG DEBIAN_TAG=...' in $dockerfile" >&2; exit 1; }
suite=${tag%%-*}

# Flags for hosts like the development machines: runc (crun rejects a hybrid
# cgroup v1/v2 host), ulimits within the host's (no CAP_SYS_RESOURCE), host network.
podman=(podman --runtime runc)
limits=(--network host --ulimit "nofile=$(ulimit -Sn):$(ulimit -Hn)" --ulimit nproc=1000:1000)

"$here/debootstrap_base.sh" "$base" "$suite"
if ! "${podman[@]}" image exists "docker.io/library/debian:$tag"; then
    echo "== importing $base as debian:$tag"
    tar -C "$base" --exclude=./.slipjoint-debootstrap-done -c . |
        "${podman[@]}" import --change 'CMD ["bash"]' - "docker.io/library/debian:$tag"
fi

echo "== podman build of $dockerfile ($(git -C "$source_dir" describe --always --dirty 2>/dev/null || echo 'no git'))"
image=localhost/slipjoint-check
if "${podman[@]}" image exists "$image"; then "${podman[@]}" rmi "$image" >/dev/null; fi
start=$(date +%s)
status=0
"${podman[@]}" build "${limits[@]}" "${target[@]}" --ignorefile "$source_dir/docker/Dockerfile.dockerignore" \
    -f "$dockerfile" -t "$image" "$source_dir" || status=$?
if ! "${podman[@]}" image exists "$image" && [ "$status" = 0 ]; then
    status=1  # an interrupted podman build can exit 0 without an image
fi
echo "== build wall time: $(( $(date +%s) - start )) s (exit status $status)"
[ "$status" = 0 ] || { echo "== result: FAILED (build)"; exit "$status"; }

output=${output:-$(mktemp -d /var/tmp/slipjoint-podman-output.XXXXXX)}
mkdir -p "$output"
echo "== default command, output in $output"
"${podman[@]}" run --rm --pull never "${limits[@]}" -v "$output:/output" "$image" || status=$?
ls -l "$output"
echo "== result: $([ "$status" = 0 ] && echo PASSED || echo "FAILED (default command, exit status $status)")"
exit "$status"
