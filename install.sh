#!/usr/bin/env bash
# Installs splineviz into ./.venv on Debian/Ubuntu with Python >= 3.11.
#   ./install.sh          the application
#   ./install.sh --dev    the application, its tests and the first-party plugins
# System packages (headless OpenGL, Xvfb for Qt windows, binutils for the PoCL OpenCL
# compiler, Debian's PoCL for processors newer than the LLVM of the pip wheel's PoCL,
# python3-venv) are installed with apt when missing and we are root or have sudo.
set -euo pipefail
cd "$(dirname "$0")"

APT_PACKAGES=(python3-venv binutils xvfb xauth libgl1 libegl1 libegl-mesa0 libgl1-mesa-dri
              libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0
              libxcb-render-util0 libxcb-shape0 libxcb-xinerama0 libxcb-randr0 libdbus-1-3
              libfontconfig1 libusb-1.0-0 libgomp1 pocl-opencl-icd)
# --dev: the web view's browser test drives Debian's headless Chromium through selenium
[ "${1:-}" = "--dev" ] && APT_PACKAGES+=(chromium chromium-driver)

missing=()
if command -v dpkg-query >/dev/null 2>&1; then
  for p in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
fi
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  if [ -z "$SUDO" ] || command -v sudo >/dev/null 2>&1; then
    echo "install.sh: apt-get install ${missing[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "install.sh: please install these system packages: ${missing[*]}" >&2
  fi
fi

PY=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$PY" -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
target="."
[ "${1:-}" = "--dev" ] && target=".[dev]"
.venv/bin/python -m pip install -q -e "$target"
for plugin in plugins/*/; do
  if [ -f "$plugin/pyproject.toml" ]; then .venv/bin/python -m pip install -q -e "$plugin"; fi
done
# the truncated-octahedral ray caster's tables (a second of Python) into the user cache now,
# not the first time the model is chosen in the app
.venv/bin/python -c "from splineviz.compute.to_tables import cell_classes, class_points, stencils, subcell_masks; stencils(2); cell_classes(); class_points(2); subcell_masks()" \
  || echo "install.sh: could not prepare the ray-casting tables (they are made on first use)" >&2
# the point projection's numba kernels (the fits and the connectivity's normals) into numba's
# cache (10-20 s once, not at first use)
.venv/bin/python -c "from splineviz.pointcloud import cocone, local_fits; local_fits.compile_kernels(); cocone.compile_kernels()" \
  || echo "install.sh: could not compile the projection kernels (they compile on first use)" >&2
# ... and the mesher's (the advancing front's geometry tests, the valence flips, the spline
# front's evaluation of type-6 splines)
.venv/bin/python -c "from splineviz.pointcloud import front_kernels, relaxation, spline_kernels; front_kernels.compile_kernels(); relaxation.compile_kernels(); spline_kernels.compile_kernels()" \
  || echo "install.sh: could not compile the mesher kernels (they compile on first use)" >&2
echo "install.sh: splineviz installed in .venv"
