#!/usr/bin/env bash
# Set up the development environment of gait_planner in a virtual environment (default .venv/).
#
#   tools/setup.sh [VENV_DIR]
#
# 1. checks the machine: python3 with its venv module and headers, cmake, make, C and C++ compilers;
# 2. creates VENV_DIR with `python3 -m venv` if it is missing;
# 3. pip-installs requirements.txt (pinned ROS 2 wheels from PyPI, numerics, tests);
# 4. points the ROS message wheels' exported CMake files at this interpreter's include dir and
#    numpy's include dir (the wheels name their builder's /opt/python/cp311-cp311/... paths);
# 5. installs gait_planner itself editable (pip install -e . --no-deps);
# 6. compiles walker3d's default problem and plans it (what `make run` needs; the other
#    scenes, ground forms, gaits and anchors are `make prepare`), in the background while
# 7. configures, builds and installs msg_defs/ (gait_planner_msgs) into the venv prefix, and
#    tools/tf2_msgs (tf2_msgs/TFMessage) when no tf2_msgs is installed (no PyPI wheel);
#    then it waits for step 6.
#
# Steps 3, 5, 6 and 7 are skipped when the stamp files under VENV_DIR/.gait_planner_setup/ show that
# their inputs have not changed, so a second run changes nothing and takes a few seconds.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
self="$repo/tools/$(basename "${BASH_SOURCE[0]}")"
cd "$repo"
venv="${1:-.venv}"
case "$venv" in /*) ;; *) venv="$repo/$venv" ;; esac
stamps="$venv/.gait_planner_setup"
build_dir="$stamps/build/msg_defs"
python_bin="${PYTHON:-python3}"

say() { printf 'setup: %s\n' "$*"; }
# pip with a find-links/extra-index entry that does not exist warns once per package: hide that.
pip_install() {
  "$py" -m pip install --quiet --disable-pip-version-check "$@" \
    2> >(grep -v "is ignored: it is neither a file nor a directory" >&2)
}
die() { printf 'setup: %s\n' "$*" >&2; exit 1; }

# --- 1. the machine --------------------------------------------------------------------------
command -v "$python_bin" >/dev/null 2>&1 \
  || die "python3 is missing; install it with: apt-get install python3 python3-venv python3-dev"
if [[ ! -x "$venv/bin/python" ]]; then
  "$python_bin" -c 'import sys; assert sys.version_info[:2] == (3, 11)' 2>/dev/null \
    || die "$python_bin is not Python 3.11, which the ROS 2 wheels need; run again with PYTHON=python3.11 (apt-get install python3.11-venv python3.11-dev)"
  "$python_bin" -c 'import venv, ensurepip' >/dev/null 2>&1 \
    || die "the python3 venv module is missing; install it with: apt-get install python3-venv"
fi
command -v cmake >/dev/null 2>&1 || die "cmake is missing; install it with: apt-get install cmake"
command -v make >/dev/null 2>&1 || die "make is missing; install it with: apt-get install make"
command -v "${CC:-cc}" >/dev/null 2>&1 \
  || die "no C compiler (${CC:-cc}) found; install one with: apt-get install build-essential"
command -v "${CXX:-c++}" >/dev/null 2>&1 \
  || die "no C++ compiler (${CXX:-c++}) found; install one with: apt-get install build-essential"

# --- 2. the virtual environment --------------------------------------------------------------
if [[ ! -x "$venv/bin/python" ]]; then
  say "creating $venv"
  "$python_bin" -m venv "$venv"
fi
py="$venv/bin/python"
"$py" -c 'import sys; assert sys.version_info[:2] == (3, 11)' 2>/dev/null \
  || die "$venv uses $("$py" -c 'import sys; print(sys.version.split()[0])'), but the ROS 2 wheels need Python 3.11; remove $venv and run again with PYTHON=python3.11"
mkdir -p "$stamps"

# Stamp helpers: a stamp holds the hash of a step's inputs; the step runs when it differs.
hash_of() { cat "$@" | sha256sum | cut -d' ' -f1; }
is_current() { [[ -f "$stamps/$1" && "$(cat "$stamps/$1")" == "$2" ]]; }
mark() { printf '%s\n' "$2" >"$stamps/$1"; }

# --- 3. pinned requirements ------------------------------------------------------------------
req_hash="$(hash_of requirements.txt)"
if ! is_current requirements "$req_hash"; then
  say "installing requirements.txt into $venv (about a minute on a fresh venv)"
  pip_install -r requirements.txt
  mark requirements "$req_hash"
  rm -f "$stamps/msg_defs"  # new wheels: rebuild the interface package against them
fi

# --- 4. CMake paths of the message wheels ----------------------------------------------------
# Idempotent: once rewritten, the builder's paths no longer occur (a re-installed wheel brings
# them back, and is rewritten again here).
wheel_python=/opt/python/cp311-cp311
mapfile -t stale < <(grep -rlF --include='*.cmake' "$wheel_python" "$venv/share" 2>/dev/null || true)
if ((${#stale[@]})); then
  py_include="$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
  np_include="$("$py" -c 'import numpy; print(numpy.get_include())')"
  [[ -f "$py_include/Python.h" ]] \
    || die "the Python headers ($py_include/Python.h) are missing; install them with: apt-get install python3-dev"
  say "pointing ${#stale[@]} CMake files of the message wheels at $py_include and $np_include"
  sed -i -e "s|$wheel_python/lib/python3.11/site-packages/numpy/_core/include|$np_include|g" \
         -e "s|$wheel_python/include/python3.11|$py_include|g" "${stale[@]}"
fi

# --- 5. gait_planner, editable ---------------------------------------------------------------
pkg_hash="$( { printf '%s\n' "$venv"; cat setup.py setup.cfg package.xml; } | sha256sum | cut -d' ' -f1)"
if ! is_current gait_planner "$pkg_hash" || [[ ! -x "$venv/bin/gait-planner" ]]; then
  say "installing gait_planner editable into $venv"
  # PEP 660 editable install (pip puts the console script into $venv/bin); an older pip would
  # otherwise run `setup.py develop`, which follows setup.cfg's ROS script_dir.
  pep517=()
  [[ "$("$py" -m pip install --help 2>/dev/null)" == *--use-pep517* ]] && pep517=(--use-pep517)
  # (PYTHONWARNINGS: setuptools' note on flat layouts is information, not a problem.)
  PYTHONWARNINGS=ignore pip_install --no-deps --no-build-isolation "${pep517[@]}" -e .
  mark gait_planner "$pkg_hash"
fi

# --- 6. what the first plan needs: walker3d's default problem, compiled, and its plan --------
# The planner compiles each scene's per-node derivative elements to C the first time they
# are needed and caches them by source hash. Set-up compiles only what `make run` plans:
# walker3d's default problem (47 libraries; 92 s with its plan on the 2-core VM, 2026-12-07)
# and plans its default request into the warm-start store (gait_planner/ocp/warm_starts.py).
# It needs no ROS message, so it runs in the background while step 7 builds the messages
# (their generators and CMake leave a core idle much of the time), and set-up waits for it
# at the end. The rest (every ground form and gait of the shipped scenes, their warm-start
# anchors) is `make prepare` (`make test` runs it first) or the node's background
# preparation. A failure only costs speed later.
prep_hash="$( { printf '%s\n' "$venv" "${GAIT_PLANNER_CACHE:-$HOME/.cache/gait_planner}";
  cat gait_planner/model/*.py gait_planner/dynamics/*.py gait_planner/ocp/*.py \
      gait_planner/cli/prepare.py config/scenes/walker3d.yaml; } | sha256sum | cut -d' ' -f1)"
prep_pid=""
prep_log="$stamps/prepare-default.log"
if ! is_current prepare-default "$prep_hash"; then
  say "compiling walker3d's default problem and planning it, beside the next steps (about 1.5 minutes the first time on 2 cores; cached; log $prep_log)"
  "$venv/bin/gait-planner" prepare --default-only walker3d >"$prep_log" 2>&1 &
  prep_pid=$!
  trap 'kill "$prep_pid" 2>/dev/null || true' EXIT  # a failing step 7 does not leave it running
fi

# --- 7. the interface package msg_defs/ (gait_planner_msgs) ----------------------------------
mapfile -t msg_sources < <(find msg_defs -type f ! -name '*~' | LC_ALL=C sort)
msg_hash="$( { printf '%s\n' "$req_hash" "$venv" "${msg_sources[@]}"; cat "${msg_sources[@]}" "$self"; } \
  | sha256sum | cut -d' ' -f1)"
if ! is_current msg_defs "$msg_hash" || [[ ! -f "$venv/share/gait_planner_msgs/package.xml" ]]; then
  say "building msg_defs/ (gait_planner_msgs) into $venv"
  old_manifest="$stamps/msg_defs-installed.txt"  # what the previous build installed
  if [[ -f "$build_dir/install_manifest.txt" ]]; then
    cp "$build_dir/install_manifest.txt" "$old_manifest"
  fi
  rm -rf "$build_dir"
  export AMENT_PREFIX_PATH="$venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
  export CMAKE_PREFIX_PATH="$venv${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
  export PATH="$venv/bin:$PATH"
  log="$stamps/msg_defs-build.log"
  if ! {
    cmake -S msg_defs -B "$build_dir" \
      -DCMAKE_PREFIX_PATH="$venv" \
      -DCMAKE_INSTALL_PREFIX="$venv" \
      -DPython3_EXECUTABLE="$py" \
      -DBUILD_TESTING=OFF &&
    cmake --build "$build_dir" --parallel "$(nproc 2>/dev/null || echo 2)" &&
    cmake --install "$build_dir"
  } >"$log" 2>&1; then
    tail -n 40 "$log" >&2
    die "building msg_defs/ failed; the full log is $log"
  fi
  # Remove what the previous build installed and this one did not (renamed or deleted
  # interfaces), after installing, so the package never disappears for a running user.
  if [[ -f "$old_manifest" ]]; then
    comm -23 <(LC_ALL=C sort "$old_manifest") <(LC_ALL=C sort "$build_dir/install_manifest.txt") \
      | xargs -r -d '\n' rm -f
    rm -f "$old_manifest"
  fi
  "$py" -c 'from gait_planner_msgs.srv import PlanGait; from gait_planner_msgs.action import PlanGait as PlanGaitAction; from gait_planner_msgs.msg import ContactForces, MultibodyState' \
    || die "gait_planner_msgs was built but does not import; see $log"
  mark msg_defs "$msg_hash"
fi

# --- 7b. tf2_msgs/TFMessage, where no tf2_msgs is installed ----------------------------------
# PyPI has no tf2_msgs wheel; the node subscribes to /tf (PlanGait's start "robot") and its
# tests publish it, so tools/tf2_msgs (TFMessage alone, ROS 2's definition) is built into
# the venv when `import tf2_msgs` fails. A full ROS 2 install has the real package.
if ! "$py" -c 'import tf2_msgs.msg' >/dev/null 2>&1; then
  say "building tools/tf2_msgs (tf2_msgs/TFMessage, no wheel on PyPI) into $venv"
  tf_build="$stamps/build/tf2_msgs"
  tf_log="$stamps/tf2_msgs-build.log"
  rm -rf "$tf_build"
  if ! (
    export AMENT_PREFIX_PATH="$venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
    export PATH="$venv/bin:$PATH"
    cmake -S tools/tf2_msgs -B "$tf_build" -DCMAKE_PREFIX_PATH="$venv" \
      -DCMAKE_INSTALL_PREFIX="$venv" -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF &&
    cmake --build "$tf_build" --parallel "$(nproc 2>/dev/null || echo 2)" &&
    cmake --install "$tf_build"
  ) >"$tf_log" 2>&1 || ! "$py" -c 'from tf2_msgs.msg import TFMessage' >/dev/null 2>&1; then
    tail -n 40 "$tf_log" >&2
    die "building tools/tf2_msgs failed; the full log is $tf_log"
  fi
fi

# --- 6, continued: wait for walker3d's default problem ----------------------------------------
if [[ -n "$prep_pid" ]]; then
  if wait "$prep_pid"; then
    mark prepare-default "$prep_hash"
    say "$(tail -n 1 "$prep_log")"
    say "the other ground forms, gaits and scenes: \`make prepare\` (minutes; the node does it in the background)"
  else
    tail -n 20 "$prep_log" >&2
    say "warning: compiling failed (log $prep_log); the plan will compile (or fall back to CasADi) when asked"
  fi
fi

say "ready: $venv (${SECONDS} s)"
