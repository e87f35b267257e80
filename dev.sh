#!/usr/bin/env bash
# dev.sh: every developer task in one place. `./dev.sh help` lists the verbs.
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(cmake ninja-build g++ clang libclang-rt-14-dev libglm-dev libembree-dev libbullet-dev
          libbenchmark-dev libtinyobjloader-dev libstb-dev libosmesa6-dev libopenscenegraph-dev
          xvfb xauth)
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}

say() { printf '\033[1m==> %s\033[0m\n' "$*"; }

deps() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  say "installing Debian packages: ${missing[*]}"
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
      sudo=(sudo)
    else
      echo "dev.sh: these Debian packages are missing: ${missing[*]}" >&2
      echo "dev.sh: run as root, or give this user sudo, or install them yourself:" >&2
      echo "    apt-get install ${missing[*]}" >&2
      exit 1
    fi
  fi
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

build() {  # build <preset> [targets...]
  local preset=$1; shift
  [ -f "build/$preset/CMakeCache.txt" ] || cmake --preset "$preset" >/dev/null
  local targets=()
  [ $# -gt 0 ] && targets=(--target "$@")
  # clang 14 has been seen to segfault now and then under load (the crash shows as garbage
  # "not valid UTF-8" errors in system headers); one serial retry tells that from a real error.
  cmake --build --preset "$preset" -j "$JOBS" "${targets[@]}" && return 0
  say "build ($preset) failed; retrying once with one job to rule out a compiler crash"
  cmake --build --preset "$preset" -j 1 "${targets[@]}"
}

run_tests() {  # run_tests <preset> [ctest args...]
  local preset=$1; shift
  build "$preset"
  say "ctest ($preset)"
  ctest --preset "$preset" -j "$JOBS" "$@"
}

cmd_demo() {
  deps
  build release cullkit_demo
  mkdir -p out
  say "demo"
  ./build/release/examples/cullkit_demo "${@:-out}"
}

cmd_test() {
  deps
  cmd_fuzz "${FUZZ_SECONDS:-20}"
  say "strict: clang++, C++20, -fno-exceptions -fno-rtti"
  # Tests labelled heavy (real scenes at full size) run in the release preset only: under the
  # sanitizers they take minutes each and check nothing the lighter tests do not also reach.
  run_tests strict --no-tests=error -LE heavy
  run_tests asan --no-tests=error -LE heavy
  run_tests release --no-tests=error
}

cmd_matrix() {
  deps
  for p in clang cxx20 noexcept strict portable; do run_tests "$p" -LE bench; done
}

cmd_bench() {
  deps
  build release
  mkdir -p out/bench
  for b in build/release/bench/bench_*; do
    [ -x "$b" ] || continue
    say "$(basename "$b")"
    "$b" "$@" | tee "out/bench/$(basename "$b").csv"
  done
}

cmd_fuzz() {
  deps
  local seconds=${1:-120}
  rm -f build/fuzz/CMakeCache.txt
  cmake --preset fuzz -DCULLKIT_FUZZ_SECONDS="$seconds" >/dev/null
  build fuzz
  if ! ls fuzz/fuzz_*.cpp >/dev/null 2>&1; then say "fuzz: no fuzzers yet"; return 0; fi
  say "fuzz ($seconds s each)"
  ctest --preset fuzz -j "$JOBS"
}

cmd_asan() { deps; run_tests asan "$@"; }
cmd_deps() { deps; }
cmd_clean() { rm -rf build out; }

cmd_help() {
  cat <<'TXT'
usage: ./dev.sh <verb> [args]
  demo [dir]     build and run the main demo on a generated city; writes PNGs to dir (default out/)
  test           the whole suite: release, ASan+UBSan, clang++ C++20 without exceptions/RTTI,
                 and a bounded libFuzzer run (FUZZ_SECONDS, default 20 per fuzzer)
  bench [args]   build and run every benchmark at full size; CSV to out/bench/
  fuzz [seconds] build the libFuzzer targets with clang and run each for that long (default 120)
  asan [args]    only the ASan+UBSan suite (args go to ctest, e.g. -R abt)
  matrix         every compiler/standard/flag preset: clang, cxx20, noexcept, strict, portable
  deps           install the Debian packages the project needs (apt-get, as root or via sudo)
  clean          remove build/ and out/
Any verb installs missing Debian packages first. JOBS sets build parallelism.
TXT
}

verb=${1:-help}
shift || true
case "$verb" in
  demo|test|bench|fuzz|asan|matrix|deps|clean|help) "cmd_$verb" "$@" ;;
  *) echo "dev.sh: unknown verb '$verb'" >&2; cmd_help >&2; exit 2 ;;
esac
