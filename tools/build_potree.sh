#!/usr/bin/env bash
# Builds PotreeConverter 2 from its public source, for the conversion comparison of
# tools/bench_convert_scale.sh. Its code stays out of this repository: it is
# cloned (or taken from POTREE_SRC, a checkout) into target/potree and built there.
#
#   tools/build_potree.sh            # prints the path of the PotreeConverter binary
#
# Needs cmake, a C++20 compiler and libtbb (apt-get install -y cmake g++ libtbb-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
root=target/potree
mkdir -p "$root"
if [ -n "${POTREE_SRC:-}" ]; then
  rm -rf "$root/src" && mkdir -p "$root/src"
  if [ -d "$POTREE_SRC/.git" ] || git -C "$POTREE_SRC" rev-parse --git-dir > /dev/null 2>&1; then
    # What the build reads, and no more: a snapshot may lack the web viewer's large
    # files, and `git archive HEAD <paths>` fails on them even when they are not asked
    # for, so the one folder is archived from its own tree and the files shown.
    git -C "$POTREE_SRC" archive --prefix=Converter/ HEAD:Converter | tar -x -C "$root/src"
    for f in CMakeLists.txt LICENSE README.md; do
      git -C "$POTREE_SRC" show "HEAD:$f" > "$root/src/$f"
    done
  else
    cp -r "$POTREE_SRC"/. "$root/src"
  fi
elif [ ! -d "$root/src" ]; then
  git clone --depth 1 https://github.com/potree/PotreeConverter "$root/src" >&2
fi
mkdir -p "$root/src/resources/page_template"
# The same instruction set as spt's own build (.cargo/config.toml): x86-64-v3 on x86-64.
flags=""
[ "$(uname -m)" = x86_64 ] && flags="-march=x86-64-v3"
cmake -S "$root/src" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="$flags" > "$root/cmake.log" 2>&1
cmake --build "$root/build" -j "${JOBS:-2}" > "$root/build.log" 2>&1 || { tail -30 "$root/build.log" >&2; exit 1; }
echo "$root/build/PotreeConverter"
