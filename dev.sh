#!/usr/bin/env bash
# One entry point for a fresh machine:  bash dev.sh render [ARGS...]  |  bash dev.sh test [PYTEST ARGS...]
# `bash dev.sh test` without arguments runs ruff, then the whole suite: tests/ in .venv (numpy 2),
# then tests/blender in
# .venv-blender (bpy 5.0 needs numpy < 2: constraints-blender.txt). With arguments it runs pytest in .venv only;
# `bash dev.sh test-blender [PYTEST ARGS...]` runs the Blender tests alone.
# The first run installs what is missing: python3 + venv (apt), libLLVM >= 16 (apt: libllvm19, because
# Dr.Jit 1.5 aborts on Debian's default LLVM 15), a virtual environment in .venv, and styletrace with
# versions pinned by constraints.txt (mitsuba 3.9.1, drjit 1.5.0, numpy, ray, ...); for `test` also Chromium (apt),
# which the preview's browser test drives through Playwright, and Blender + Xvfb (apt, about 195 MB), which
# tests/blender/test_viewport_draw.py runs to read what the 3D viewport draws.
set -euo pipefail
cd "$(dirname "$0")"
VENV=${STYLETRACE_VENV:-.venv}
BLENDER_VENV=${STYLETRACE_BLENDER_VENV:-.venv-blender}

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    echo "dev.sh: need root to run: $*" >&2; exit 1; fi
}

apt_install() {
  command -v apt-get >/dev/null || { echo "dev.sh: no apt-get here; install $* by hand" >&2; exit 1; }
  if [ -z "${APT_UPDATED:-}" ]; then as_root apt-get update -qq; APT_UPDATED=1; fi
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
}

have_llvm() {  # a libLLVM of major version >= 16 anywhere the package looks
  local f
  for f in /usr/lib/*-linux-gnu/libLLVM*.so* /usr/lib64/libLLVM*.so* /usr/lib/libLLVM*.so* /usr/lib/llvm-*/lib/libLLVM*.so*; do
    [ -e "$f" ] || continue
    local major
    major=$(basename "$f" | sed -nE 's/^libLLVM-([0-9]+).*/\1/p; s/^libLLVM\.so\.([0-9]+).*/\1/p')
    [ -n "$major" ] && [ "$major" -ge 16 ] && return 0
  done
  return 1
}

setup() {
  command -v python3 >/dev/null || apt_install python3 python3-venv
  python3 -c 'import ensurepip, venv' 2>/dev/null || apt_install python3-venv
  have_llvm || apt_install libllvm19
  # the preview's browser test drives Debian's Chromium with Playwright (Playwright's own download cannot work here)
  if [ "${1:-}" = test ] && ! command -v chromium >/dev/null; then apt_install chromium; fi
  # the viewport's drawing test runs Debian's Blender (a GUI) under Xvfb (tests/blender/test_viewport_draw.py)
  if [ "${1:-}" = test ] && ! { command -v blender && command -v xvfb-run && command -v xauth; } >/dev/null; then
    apt_install --no-install-recommends blender xvfb xauth libgl1-mesa-dri
  fi
  if [ ! -x "$VENV/bin/python" ]; then python3 -m venv "$VENV"; fi
  local stamp="$VENV/.styletrace-installed"
  if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || [ constraints.txt -nt "$stamp" ]; then
    "$VENV/bin/python" -m pip install -q --upgrade pip
    "$VENV/bin/python" -m pip install -q -c constraints.txt -e ".[test,plots,preview,ray,denoise]"
    touch "$stamp"
  fi
}

setup_blender() {  # Blender as a Python module with numpy 1.26, beside the main venv (docs/blender.md)
  setup test
  if [ ! -x "$BLENDER_VENV/bin/python" ]; then python3 -m venv "$BLENDER_VENV"; fi
  local stamp="$BLENDER_VENV/.styletrace-installed"
  if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || [ constraints-blender.txt -nt "$stamp" ]; then
    "$BLENDER_VENV/bin/python" -m pip install -q --upgrade pip
    "$BLENDER_VENV/bin/python" -m pip install -q -c constraints-blender.txt -e ".[test,blender,denoise,plots]"
    touch "$stamp"
  fi
}

cmd=${1:-}
[ $# -gt 0 ] && shift
case "$cmd" in
  render) setup
          if [ $# -eq 0 ]; then  # the demo: GI cel shading at every default, seen in a mirror and through glass
            set -- lines --style cel --width 512 --height 512 -o render.png
          fi
          exec "$VENV/bin/styletrace" render "$@" ;;
  test)   if [ $# -gt 0 ]; then setup test; exec "$VENV/bin/python" -m pytest -q "$@"; fi
          setup_blender
          "$VENV/bin/ruff" check .  # the house rules: imports, line length 100 (pyproject.toml)
          # two processes (pytest-xdist, a file per process at a time): on a fresh machine each
          # compiles its tests' kernels while the other renders (docs/install.md, "How long")
          "$VENV/bin/python" -m pytest -q -n "${STYLETRACE_TEST_WORKERS:-2}" --dist loadfile \
            --ignore=tests/blender
          exec "$BLENDER_VENV/bin/python" -m pytest -q tests/blender ;;
  test-blender) setup_blender; exec "$BLENDER_VENV/bin/python" -m pytest -q tests/blender "$@" ;;
  setup)  setup ;;
  *) echo "usage: bash dev.sh render [styletrace render args] | bash dev.sh test [pytest args] | bash dev.sh test-blender [pytest args] | bash dev.sh setup" >&2; exit 2 ;;
esac
