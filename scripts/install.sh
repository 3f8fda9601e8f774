#!/usr/bin/env bash
# Sets touchbench up on a fresh Debian machine with Python >= 3.11: the system libraries it
# needs (PortAudio for sound-card capture, libsndfile for audio files; WEKA and a Java
# runtime, which the tests run to check the WEKA-named classifiers; Chromium, which the
# web-page tests drive through Playwright; wrk, the HTTP load generator of perf/serve.py;
# ROS 1 (rosmaster, rospy, genpy) for `touchbench ros` and its tests, which reach these
# system packages from the venv through drivers/ros1.py only; R's limma for one test),
# a .venv/ at the repository root, and touchbench with every extra and its test tools
# installed (editable) inside it, at the versions of scripts/constraints.txt.
# Safe to run again: it only does what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

apt_install() {
  local options=() missing=()
  if [ "${1-}" = --lean ]; then options=(--no-install-recommends); shift; fi
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" \
      || missing+=("$package")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "installing Debian packages: ${missing[*]}" >&2
    as_root apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${options[@]}" "${missing[@]}" \
      >/dev/null
  fi
}

PYTHON=${PYTHON:-python3}
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
  echo "touchbench needs Python >= 3.11 as '$PYTHON' (set PYTHON=/path/to/python3.11)" >&2
  exit 2
fi

apt_install libportaudio2 libsndfile1 weka default-jre-headless chromium wrk \
  ros-core python3-rospy python3-genpy python3-rosgraph
# R's limma, the reference the race's moderated t-test is checked against (R's
# recommended packages would add compilers and manuals the check does not need)
apt_install --lean r-bioc-limma
"$PYTHON" -c 'import ensurepip, venv' 2>/dev/null || apt_install python3-venv

[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
stamp=".venv/.installed-$(cat pyproject.toml scripts/constraints.txt | sha256sum | cut -c1-16)"
if [ ! -f "$stamp" ]; then
  echo "installing touchbench with every extra and its test tools into .venv/" >&2
  .venv/bin/python -m pip install -q --upgrade pip
  # the exact versions tested on this machine (scripts/constraints.txt), every extra: first
  # the packages with numba kernels, whose kernels are then compiled into numba's cache
  # (scripts/compile_kernels.py, reading touchbench from this folder) while pip, which
  # keeps one core busy, installs the rest
  .venv/bin/python -m pip install -q -c scripts/constraints.txt aeon librosa
  PYTHONPATH="$PWD" .venv/bin/python scripts/compile_kernels.py 2>.venv/compile-kernels.log &
  kernels=$!
  trap 'kill "$kernels" 2>/dev/null || true' EXIT
  .venv/bin/python -m pip install -q -c scripts/constraints.txt -e '.[all,test]'
  if ! wait "$kernels"; then
    echo "warning: numba kernels not compiled ahead (see .venv/compile-kernels.log);" \
      "they compile on first use" >&2
  fi
  trap - EXIT
  rm -f .venv/.installed-*
  touch "$stamp"
fi

# The project's own modules compiled to bytecode, as pip compiles what it installs (an
# editable install's sources are this folder's): every touchbench process (a service, a
# job, each engine worker) then reads them rather than compiling them again, also where
# PYTHONDONTWRITEBYTECODE is set.  Only what changed since the last run is compiled.
.venv/bin/python -m compileall -q -j 0 touchbench app benchmark features drivers >/dev/null
