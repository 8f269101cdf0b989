#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (root, or a user with sudo):
#
#   bash scripts/run.sh demo    install what is missing, build, run the main job
#   bash scripts/run.sh test    install what is missing, build, pip install ./python into .venv
#                               (only the bindings: it links build/'s libraries), run every test
#                               (ctest; pytest on the installed package), then the parsers of
#                               users' files (their tests and fuzz targets) again under
#                               AddressSanitizer + UndefinedBehaviorSanitizer; prints the wall
#                               time of each phase
#   bash scripts/run.sh setup   only install what is missing (system packages + .venv)
#   bash scripts/run.sh build   setup, then configure and build build/ (Release)
#   bash scripts/run.sh quick   the developer loop: build/ incrementally, then the fast tests
#                               (ctest labels unit, cli, python; not slow), pytest on build/'s
#                               module; not a substitute for `test`
#
# Arguments after `demo` are passed to the main job. Environment: PCR_JOBS (parallel jobs,
# default nproc), PCR_PYTHON (interpreter for .venv, default python3).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)

# The main job: the whole method on the built-in virtual robot, written to pcr-demo/.
MAIN_JOB=(build/apps/pcr demo)  # writes pcr-demo/ (pcr demo --output)
MAIN_TARGETS=(pcr_cli _pcr)

APT_PACKAGES=(
  build-essential cmake ninja-build pkg-config clang clang-format libclang-rt-14-dev libomp-14-dev
  libeigen3-dev libceres-dev libopencv-dev libapriltag-dev libsundials-dev
  libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev
  python3 python3-dev python3-venv python3-pip
  slurmctld slurmd slurm-client munge
)
# slurmctld, slurmd, slurm-client and munge: the one-node Slurm cluster on which the tests run a
# study through dask-jobqueue's SLURMCluster (python/tests/test_cluster.py, ctest label cluster);
# the test starts its own daemons and stops them (it needs none of the packages' services).
# Python packages of the project virtual environment (.venv); pybind11's minimum is checked below.
# dask, distributed, pandas and pyarrow are pcr.study's (the [study] extra); nbclient, nbformat
# and ipykernel run the example notebook in the tests (python/tests/test_notebook.py);
# dask-jobqueue is SLURMCluster, for test_cluster.py.
PIP_PACKAGES=('pybind11>=2.12' numpy pytest scikit-build-core matplotlib dask distributed pandas
  pyarrow nbclient nbformat ipykernel dask-jobqueue)

JOBS=${PCR_JOBS:-$(nproc)}
VENV=$ROOT/.venv

log() { printf '\n==> %s\n' "$*" >&2; }
die() { printf 'error: %s\n' "$*" >&2; exit 1; }

# ---- system packages -------------------------------------------------------------------------
install_system_packages() {
  local missing=() pkg
  for pkg in "${APT_PACKAGES[@]}"; do
    # `dpkg -s` also succeeds for removed packages that left their config files behind.
    if [[ $(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null) != installed ]]; then
      missing+=("$pkg")
    fi
  done
  if ((${#missing[@]} == 0)); then
    return
  fi
  local sudo=()
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || die "missing packages (${missing[*]}): run as root or install sudo"
    sudo=(sudo)
  fi
  log "Installing ${missing[*]}"
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y --no-install-recommends "${missing[@]}"
}

# ---- Python virtual environment (pip refuses system-wide installs, PEP 668) ------------------
venv_satisfied() {
  "$VENV/bin/python" - "$@" <<'EOF' 2>/dev/null
import re, sys
from importlib.metadata import version
for req in sys.argv[1:]:
    name, _, minimum = req.partition(">=")
    have = version(name)  # raises when missing
    if minimum:
        as_ints = lambda v: [int(x) for x in re.findall(r"\d+", v)[:3]]
        if as_ints(have) < as_ints(minimum):
            sys.exit(1)
EOF
}

setup_venv() {
  local python=${PCR_PYTHON:-python3}
  if ! "$VENV/bin/python" -c '' 2>/dev/null; then
    log "Creating $VENV with $(command -v "$python")"
    rm -rf "$VENV"
    "$python" -m venv "$VENV"
  fi
  if ! venv_satisfied "${PIP_PACKAGES[@]}"; then
    log "Installing ${PIP_PACKAGES[*]} into $VENV"
    "$VENV/bin/python" -m pip install --disable-pip-version-check --quiet "${PIP_PACKAGES[@]}"
  fi
}

# ---- build -----------------------------------------------------------------------------------
# Both build trees and the bindings are compiled by clang, which compiles this tree in less than
# half gcc's time (-O3: src/calib/spatial_calibration.cpp 113 s against 309 s; with the
# sanitizers, calibrator.cpp 53 s against 112 s). libomp-14-dev is for SUNDIALS' CMake package,
# which asks for OpenMP.
CXX_COMPILER=clang++

# configure DIR ARGS...: Ninja and $CXX_COMPILER for a new build tree; an existing one keeps its
# generator, and is made anew if another compiler configured it (CMake cannot switch a tree's).
configure() {
  local dir=$1
  shift
  if [[ -f $dir/CMakeCache.txt ]] &&
    ! grep -q "^CMAKE_CXX_COMPILER:[A-Z]*=.*$CXX_COMPILER\$" "$dir/CMakeCache.txt"; then
    rm -rf "$dir"
  fi
  local generator=()
  [[ -f $dir/CMakeCache.txt ]] || generator=(-G Ninja)
  cmake -S "$ROOT" -B "$dir" "${generator[@]}" "-DCMAKE_CXX_COMPILER=$CXX_COMPILER" "$@"
}

# build_main [--pytest-installed] [cmake --build args]: configure and build build/ (Release), with
# the pybind11 module against .venv. --pytest-installed: ctest's pytest runs on the package
# installed in .venv (install_python_package) instead of the build tree's, whose module is then
# not built.
build_main() {
  local pytest_installed=OFF
  if [[ ${1:-} == --pytest-installed ]]; then
    pytest_installed=ON
    shift
  fi
  local python_args=(-DPCR_BUILD_PYTHON=ON "-DPython_EXECUTABLE=$VENV/bin/python"
    "-Dpybind11_DIR=$("$VENV/bin/python" -m pybind11 --cmakedir)"
    "-DPCR_PYTEST_INSTALLED=$pytest_installed")
  log "Building build/ (Release, $CXX_COMPILER, $JOBS jobs)"
  configure build -DCMAKE_BUILD_TYPE=Release "${python_args[@]}"
  cmake --build build -j "$JOBS" "$@"
}

# `pip install ./python` into .venv, as the README tells users, with the build tools .venv
# already has (no download) and a kept build directory (build/pip) so that a re-run only
# recompiles what changed. pcr_DIR=build: only the bindings are compiled, against the libraries
# build/ has (python/CMakeLists.txt). (--config-settings, not -C: Debian 12's venv pip is 23.0,
# -C is 23.1.)
install_python_package() {
  log "pip install ./python into $VENV"
  CMAKE_BUILD_PARALLEL_LEVEL=$JOBS "$VENV/bin/python" -m pip install --disable-pip-version-check \
    --quiet --no-build-isolation --no-deps --config-settings="build-dir=$ROOT/build/pip" \
    --config-settings="cmake.define.pcr_DIR=$ROOT/build" \
    --config-settings="cmake.define.CMAKE_CXX_COMPILER=$CXX_COMPILER" "$ROOT/python"
}

# phase NAME: the current phase ends and NAME begins; print_timings lists their wall times.
PHASE='' PHASE_START=0 TIMINGS=()
phase() {
  [[ -z $PHASE ]] || TIMINGS+=("$(printf '%-22s %5d s' "$PHASE" $((SECONDS - PHASE_START)))")
  PHASE=$1 PHASE_START=$SECONDS
}
print_timings() {
  phase ''
  ((${#TIMINGS[@]})) || return 0
  printf '\n==> Wall time per phase\n' >&2
  printf '    %s\n' "${TIMINGS[@]}" >&2
  printf '    %-22s %5d s\n' total "$SECONDS" >&2
}

# The C++ sources are formatted by the repository's .clang-format (Debian 12's clang-format 14):
# reports the files that are not, and fails. `clang-format -i FILE` formats one.
check_format() {
  local files
  if git -C "$ROOT" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    mapfile -t files < <(git -C "$ROOT" ls-files '*.cpp' '*.hpp')
  else
    mapfile -t files < <(cd "$ROOT" && find apps benchmarks include python/src src tests \
      -name '*.cpp' -o -name '*.hpp')
  fi
  log "clang-format --dry-run on ${#files[@]} files"
  (cd "$ROOT" && clang-format --dry-run --Werror "${files[@]}")
}

# ---- commands --------------------------------------------------------------------------------
run_demo() {
  install_system_packages
  setup_venv
  local targets=() t
  for t in "${MAIN_TARGETS[@]}"; do targets+=(--target "$t"); done
  build_main "${targets[@]}"
  log "Running ${MAIN_JOB[*]} $*"
  "${MAIN_JOB[@]}" "$@"
  # The figures, drawn from the demo's files by the Python package built in build/python
  # (matplotlib): $out/figures/*.png and $out/figures.md, which report.md links to.
  local out=pcr-demo arg previous=
  for arg in "$@"; do
    [[ $previous == --output ]] && out=$arg
    [[ $arg == --output=* ]] && out=${arg#--output=}
    previous=$arg
  done
  log "Drawing the figures into $out/figures"
  PYTHONPATH=$ROOT/build/python MPLBACKEND=Agg "$VENV/bin/python" -m pcr.plot "$out"
}

run_tests() {
  local failed=()
  trap print_timings EXIT  # also when a phase fails (set -e)
  phase setup
  install_system_packages
  setup_venv
  phase format
  check_format || failed+=("clang-format")
  phase build/
  build_main --pytest-installed
  phase "pip install ./python"
  install_python_package
  phase "ctest build/"
  log "ctest in build/"
  ctest --test-dir build --output-on-failure -j "$JOBS" --timeout 900 || failed+=("ctest build/")

  # The parsers of users' files again under ASan + UBSan, with assertions on (Debug keeps
  # Eigen's bounds checks): the tests labelled inputs and the fuzz targets of pcr::io's and
  # pcr::vision's parsers (target pcr_input_checks, tests/CMakeLists.txt). The whole suite under
  # the sanitizers (every target, ctest without -L) takes over an hour on 2 cores, more than the
  # time CI gives the test command. The libraries are compiled at -O1 (src/CMakeLists.txt), the
  # tests at -O0; -g1 (line tables only: the reports' stack traces keep their file:line) compiles
  # 25-35 % faster than -g. The fuzz targets (PCR_FUZZ) link libFuzzer from libclang-rt-14-dev.
  phase build-asan/
  log "Building build-asan/ (AddressSanitizer + UndefinedBehaviorSanitizer, $CXX_COMPILER)"
  configure build-asan -DCMAKE_BUILD_TYPE=Debug \
    "-DCMAKE_CXX_FLAGS_DEBUG=-O0 -g1" -DPCR_SANITIZE=ON -DPCR_FUZZ=ON -DPCR_BUILD_BENCHMARKS=OFF \
    -DPCR_BUILD_PYTHON=OFF
  cmake --build build-asan -j "$JOBS" --target pcr_input_checks
  # Every test's output is kept (JUnit XML) and searched for reports, so one from a child process
  # whose failure a test expects (a CLI run on a bad file) is not lost.
  local junit=$ROOT/build-asan/ctest-output.xml
  local report_pattern='SUMMARY: [A-Za-z]+Sanitizer|[0-9]+: runtime error: '
  rm -f "$junit"
  phase "ctest build-asan/"
  log "ctest in build-asan/"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    ctest --test-dir build-asan -L inputs --output-on-failure -j "$JOBS" --timeout 900 \
    --output-junit "$junit" --test-output-size-passed 1048576 --test-output-size-failed 1048576 ||
    failed+=("ctest build-asan/")
  if grep -E -q "$report_pattern" "$junit"; then
    grep -E -B2 -A12 "$report_pattern" "$junit" >&2
    failed+=("sanitizer reports in $junit")
  fi

  trap - EXIT
  print_timings
  if ((${#failed[@]})); then
    die "FAILED: ${failed[*]}"
  fi
  log "All tests passed"
}

run_quick() {
  install_system_packages
  setup_venv
  build_main
  log "ctest in build/ (labels unit, cli, python; not slow)"
  ctest --test-dir build --output-on-failure -j "$JOBS" --timeout 900 -L 'unit|cli|python' -LE slow
}

case ${1:-} in
  demo) shift; run_demo "$@" ;;
  test) run_tests ;;
  setup) install_system_packages; setup_venv ;;
  build) install_system_packages; setup_venv; build_main ;;
  quick) run_quick ;;
  *)
    echo "usage: bash scripts/run.sh {demo|test|setup|build|quick} [main job arguments]" >&2
    exit 2
    ;;
esac
