#!/bin/sh
# Copies into FOLDER every shared library the OBJECTs load but what the machine must have, so that
# they run where those libraries are not installed: the relocatable bundle's lib/
# (cmake/make-bundle.sh) and the wheel's vkray/lib (pyproject.toml, CMakeLists.txt). Left out: glibc
# and its parts, the C++ runtime (libstdc++ and libgcc_s of GCC 12 or newer) and zlib, which every
# Linux with glibc 2.36 or newer has, and the GPU driver, which must be the machine's. The Vulkan
# loader goes to FOLDER/vulkan, for machines without one (engine/vulkan/loader.cpp looks there). Each
# copy gets RUNPATH $ORIGIN, to find the others beside it; the copyright file of each library's
# Debian package goes to LICENSES. Usage: sh cmake/carry-libraries.sh FOLDER LICENSES OBJECT...
set -eu
folder=$1
licenses=$2
shift 2
command -v patchelf >/dev/null || { echo "vkray: patchelf is missing: sh cmake/install-deps.sh installs it" >&2; exit 2; }
mkdir -p "$folder/vulkan" "$licenses"
carried() {
  case "$(basename "$1")" in
    ld-linux*|libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|libresolv.so*|libutil.so*) return 1 ;;
    libstdc++.so*|libgcc_s.so*|libz.so*|libvulkan.so*) return 1 ;;
  esac
}
loader=""
for object in "$@"; do
  if ldd "$object" | grep -q 'not found'; then
    echo "vkray: $object needs a library this machine lacks:" >&2
    ldd "$object" | grep 'not found' >&2
    exit 1
  fi
  for library in $(ldd "$object" | awk '/=> \// {print $3}'); do
    case "$(basename "$library")" in libvulkan.so.1) loader="$library" ;; esac
    carried "$library" && cp -L "$library" "$folder/"
  done
done
[ -n "$loader" ] || loader=$(/sbin/ldconfig -p | awk '/libvulkan\.so\.1 \(libc6,x86-64\)/ {print $NF; exit}')
cp -L "$loader" "$folder/vulkan/libvulkan.so.1"
for library in "$folder"/*.so* "$folder/vulkan/libvulkan.so.1"; do
  case "$library" in */libvkray.so) continue ;; esac  # vkray's own: its caller sets its RUNPATH
  patchelf --set-rpath '$ORIGIN' "$library"
  # Their licences travel with them.
  package=$(dpkg -S "*/$(basename "$library")" 2>/dev/null | head -n 1 | cut -d: -f1)
  [ -n "$package" ] && cp "/usr/share/doc/$package/copyright" "$licenses/$package.copyright"
done
