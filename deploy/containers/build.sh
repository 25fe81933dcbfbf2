#!/usr/bin/env bash
# Builds Lockstep's container images from Debian alone (no registry):
#   1. localhost/lockstep/debian-min:bookworm  debootstrap --variant=minbase bookworm, podman import
#   2. localhost/lockstep/runtime               + the runtime libraries (Containerfile.runtime)
#   3. localhost/lockstep/<service>             coordinator air_sim ground_sim render sensors recorder
#      localhost/lockstep/client                the lockstep CLI and the Python packages
#      localhost/lockstep/discovery             a Fast DDS Discovery Server (Kubernetes)
# The programs are copied from a build dir (default: build/ at the repository root, made by
# ./dev build): the images hold the same binaries the tests ran, plus Debian's runtime
# packages only.
#
#   deploy/containers/build.sh [--build-dir DIR] [--rebuild-base] [IMAGE ...]
#
# Needs root (debootstrap) and Debian's podman, runc and debootstrap
# (apt-get install podman runc debootstrap). PODMAN overrides the podman command
# (default: deploy/containers/podman, which adds runc/cgroupfs settings). Prints each
# image's size and how long it took.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build_dir="$root/build"
rebuild_base=0
images=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) build_dir=$(cd "$2" && pwd); shift 2 ;;
    --rebuild-base) rebuild_base=1; shift ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    -*) echo "build.sh: unknown option $1" >&2; exit 2 ;;
    *) images+=("$1"); shift ;;
  esac
done
all=(coordinator air_sim ground_sim render sensors recorder client discovery)
[ ${#images[@]} -gt 0 ] || images=("${all[@]}")
for i in "${images[@]}"; do
  [ -f "$here/Containerfile.$i" ] || { echo "build.sh: no image '$i' (have: ${all[*]})" >&2; exit 2; }
done
PODMAN=${PODMAN:-$here/podman}
work=${LOCKSTEP_CONTAINER_WORK:-/var/tmp/lockstep-containers}
mkdir -p "$work"
base=localhost/lockstep/debian-min:bookworm

timed() { local t0=$SECONDS; "$@"; echo "build.sh: $((SECONDS - t0)) s"; }

# 1. The base image, from Debian's archive by debootstrap.
if [ $rebuild_base = 1 ] || ! $PODMAN image exists "$base"; then
  command -v debootstrap >/dev/null || { echo "build.sh: debootstrap missing (apt-get install debootstrap)" >&2; exit 1; }
  echo "build.sh: $base: debootstrap --variant=minbase bookworm"
  t0=$SECONDS
  rm -rf "$work/rootfs"
  debootstrap --variant=minbase bookworm "$work/rootfs" "${LOCKSTEP_DEBIAN_MIRROR:-http://deb.debian.org/debian}" >"$work/debootstrap.log" 2>&1 \
    || { tail -20 "$work/debootstrap.log" >&2; exit 1; }
  tar -C "$work/rootfs" -c . | $PODMAN import - "$base" >/dev/null
  rm -rf "$work/rootfs"
  echo "build.sh: $base in $((SECONDS - t0)) s"
fi

# 2. The build context: programs, Python packages, maps and QoS files.
ctx="$work/context"
rm -rf "$ctx"
mkdir -p "$ctx/bin" "$ctx/qos"
for p in lockstep lockstep-map lockstep_coordinator lockstep_air_sim lockstep_ground_sim lockstep_render \
         lockstep_sensors lockstep_recorder; do
  [ -x "$build_dir/bin/$p" ] || { echo "build.sh: $build_dir/bin/$p missing: build it first (./dev build)" >&2; exit 1; }
  cp "$build_dir/bin/$p" "$ctx/bin/"
done
strip --strip-unneeded "$ctx"/bin/* 2>/dev/null || true
[ -d "$build_dir/python/lockstep" ] || { echo "build.sh: $build_dir/python missing (target lockstep_python)" >&2; exit 1; }
cp -r "$build_dir/python" "$ctx/python"
find "$ctx/python" -name __pycache__ -prune -exec rm -rf {} +
strip --strip-unneeded "$ctx"/python/lockstep/_lockstep*.so 2>/dev/null || true
cp -r "$build_dir/maps" "$ctx/maps"
cp "$root/deploy/qos/fastdds.xml" "$ctx/qos/fastdds.xml"
cp "$root/deploy/multihost/fastdds.xml" "$ctx/qos/multihost.xml"
cp "$here"/Containerfile.* "$ctx/"
cp -r "$here/scripts" "$ctx/scripts"

# 3. The images.
build_one() {
  local name=$1 t0=$SECONDS
  $PODMAN build --quiet --network host -f "$ctx/Containerfile.$name" -t "localhost/lockstep/$name:latest" "$ctx" >/dev/null
  local size
  size=$($PODMAN image inspect --format '{{.Size}}' "localhost/lockstep/$name:latest")
  printf 'build.sh: localhost/lockstep/%-11s %4d MB  %3d s\n' "$name" $((size / 1000000)) $((SECONDS - t0))
}
need_runtime=0
for i in "${images[@]}"; do [ "$i" = discovery ] || need_runtime=1; done
[ $need_runtime = 0 ] || build_one runtime
for i in "${images[@]}"; do build_one "$i"; done
# The images these replaced (untagged now): Lockstep's only (label org.lockstep.image).
$PODMAN image prune -f --filter label=org.lockstep.image=1 >/dev/null || true
