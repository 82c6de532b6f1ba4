# Sourced by cmake/check-bundle.sh and cmake/check-debian13.sh: `make_fresh_root SUITE` makes a fresh
# Debian root (debootstrap minbase of bookworm or trixie, from the machine's Debian archive:
# cmake/debian-archive.sh) in a temporary folder, $root, with the machine's resolv.conf and /proc
# mounted, unmounted and removed when the calling script exits. As root, with debootstrap
# (cmake/debian-packages-bundle.txt).
make_fresh_root() {
  root=$(mktemp -d)
  chmod 755 "$root"  # the root of the new system: every user walks through it
  trap 'umount "$root/proc" 2>/dev/null || true; rm -rf "$root"' EXIT
  archive=$(sh cmake/debian-archive.sh)
  echo "vkray: making a fresh Debian $1 root in $root from $archive"
  debootstrap --variant=minbase "$1" "$root" "$archive" >"$root.debootstrap.log" 2>&1 ||
    { tail -n 20 "$root.debootstrap.log"; exit 1; }
  rm -f "$root.debootstrap.log"
  cp /etc/resolv.conf "$root/etc/resolv.conf"
  mount -t proc proc "$root/proc"
}
