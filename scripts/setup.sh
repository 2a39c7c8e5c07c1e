#!/usr/bin/env bash
# Installs every Debian package the workspace needs (scripts/deps.txt plus any extra names given as
# arguments). Idempotent: when everything is installed it only checks and returns in about a second.
# Needs root (or sudo) on a Debian 12 machine.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

mapfile -t wanted < <(sed -e 's/#.*//' -e 's/[[:space:]]//g' "$here/deps.txt" | grep -v '^$')
wanted+=("$@")

missing=()
for pkg in "${wanted[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$pkg")
done

# roslaunch and rostest address this machine as "localhost"; a minimal system may lack the entry.
if ! getent hosts localhost >/dev/null 2>&1; then
  if [[ $(id -u) -eq 0 ]]; then
    echo "setup: 'localhost' does not resolve (roslaunch needs it); adding '127.0.0.1 localhost' to /etc/hosts"
    echo "127.0.0.1 localhost" >> /etc/hosts
  else
    echo "setup: 'localhost' does not resolve; add '127.0.0.1 localhost' to /etc/hosts (roslaunch needs it)" >&2
  fi
fi

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "setup: all ${#wanted[@]} Debian packages are installed"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "setup: need root to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get -o DPkg::Lock::Timeout=600 update -qq
$SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
