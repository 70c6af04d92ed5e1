#!/usr/bin/env bash
# Builds HILBERT's C++ port (yramic/Advanced_Numerical_Methods, BEM/CppHilbert) and our
# timing driver OUTSIDE the project tree.  Nothing of theirs is copied into this repo.
#   REPO=/path/to/Advanced_Numerical_Methods (a clone, or a bare git dir)   [required]
#   BUILD=/tmp/peers/build                                                  [default]
# Needs g++ and Eigen 3 (Debian: apt-get install libeigen3-dev).
set -euo pipefail
: "${REPO:?set REPO to a clone (or git dir) of yramic/Advanced_Numerical_Methods}"
BUILD=${BUILD:-/tmp/peers/build}
HERE=$(cd "$(dirname "$0")" && pwd)
EIGEN=${EIGEN:-/usr/include/eigen3}
[ -d "$EIGEN/Eigen" ] || { echo "Eigen not found in $EIGEN (apt-get install libeigen3-dev)"; exit 1; }
mkdir -p "$BUILD/src"
if [ -d "$REPO/BEM/CppHilbert" ]; then
  cp -r "$REPO/BEM/CppHilbert/Library/source/." "$BUILD/src/"
else   # bare git directory
  git --git-dir="$REPO" archive HEAD BEM/CppHilbert/Library/source | tar -x -C "$BUILD"
  cp -r "$BUILD/BEM/CppHilbert/Library/source/." "$BUILD/src/"
fi
cd "$BUILD"
FLAGS="-O3 -march=native -DNDEBUG -I$EIGEN -Isrc"
objs=()
for f in src/*.cpp; do o=$(basename "${f%.cpp}").o; g++ $FLAGS -c "$f" -o "$o"; objs+=("$o"); done
gcc -O3 -march=native -DNDEBUG -Isrc -c src/gaussQuadrature.c -o gaussQuadrature.o
g++ $FLAGS "$HERE/hilbert_driver.cpp" "${objs[@]}" gaussQuadrature.o -o hilbert_driver
echo "built $BUILD/hilbert_driver"
