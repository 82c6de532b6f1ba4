#!/bin/sh
# Installs the Debian packages listed in cmake/debian-packages.txt (or in the list file given as
# the argument) that are not installed yet. Idempotent, never prompts; runs apt-get directly as
# root and through sudo otherwise.
set -eu
list="${1:-$(dirname "$0")/debian-packages.txt}"
missing=""
for package in $(sed 's/#.*//' "$list"); do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$package" 2>/dev/null || true)
  [ "$status" = "installed" ] || missing="$missing $package"
done
[ -z "$missing" ] && exit 0
if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
echo "vkray: installing Debian packages:$missing"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends $missing
