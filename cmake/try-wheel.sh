#!/bin/sh
# The wheel where a user meets it (docs/python.md): in the fresh Debian root ROOT (debootstrap
# minbase, /proc mounted, made by the caller), with only the distribution's python3-venv,
# python3-numpy, libvulkan1 and mesa-vulkan-drivers, a user who is not root makes a venv with
# --system-site-packages (numpy from the distribution), installs the wheel with pip install
# --no-index, and runs the README's Python quick start and cast_rays and occluded against a
# sphere's closed form. CI runs it in a fresh Debian 12 (cmake/check-bundle.sh) and a fresh Debian
# 13 (cmake/check-debian13.sh) with the same wheel file. Usage: sh cmake/try-wheel.sh ROOT WHEEL
set -eu
cd "$(dirname "$0")/.."
root=$1
wheel=$2
chroot "$root" sh -c 'DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends python3-venv python3-numpy libvulkan1 mesa-vulkan-drivers' \
  >"$root/tmp/apt-wheel.log" 2>&1 || { tail -n 20 "$root/tmp/apt-wheel.log"; exit 1; }
chroot "$root" id pythonuser >/dev/null 2>&1 || chroot "$root" useradd --create-home pythonuser
cp "$wheel" "$root/tmp/"
# The README's quick start: the ```python block under "## Quick start".
awk '/^## Quick start/ {section = 1} section && /^```python/ {code = 1; next} code && /^```/ {exit} code' README.md >"$root/tmp/quick_start.py"
[ -s "$root/tmp/quick_start.py" ] || { echo "vkray: no Python quick start in the README" >&2; exit 1; }
cat >"$root/tmp/rays.py" <<'RAYS'
import numpy as np
import vkray
# A unit sphere at the origin: each ray's nearest hit by the closed form.
renderer = vkray.Renderer(vkray.Scene(spheres=np.array([[0.0, 0.0, 0.0, 1.0]])))
rays = np.array([[0, 0, 5, 0, 0, -1], [0, 0, 5, 0, 0, 1], [3, 0, 0, -2, 0, 0]], dtype=float)
t = renderer.cast_rays(rays)["t"]
assert abs(t[0] - 4) < 1e-5 and np.isinf(t[1]) and abs(t[2] - 2) < 1e-5, t
assert renderer.occluded(rays).tolist() == [True, False, True]
assert renderer.occluded(rays, t_max=1.01, t_along="direction").tolist() == [False, False, True]
print("cast_rays and occluded agree with the closed form on", renderer.device_name)
RAYS
chroot --userspec=pythonuser:pythonuser "$root" /usr/bin/env -i HOME=/home/pythonuser PATH=/usr/bin:/bin LANG=C.UTF-8 sh -c '
  set -e
  cd /home/pythonuser
  python3 -m venv --system-site-packages venv
  venv/bin/pip install -q --no-index /tmp/vkray-*.whl
  venv/bin/python -c "import sys, numpy, vkray; print(\"vkray\", vkray.__version__, \"from\", vkray.__file__, \"in Python\", sys.version.split()[0], \"with numpy\", numpy.__version__)"
  venv/bin/python /tmp/quick_start.py
  venv/bin/python /tmp/rays.py'
echo "vkray: the wheel works in $(cat "$root/etc/debian_version")'s Python, installed by a user into a venv"
