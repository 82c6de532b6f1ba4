#!/bin/sh
# Prints the Debian archive this machine's apt takes Debian 12 (bookworm) from, as its own sources
# name it (a site's mirror where it has one): where cmake/install-deps.sh adds bookworm-backports
# from and cmake/check-bundle.sh makes its fresh Debian 12 from. No archive's name is written in
# vkray's files. Exits 1, saying so, where apt's sources have no bookworm.
set -eu
archive=$(apt-get indextargets --format '$(RELEASE) $(REPO_URI)' 2>/dev/null | awk '$1 == "bookworm" {print $2; exit}')
if [ -z "$archive" ]; then
  echo "vkray: apt's sources name no archive of Debian 12 (bookworm) to take packages from: add the machine's Debian archive to /etc/apt/sources.list" >&2
  exit 1
fi
echo "$archive"
