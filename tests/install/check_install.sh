#!/usr/bin/env bash
# The installed package as a user meets it (ctest Install.ConsumerBuildsAndRuns):
#   1. `cmake --install` of this build into a fresh prefix;
#   2. a consumer project configured with find_package(Cuberille), built and run;
#   3. the same program built with pkg-config's flags alone, and run;
#   4. the Python package imported from <prefix>/lib/python3/dist-packages, rendering;
#   5. the installed tool rendering to a PNG.
# Usage: check_install.sh BUILD_DIR WORK_DIR PYTHON
set -euo pipefail
build="$1" work="$2" python="$3"
here="$(cd "$(dirname "$0")" && pwd)"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null

cmake -S "$here/consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/thumbnail"

export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# shellcheck disable=SC2046  # pkg-config's flags are words
c++ -O1 "$here/consumer/thumbnail.cpp" -o "$work/thumbnail-pkg-config" $(pkg-config --cflags --libs cuberille) -Wl,-rpath,"$prefix/lib"
"$work/thumbnail-pkg-config"

PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c '
import cuberille
image = cuberille.render("demo", 64, 36, msaa=4)
assert image.shape == (36, 64, 4) and image.dtype.name == "uint8", image.shape
print("python: cuberille.render gave", image.shape, "from", cuberille.__file__)'

"$prefix/bin/cuberille" render demo --width 64 --height 36 --out "$work/demo.png" --quiet
test -s "$work/demo.png"
echo "installed tool wrote $work/demo.png"
