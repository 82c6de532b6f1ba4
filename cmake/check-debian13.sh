#!/bin/sh
# The wheel in a fresh Debian 13 (Python 3.13, numpy 2), the same file CI tried in a fresh Debian 12
# (cmake/check-bundle.sh): cmake/try-wheel.sh in a fresh root (cmake/fresh-root.sh). As root, after
# building the wheel (docs/python.md). Usage: sh cmake/check-debian13.sh [WHEEL]
set -eu
cd "$(dirname "$0")/.."
wheel="${1:-$(ls build/dist/vkray-*.whl 2>/dev/null | head -n 1)}"
[ -f "$wheel" ] || { echo "vkray: no wheel in build/dist: python3 -m build --wheel --no-isolation --outdir build/dist first" >&2; exit 2; }
sh cmake/install-deps.sh cmake/debian-packages-bundle.txt
. cmake/fresh-root.sh
make_fresh_root trixie
sh cmake/try-wheel.sh "$root" "$wheel"
