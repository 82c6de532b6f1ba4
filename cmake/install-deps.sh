#!/bin/sh
# Installs the Debian packages listed in cmake/debian-packages.txt (or in the list file given as
# the argument) that are not installed yet. Idempotent, never prompts; runs apt-get directly as
# root and through sudo otherwise.
# A line is a package name, or a name, a release and the least version vkray needs from it
# ("mesa-vulkan-drivers bookworm-backports 25.0"): such a package is installed from that release,
# with the dependencies it needs from there, when its installed version is older; for it the
# release's apt source is added to /etc/apt/sources.list.d/vkray-RELEASE.list. docs/install.md, "What the
# install script changes", lists the effect on a machine.
set -eu
list="${1:-$(dirname "$0")/debian-packages.txt}"
if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

missing=""
from_release=""  # "name release" pairs
while read -r name release minimum; do
  [ -n "$name" ] || continue
  if [ -z "${release:-}" ]; then
    status=$(dpkg-query -W -f='${db:Status-Status}' "$name" 2>/dev/null || true)
    [ "$status" = "installed" ] || missing="$missing $name"
  else
    version=$(dpkg-query -W -f='${db:Status-Status} ${Version}' "$name" 2>/dev/null || true)
    case "$version" in
      "installed "*) dpkg --compare-versions "${version#installed }" ge "$minimum" && continue ;;
    esac
    from_release="$from_release $name:$release"
  fi
done <<EOF
$(sed 's/#.*//' "$list")
EOF
[ -z "$missing" ] && [ -z "$from_release" ] && exit 0

for entry in $from_release; do
  release="${entry#*:}"
  source_list="/etc/apt/sources.list.d/vkray-$release.list"
  if [ ! -f "$source_list" ]; then
    # From the archive the machine already takes Debian 12 from (its own sources: a site's mirror).
    archive=$(sh "$(dirname "$0")/debian-archive.sh")
    echo "vkray: adding Debian's $release from $archive to apt's sources ($source_list)"
    echo "deb $archive $release main" | $sudo tee "$source_list" >/dev/null
  fi
done
$sudo apt-get update -q
if [ -n "$missing" ]; then
  echo "vkray: installing Debian packages:$missing"
  $sudo apt-get install -y -q --no-install-recommends $missing
fi
for entry in $from_release; do
  echo "vkray: installing ${entry%%:*} from Debian's ${entry#*:}"
  $sudo apt-get install -y -q --no-install-recommends -t "${entry#*:}" "${entry%%:*}"
done
