#!/usr/bin/env bash
# Installs the Debian packages impact needs, only those that are missing.
# Non-interactive and idempotent; prints nothing when everything is present.
#   --peers   also the peer libraries the benchmarks compare against when found
#             (bench/): Bullet (libbullet-dev), FCL (libfcl-dev, libccd-dev), ODE (libode-dev)
set -euo pipefail
packages=(cmake g++ make libtbb-dev libeigen3-dev libembree-dev libgtest-dev libbenchmark-dev)
for arg in "$@"; do
  case "$arg" in
    --peers) packages+=(pkg-config libbullet-dev libfcl-dev libccd-dev libode-dev) ;;
    -h|--help) sed -n '2,5s/^# \{0,1\}//p' "$0"; exit 0 ;;
    *) echo "install_deps: unknown option '$arg' (known: --peers)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
echo "install_deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq >/dev/null
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
