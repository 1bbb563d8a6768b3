#!/usr/bin/env bash
# Installs the Debian packages the build and the tests need. Idempotent: when everything is
# already installed it only runs dpkg-query and returns.
set -euo pipefail
packages=(
  build-essential cmake make ninja-build pkg-config
  libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libyaml-cpp-dev liburdfdom-dev libcli11-dev libtbb-dev libxsimd-dev libccd-dev
  pybind11-dev python3-dev python3-numpy python3-matplotlib python3-pytest
  python3-scipy python3-distributed
  libmujoco-dev libbullet-dev
  # real robots the tests load: MuJoCo's sample MJCF models, DART's URDFs
  libmujoco-samples dart-doc
  clang libclang-rt-14-dev
  nodejs
  # the viewer's tests (tests/cli/view_*.py) drive it headless
  chromium
)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# npm may come from Debian's package or with nodejs itself.
if ! command -v npm >/dev/null 2>&1; then missing+=(npm); fi
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
