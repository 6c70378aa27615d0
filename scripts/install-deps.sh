#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Debian 12 packages bspf builds and tests with. Does nothing when
# all are present; uses sudo only when not run as root.
set -euo pipefail

packages=(
  cmake g++ make pkg-config
  ninja-build         # the package tests build consumers with Ninja (tests/package)
  libassimp-dev       # bspc: mesh import (compiler only; the runtime never links it)
  libeigen3-dev       # geometry maths, header-only
  libflatbuffers-dev  # blob format: runtime reader, compiler writer
  flatbuffers-compiler # flatc generates the schema header at build time
  libcli11-dev        # command-line parsing for bspc and the samples
  catch2              # test framework (v2 as packaged in Debian 12)
  clang               # the fuzz targets (scripts/fuzz.sh): libFuzzer needs clang
  libclang-rt-14-dev  # libFuzzer and the sanitizer runtimes for clang 14
)
if [ "${BSPF_WITH_BENCH:-0}" = 1 ]; then
  packages+=(libbenchmark-dev libbullet-dev gnuplot-nox)
fi
# scripts/cross-windows.sh: the mingw-w64 cross compiler (posix threads, for
# std::thread) and wine to run its programs.
if [ "${BSPF_WITH_WINDOWS:-0}" = 1 ]; then
  packages+=(g++-mingw-w64-x86-64-posix wine wine64)
fi
# scripts/clang-build.sh: the whole project built with clang too.
if [ "${BSPF_WITH_CLANG:-0}" = 1 ]; then
  packages+=(clang)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=()
[ "$(id -u)" -eq 0 ] || sudo=(sudo)
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
