#!/bin/sh
# SPDX-License-Identifier: MIT
#
# Recipe of the iec2kmod module-build container's root file system.
#
#   build-rootfs.sh ROOTFS MIRROR SECURITY_MIRROR KERNEL_RELEASE HEADERS_VERSION
#
# debootstraps Debian bookworm (minbase) into ROOTFS from MIRROR, then installs,
# with apt inside a chroot, the toolchain and exactly the PREEMPT_RT kbuild
# headers the host has (linux-headers-KERNEL_RELEASE=HEADERS_VERSION), so that
# modules built in the container carry the same vermagic and symbol CRCs.
# iec2kmod/container.py runs it as root, tars ROOTFS and `docker import`s it;
# the image tag is a hash of this directory plus the headers version, so any
# edit here makes a new image.  Nothing is ever pulled from an image registry.
set -eu

ROOTFS=$1 MIRROR=$2 SECMIRROR=$3 KREL=$4 KVERSION=$5
SUITE=bookworm
PACKAGES="build-essential make gcc kmod python3 ca-certificates linux-headers-$KREL=$KVERSION"

say() { printf '[container-rootfs] %s\n' "$*"; }

[ "$(id -u)" = 0 ] || { echo "build-rootfs.sh must run as root" >&2; exit 1; }
command -v debootstrap >/dev/null || { echo "debootstrap missing: apt-get install debootstrap" >&2; exit 1; }

say "debootstrap --variant=minbase $SUITE $ROOTFS $MIRROR"
debootstrap --variant=minbase "$SUITE" "$ROOTFS" "$MIRROR" >"$ROOTFS.debootstrap.log" 2>&1 || {
    tail -n 30 "$ROOTFS.debootstrap.log" >&2
    echo "debootstrap failed (full log: $ROOTFS.debootstrap.log)" >&2
    exit 1
}
rm -f "$ROOTFS.debootstrap.log"

cat >"$ROOTFS/etc/apt/sources.list" <<SOURCES
deb $MIRROR $SUITE main
deb $MIRROR $SUITE-updates main
deb $SECMIRROR $SUITE-security main
SOURCES
# no recommends, no docs/man pages, no daemons started by maintainer scripts
cat >"$ROOTFS/etc/apt/apt.conf.d/90iec2kmod" <<'APT'
APT::Install-Recommends "false";
APT::Install-Suggests "false";
APT
cat >"$ROOTFS/etc/dpkg/dpkg.cfg.d/90iec2kmod" <<'DPKG'
path-exclude=/usr/share/doc/*
path-exclude=/usr/share/man/*
path-exclude=/usr/share/info/*
path-exclude=/usr/share/locale/*
DPKG
printf '#!/bin/sh\nexit 101\n' >"$ROOTFS/usr/sbin/policy-rc.d"
chmod 755 "$ROOTFS/usr/sbin/policy-rc.d"
cp /etc/resolv.conf "$ROOTFS/etc/resolv.conf" 2>/dev/null || true

cleanup() {
    umount "$ROOTFS/proc" 2>/dev/null || true
    umount "$ROOTFS/dev" 2>/dev/null || true
}
trap cleanup EXIT
mount -t proc proc "$ROOTFS/proc"
mount --bind /dev "$ROOTFS/dev"

say "apt-get install $PACKAGES"
chroot "$ROOTFS" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive \
    sh -c "apt-get -q update && apt-get -q -y install $PACKAGES && apt-get clean" \
    >"$ROOTFS.apt.log" 2>&1 || {
    tail -n 30 "$ROOTFS.apt.log" >&2
    echo "apt-get install in the container root failed (full log: $ROOTFS.apt.log)" >&2
    exit 1
}
rm -f "$ROOTFS.apt.log"
cleanup
trap - EXIT

rm -rf "$ROOTFS/var/lib/apt/lists/"* "$ROOTFS/var/cache/apt/"*.bin "$ROOTFS/usr/sbin/policy-rc.d"
: >"$ROOTFS/etc/resolv.conf"
test -f "$ROOTFS/usr/src/linux-headers-$KREL/Module.symvers" || {
    echo "linux-headers-$KREL missing in the container root" >&2; exit 1; }
say "root file system ready: $ROOTFS"
