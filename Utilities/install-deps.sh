#!/usr/bin/env bash
# Installs, from Debian's packages, whatever the build, the tests and the main job need and this
# machine lacks. Safe to run again: installed packages are skipped.
set -euo pipefail

packages=(
  # compilers and test tools
  build-essential cmake libgtest-dev nlohmann-json3-dev
  # the house rules' check (Testing/Layers/check_house.py): functions and their extents
  universal-ctags
  # the sanitizer and fuzzing builds (Utilities/sanitize.sh, fuzz.sh): clang, its runtimes
  # (ASan, UBSan, libFuzzer) and its OpenMP
  clang libclang-rt-14-dev libomp-dev
  # ParaView 5.11 and what find_package(ParaView) needs beside paraview-dev
  # (see shared notes: paraview-dev does not pull these)
  paraview paraview-dev python3-paraview
  qtbase5-dev qttools5-dev libqt5svg5-dev libqt5x11extras5-dev libqt5opengl5-dev
  qtxmlpatterns5-dev-tools libqt5xmlpatterns5-dev libopenmpi-dev openmpi-bin python3-dev
  libhdf5-dev libhdf5-openmpi-dev libnetcdf-dev libgdal-dev libboost-dev libglew-dev libgl2ps-dev
  libtheora-dev libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libxml2-dev
  liblz4-dev liblzma-dev libjpeg-dev libpng-dev libtiff-dev libfreetype-dev libexpat1-dev
  zlib1g-dev libutfcpp-dev libdouble-conversion-dev libx11-dev libgl-dev libeigen3-dev
  libpugixml-dev libjsoncpp-dev libprotobuf-dev protobuf-compiler libcgns-dev libogg-dev
  libxt-dev libglvnd-dev libexodusii-dev libfmt-dev libsqlite3-dev libproj-dev libpq-dev
  libcli11-dev
  # rendering without a display (Debian's VTK is X only), and the plots
  xvfb xauth libgl1-mesa-dri python3-numpy python3-matplotlib
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "install-deps: installing ${#missing[@]} Debian packages: ${missing[*]}"
  sudo_cmd=()
  [[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -q
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q \
    "${missing[@]}"
else
  echo "install-deps: all ${#packages[@]} Debian packages present"
fi
