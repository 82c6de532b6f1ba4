#!/bin/sh
# The relocatable bundle where a user meets it (docs/install.md, "Installing on a GPU server"): in a fresh
# Debian 12 (debootstrap minbase: no compiler, no -dev package, no build tree), unpacked into a
# folder of a user who is not root and run from another one:
# 1. before the machine has any Vulkan package, it starts on its own loader and says in one line
#    that no driver is there and what to install, exit 1;
# 2. with only what a user would install (libvulkan1 and mesa-vulkan-drivers for lavapipe,
#    python3-numpy for Python) it lists the device on the machine's loader, renders the bunny (the
#    built-in scene where ../shared/models is absent), passes the report's checks at reduced sizes
#    (`vkray report --reduced`: every row ran, every check passed) and renders from Python;
# 3. the wheel, installed by a user into a venv, runs the README's quick start (cmake/try-wheel.sh).
# CI runs it after the suite (.ci/run). Usage: sh cmake/check-bundle.sh [BUILD_DIR], as root, after
# sh cmake/make-bundle.sh and building the wheel (docs/python.md); it installs debootstrap
# (cmake/debian-packages-bundle.txt).
set -eu
cd "$(dirname "$0")/.."
build="${1:-build}"
bundle=$(ls "$build"/vkray-*-linux-*.tar.gz 2>/dev/null | head -n 1)
[ -n "$bundle" ] || { echo "vkray: no bundle in $build: sh cmake/make-bundle.sh $build first" >&2; exit 2; }
wheel=$(ls "$build"/dist/vkray-*.whl 2>/dev/null | head -n 1)
[ -n "$wheel" ] || { echo "vkray: no wheel in $build/dist: python3 -m build --wheel --no-isolation --outdir $build/dist first" >&2; exit 2; }
sh cmake/install-deps.sh cmake/debian-packages-bundle.txt

. cmake/fresh-root.sh
make_fresh_root bookworm
chroot "$root" useradd --create-home newcomer
cp "$bundle" "$root/tmp/vkray.tar.gz"
model=/tmp/models/stanford-bunny.obj
if [ -f ../shared/models/stanford-bunny.obj ]; then
  mkdir -p "$root/tmp/models"
  cp ../shared/models/stanford-bunny.obj ../shared/models/stanford-dragon-100k.obj "$root/tmp/models/"
else
  echo "vkray: ../shared/models is absent: the built-in scene and a generated mesh stand in for the models"
  model=""
fi
# As the user, in a folder of theirs, from another folder.
as_newcomer() {
  chroot --userspec=newcomer:newcomer "$root" /usr/bin/env -i HOME=/home/newcomer PATH=/usr/bin:/bin LANG=C.UTF-8 \
    sh -c "cd /home/newcomer/elsewhere && $1"
}
chroot --userspec=newcomer:newcomer "$root" sh -c \
  'mkdir -p /home/newcomer/tools /home/newcomer/elsewhere && tar -C /home/newcomer/tools -xzf /tmp/vkray.tar.gz'
vkray='../tools/vkray-*/bin/vkray'

echo "vkray: 1. no Vulkan package on the machine"
if as_newcomer "$vkray info" >"$root/tmp/no-loader.log" 2>&1; then
  cat "$root/tmp/no-loader.log"; echo "vkray: without a Vulkan driver, 'vkray info' succeeded" >&2; exit 1
fi
cat "$root/tmp/no-loader.log"
grep -q "no Vulkan driver found by the Vulkan loader .*(the bundle's: this machine has none)" "$root/tmp/no-loader.log" || { echo "vkray: not the one line expected" >&2; exit 1; }
# A multiarch machine lists an i386 loader beside (or without) its own: that one is not the machine's
# loader for vkray, in ldconfig's cache or on LD_LIBRARY_PATH. An i386 ELF of that name stands for it.
mkdir -p "$root/usr/lib/i386-linux-gnu"
echo /usr/lib/i386-linux-gnu >"$root/etc/ld.so.conf.d/i386-linux-gnu.conf"  # as libc6:i386 lists it
echo 'int not_a_vulkan_loader;' | gcc -m32 -shared -nostdlib -x c - -Wl,-soname,libvulkan.so.1 -o "$root/usr/lib/i386-linux-gnu/libvulkan.so.1"
chroot "$root" ldconfig
# ldconfig lists it as "(ELF)" (a real one, linked to i386's libc, as "(libc6)"): anything but x86-64.
chroot "$root" ldconfig -p | grep 'libvulkan\.so\.1 (' | grep -qv 'x86-64' || { echo "vkray: ldconfig does not list the i386 stand-in" >&2; exit 1; }
for path in "" /usr/lib/i386-linux-gnu; do
  as_newcomer "LD_LIBRARY_PATH=$path $vkray info" >"$root/tmp/i386.log" 2>&1 || true
  grep -q "(the bundle's: this machine has none)" "$root/tmp/i386.log" ||
    { cat "$root/tmp/i386.log"; echo "vkray: an i386 libvulkan.so.1 (LD_LIBRARY_PATH='$path') was taken for the machine's loader" >&2; exit 1; }
done

echo "vkray: 2. with libvulkan1, mesa-vulkan-drivers and python3-numpy"
chroot "$root" sh -c 'DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends libvulkan1 mesa-vulkan-drivers python3-numpy' \
  >"$root/tmp/apt.log" 2>&1 || { tail -n 20 "$root/tmp/apt.log"; exit 1; }
as_newcomer "$vkray info"
as_newcomer "$vkray info" | grep -q "Vulkan loader .*(the machine's)"
as_newcomer "$vkray render $model -o render.exr && ls -l render.exr render.png"
models="--models /tmp/models"
[ -n "$model" ] || models="--models /nonexistent"
# Its clock guards against a hang, not a speed: CI runs this beside the sanitizers on the same cores,
# where the default 3 minutes ran out with the last group's 6 rows not run (180 s in all).
as_newcomer "$vkray report report $models --reduced --minutes 30 && cat report/report.md | head -n 12"
as_newcomer "PYTHONPATH=\$(echo ../tools/vkray-*/python) python3 -c 'import vkray, numpy; r = vkray.Renderer(vkray.load(\"\", 64, 48)); d = r.render()[\"depth\"]; assert d.shape == (48, 64) and numpy.isfinite(d).any(); print(\"python: rendered on\", r.device_name)'"
echo "vkray: the bundle works in a fresh Debian 12"
echo "vkray: 3. the wheel, installed by a user into a venv"
sh cmake/try-wheel.sh "$root" "$wheel"
