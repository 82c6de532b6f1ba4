#!/bin/sh
# Makes the relocatable bundle of a built tree (docs/install.md, "Installing on a GPU server"):
# BUILD/vkray-VERSION-linux-ARCH.tar.gz holding
#   bin/vkray          a launcher: the machine's Vulkan loader where it has one, lib/vulkan/'s otherwise
#   libexec/vkray      the executable, RUNPATH $ORIGIN/../lib
#   python/vkray/      the Python package (any CPython 3.9 or later), as the wheel holds it
#   lib/libvkray.so    the C API, which the package loads, RUNPATH $ORIGIN
#   lib/               the shared libraries both need (Embree, OpenEXR, GLFW, ...), RUNPATH $ORIGIN
#   lib/vulkan/        a Vulkan loader for machines without one (found by bin/vkray and libvkray.so)
#   share/doc/vkray/   README.md, LICENSE, and the copyright file of every library carried
# What is left out for the machine to have: cmake/carry-libraries.sh. Usage, from the repository root
# after building: sh cmake/make-bundle.sh [BUILD_DIR]
set -eu
cd "$(dirname "$0")/.."
build="${1:-build}"
version=$(sed -n 's/^project(vkray VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
name="vkray-$version-linux-$(uname -m)"
stage="$build/bundle/$name"
for built in "$build/vkray" "$build/python/vkray/lib/libvkray.so" "$build/python/vkray/__init__.py"; do
  [ -f "$built" ] || { echo "vkray: $built is missing: build first (README, 'Two commands')" >&2; exit 2; }
done
command -v patchelf >/dev/null || { echo "vkray: patchelf is missing: sh cmake/install-deps.sh installs it" >&2; exit 2; }

rm -rf "$build/bundle"
mkdir -p "$stage/bin" "$stage/libexec" "$stage/lib" "$stage/python/vkray" "$stage/share/doc/vkray/third-party"
cp "$build/vkray" "$stage/libexec/vkray"
cp "$build/python/vkray/lib/libvkray.so" "$stage/lib/"
# The Python package, the wheel's own files: it finds libvkray.so in ../../lib.
cp "$build"/python/vkray/*.py "$build/python/vkray/py.typed" "$stage/python/vkray/"

# Every library the executable and libvkray.so load (cmake/carry-libraries.sh), with their licences.
sh cmake/carry-libraries.sh "$stage/lib" "$stage/share/doc/vkray/third-party" "$stage/libexec/vkray" "$stage/lib/libvkray.so"
patchelf --set-rpath '$ORIGIN/../lib' "$stage/libexec/vkray"
patchelf --set-rpath '$ORIGIN' "$stage/lib/libvkray.so"
strip --strip-unneeded "$stage/libexec/vkray" "$stage/lib/libvkray.so"
cp README.md LICENSE "$stage/share/doc/vkray/"

cat >"$stage/bin/vkray" <<'LAUNCHER'
#!/bin/sh
# vkray from its relocatable bundle: the executable in ../libexec with its libraries in ../lib. The
# Vulkan loader is the machine's where the dynamic linker finds one (it knows the machine's drivers
# and layers); where it finds none, the bundle's copy in ../lib/vulkan. The GPU driver is always the
# machine's: with none, vkray says which to install.
top=$(CDPATH='' cd -- "$(dirname -- "$(readlink -f -- "$0")")/.." && pwd)
# Only an x86-64 loader can be the machine's: a multiarch machine lists its i386 one too.
is_x86_64_elf() {
  # The first 20 bytes: ELF's magic, class 2 (64-bit) and data 1 (little-endian), then at byte 18
  # the machine, 0x3e (x86-64).
  case "$(od -An -tx1 -N20 "$1" 2>/dev/null | tr -d ' \n')" in
    7f454c460201*3e00) return 0 ;;
  esac
  return 1
}
machine_has_loader() {
  old_ifs=$IFS
  IFS=:
  for dir in ${LD_LIBRARY_PATH:-}; do
    [ -n "$dir" ] && is_x86_64_elf "$dir/libvulkan.so.1" && { IFS=$old_ifs; return 0; }
  done
  IFS=$old_ifs
  for ldconfig in /sbin/ldconfig /usr/sbin/ldconfig; do
    [ -x "$ldconfig" ] && { "$ldconfig" -p 2>/dev/null | grep -q 'libvulkan\.so\.1 (libc6,x86-64)'; return; }
  done
  return 1
}
if ! machine_has_loader; then
  LD_LIBRARY_PATH="$top/lib/vulkan${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export LD_LIBRARY_PATH
fi
exec "$top/libexec/vkray" "$@"
LAUNCHER
chmod 755 "$stage/bin/vkray"

tar -C "$build/bundle" -czf "$build/$name.tar.gz" "$name"
echo "$build/$name.tar.gz: $(du -k "$build/$name.tar.gz" | cut -f1) KiB"
