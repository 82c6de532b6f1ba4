#!/bin/sh
# Makes the relocatable bundle of a built tree (README, "Installing on a GPU server"):
# BUILD/vkray-VERSION-linux-ARCH.tar.gz holding
#   bin/vkray          a launcher: the machine's Vulkan loader where it has one, lib/vulkan/'s otherwise
#   libexec/vkray      the executable, RUNPATH $ORIGIN/../lib
#   python/vkray.*.so  the Python module (for the CPython it was built for), RUNPATH $ORIGIN/../lib
#   lib/               the shared libraries both need (Embree, OpenEXR, GLFW, ...), RUNPATH $ORIGIN
#   lib/vulkan/        a Vulkan loader for machines without one (found by bin/vkray and the module)
#   share/doc/vkray/   README.md, LICENSE, and the copyright file of every library carried
# Left out: glibc and its parts, the C++ runtime (libstdc++ and libgcc_s of GCC 12 or newer) and
# zlib, which every Linux with glibc 2.36 or newer has, and the GPU driver, which must be the
# machine's. Usage, from the repository root after building: sh cmake/make-bundle.sh [BUILD_DIR]
set -eu
cd "$(dirname "$0")/.."
build="${1:-build}"
version=$(sed -n 's/^project(vkray VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
name="vkray-$version-linux-$(uname -m)"
stage="$build/bundle/$name"
for built in "$build/vkray" "$build"/python/vkray.*.so; do
  [ -f "$built" ] || { echo "vkray: $built is missing: build first (README, 'Two commands')" >&2; exit 2; }
done
command -v patchelf >/dev/null || { echo "vkray: patchelf is missing: sh cmake/install-deps.sh installs it" >&2; exit 2; }

rm -rf "$build/bundle"
mkdir -p "$stage/bin" "$stage/libexec" "$stage/lib/vulkan" "$stage/python" "$stage/share/doc/vkray/third-party"
cp "$build/vkray" "$stage/libexec/vkray"
cp "$build"/python/vkray.*.so "$stage/python/"

# Every library the executable and the module load, but what the machine must have.
carried() {
  case "$(basename "$1")" in
    ld-linux*|libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|libresolv.so*|libutil.so*) return 1 ;;
    libstdc++.so*|libgcc_s.so*|libz.so*|libvulkan.so*) return 1 ;;
  esac
}
loader=""
for object in "$stage/libexec/vkray" "$stage"/python/vkray.*.so; do
  if ldd "$object" | grep -q 'not found'; then
    echo "vkray: $object needs a library this machine lacks:" >&2
    ldd "$object" | grep 'not found' >&2
    exit 1
  fi
  for library in $(ldd "$object" | awk '/=> \// {print $3}'); do
    case "$(basename "$library")" in libvulkan.so.1) loader="$library" ;; esac
    carried "$library" && cp -L "$library" "$stage/lib/"
  done
done
[ -n "$loader" ] || loader=$(/sbin/ldconfig -p | awk '/libvulkan\.so\.1 .*x86-64/ {print $NF; exit}')
cp -L "$loader" "$stage/lib/vulkan/libvulkan.so.1"

patchelf --set-rpath '$ORIGIN/../lib' "$stage/libexec/vkray" "$stage"/python/vkray.*.so
for library in "$stage"/lib/*.so* "$stage/lib/vulkan/libvulkan.so.1"; do patchelf --set-rpath '$ORIGIN' "$library"; done
strip --strip-unneeded "$stage/libexec/vkray" "$stage"/python/vkray.*.so

# The copyright file of each library's Debian package: their licences travel with them.
for library in "$stage"/lib/*.so* "$stage/lib/vulkan/libvulkan.so.1"; do
  file=$(basename "$library")
  package=$(dpkg -S "*/$file" 2>/dev/null | head -n 1 | cut -d: -f1)
  [ -n "$package" ] && cp "/usr/share/doc/$package/copyright" "$stage/share/doc/vkray/third-party/$package.copyright"
done
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
