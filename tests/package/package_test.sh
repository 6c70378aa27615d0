#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The package tests (ctest label `package`, tests/CMakeLists.txt): bspf as a
# game's build sees it.
#   package_test.sh MODE SOURCE_DIR BUILD_DIR WORK_DIR NINJA CXX BSPC
# MODE:
#   install       cmake --install BUILD_DIR to WORK_DIR/prefix; the expected
#                 files are there, the runtime's private headers are not
#   find-package  a consumer (tests/package/installed) finds the installed
#                 package, compiles two levels with bspf_add_levels and the
#                 installed bspc, links bspf::runtime and steps a body
#   rebuild       in that consumer's build: touching one mesh re-runs bspc for
#                 its level only (ninja -n, then ninja's output), with the same
#                 bytes; each level's step depends on its mesh and bspc only
#   pkg-config    a consumer compiled by hand with `pkg-config --cflags --libs
#                 bspf` against the prefix, run on a level the installed bspc
#                 compiled
#   subproject    a consumer (tests/package/subproject) with bspf from
#                 add_subdirectory and assimp, CLI11 and Catch2 not findable:
#                 only the runtime is built, without warnings flags on the
#                 consumer's own file (BSPC, the build's, compiles its level)
# Each prints what it checked and exits non-zero on the first failure.
set -euo pipefail
mode=$1 src=$2 build=$3 work=$4 ninja=$5 cxx=$6 bspc=$7
prefix=$work/prefix
consumer_build=$work/installed-build
meshes=$work/meshes
consumer_src=$src/tests/package/consumer.cpp

fail() { echo "FAIL: $*" >&2; exit 1; }

case $mode in
install)
  rm -rf "$prefix"
  cmake --install "$build" --prefix "$prefix" >"$work/install.log"
  for f in bin/bspc include/bspf/world.h include/bspf/movement.h include/bspf/bspf_generated.h \
           include/bspc/compile.h share/man/man1/bspc.1; do
    [ -f "$prefix/$f" ] || fail "not installed: $f"
  done
  for f in libbspf_runtime.a libbspc_lib.a cmake/bspf/bspfConfig.cmake \
           cmake/bspf/bspfConfigVersion.cmake cmake/bspf/bspfLevels.cmake \
           cmake/bspf/bspfRuntimeTargets.cmake cmake/bspf/bspfBspcTargets.cmake \
           cmake/bspf/bspfCompilerTargets.cmake pkgconfig/bspf.pc; do
    [ -n "$(find "$prefix" -path "*/lib*/$f")" ] || fail "not installed: lib/$f"
  done
  for f in mapped_file.h slide.h workspace.h; do
    [ -z "$(find "$prefix" -name "$f")" ] || fail "a private header was installed: $f"
  done
  "$prefix/bin/bspc" --version
  echo "ok: $(find "$prefix" -type f | wc -l) files installed in $prefix"
  ;;

find-package)
  rm -rf "$consumer_build" "$meshes"
  mkdir -p "$meshes"
  cp "$src/samples/box_room.obj" "$src/samples/slopes.obj" "$meshes/"
  cmake -S "$src/tests/package/installed" -B "$consumer_build" -G Ninja \
    -DCMAKE_MAKE_PROGRAM="$ninja" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$prefix" \
    -DLEVEL_SOURCES="$meshes/box_room.obj;$meshes/slopes.obj" \
    -DCONSUMER_SOURCE="$consumer_src" >"$work/installed-configure.log"
  "$ninja" -C "$consumer_build" >"$work/installed-build.log"
  # bspc ran from the prefix, not from bspf's build.
  # Captured first: under pipefail, `ninja | grep -q` fails whenever grep
  # quits before ninja has written everything (ninja then dies of SIGPIPE).
  level_commands=$("$ninja" -C "$consumer_build" -t commands levels)
  grep -q "&& $prefix/bin/bspc " <<<"$level_commands" ||
    fail "the levels were not compiled by the installed bspc"
  "$consumer_build/consumer" "$consumer_build/levels/box_room.bspf"
  "$prefix/bin/bspc" --info "$consumer_build/levels/slopes.bspf" >/dev/null
  echo "ok: find_package(bspf) consumer built, levels box_room.bspf and slopes.bspf compiled"
  ;;

rebuild)
  [ -f "$consumer_build/levels/slopes.bspf" ] || fail "no consumer build (find-package first)"
  dry=$("$ninja" -C "$consumer_build" -n)
  case $dry in *"no work to do"*) ;; *) fail "a fresh build still has work: $dry" ;; esac
  cp "$consumer_build/levels/slopes.bspf" "$work/slopes.before.bspf"
  touch "$meshes/slopes.obj"
  dry=$("$ninja" -C "$consumer_build" -n)
  [ "$(grep -c 'compiling level' <<<"$dry")" = 1 ] || fail "ninja -n plans other than one level: $dry"
  grep -q 'compiling level levels/slopes.bspf' <<<"$dry" || fail "ninja -n does not plan slopes: $dry"
  out=$("$ninja" -C "$consumer_build")
  echo "$out"
  [ "$(grep -c 'compiling level' <<<"$out")" = 1 ] || fail "ninja ran other than one level"
  grep -q 'compiling level levels/slopes.bspf' <<<"$out" || fail "ninja did not recompile slopes"
  ! grep -q 'Linking' <<<"$out" || fail "ninja relinked the consumer for a level"
  cmp "$work/slopes.before.bspf" "$consumer_build/levels/slopes.bspf" ||
    fail "the same mesh and options gave other bytes"
  # Each level's step reads its own mesh and bspc: nothing orders the two
  # steps, so ninja runs them side by side.
  for level in box_room slopes; do
    inputs=$("$ninja" -C "$consumer_build" -t query "levels/$level.bspf" |
             awk '/^  input:/ {on = 1; next} /^  outputs:/ {on = 0} on {print $1}' | tr '\n' ' ')
    [ "$inputs" = "$meshes/$level.obj $prefix/bin/bspc " ] || fail "levels/$level.bspf depends on: $inputs"
  done
  echo "ok: touching slopes.obj recompiled levels/slopes.bspf only (same bytes); each level depends on its mesh and bspc only"
  ;;

pkg-config)
  pc=$(dirname "$(find "$prefix" -name bspf.pc)")
  out=$work/pkg-config
  rm -rf "$out"
  mkdir -p "$out"
  version=$(PKG_CONFIG_PATH=$pc pkg-config --modversion bspf)
  flags=$(PKG_CONFIG_PATH=$pc pkg-config --cflags --libs bspf)
  echo "bspf.pc: version $version, flags: $flags"
  # shellcheck disable=SC2086 # the flags are words
  "$cxx" -std=c++20 "$consumer_src" $flags -o "$out/consumer"
  "$prefix/bin/bspc" --quiet "$src/samples/box_room.obj" -o "$out/box_room.bspf"
  "$out/consumer" "$out/box_room.bspf"
  echo "ok: pkg-config consumer built and run"
  ;;

subproject)
  out=$work/subproject-build
  rm -rf "$out"
  cmake -S "$src/tests/package/subproject" -B "$out" -G Ninja \
    -DCMAKE_MAKE_PROGRAM="$ninja" -DCMAKE_CXX_COMPILER="$cxx" -DBSPF_SOURCE_DIR="$src" \
    -DCONSUMER_SOURCE="$consumer_src" -DCMAKE_DISABLE_FIND_PACKAGE_assimp=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON -DCMAKE_DISABLE_FIND_PACKAGE_Catch2=ON \
    >"$work/subproject-configure.log"
  "$ninja" -C "$out" >"$work/subproject-build.log"
  # What the default build made: the runtime and the consumer, nothing else.
  built=$(cd "$out" && find . -path ./CMakeFiles -prune -o -type f \( -name '*.a' -o -name '*.so' -o -perm -u+x \) \
          -print | grep -v '/CMakeFiles/' | sed 's|^\./||' | sort | tr '\n' ' ')
  [ "$built" = "bspf/runtime/libbspf_runtime.a consumer " ] || fail "the default build made: $built"
  commands=$("$ninja" -C "$out" -t commands consumer)
  consumer_compile=$(grep -- '-c [^ ]*consumer.cpp' <<<"$commands") || fail "no compile of consumer.cpp"
  ! grep -q -- '-Wall' <<<"$consumer_compile" || fail "warnings flags reached the parent: $consumer_compile"
  grep -q -- '-std=[a-z+]*20' <<<"$consumer_compile" || fail "no C++20 from bspf::runtime: $consumer_compile"
  grep -- '-c [^ ]*world.cpp' <<<"$commands" | grep -- '-Wall' >/dev/null ||
    fail "bspf's own files lost their warnings"
  "$bspc" --quiet "$src/samples/box_room.obj" -o "$out/box_room.bspf"
  "$out/consumer" "$out/box_room.bspf"
  echo "ok: subproject built the runtime and the consumer only ($built)"
  ;;

*) fail "unknown mode $mode" ;;
esac
