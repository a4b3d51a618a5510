#!/usr/bin/env bash
# Builds the Debian package of leakwatch: the stripped binary, the service unit,
# an example config and env file, and the docs. Needs cargo and dpkg-deb.
#
#   packaging/deb.sh                      # cargo build --profile dist, then the package in target/deb/
#   packaging/deb.sh --binary PATH        # package this binary instead (the tests use theirs)
#   packaging/deb.sh --out DIR            # write the .deb into DIR
#   packaging/deb.sh --compress none      # dpkg-deb's compression (default xz)
#
# It prints the package's path on the last line of its output.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root_dir="$(dirname "$here")"
binary=""
out="$root_dir/target/deb"
compress="xz"
while [ $# -gt 0 ]; do
    case "$1" in
        --binary) binary="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        --compress) compress="$2"; shift 2 ;;
        *) echo "deb.sh: unknown argument $1 (see the header of $0)" >&2; exit 2 ;;
    esac
done
if [ -z "$binary" ]; then
    (cd "$root_dir" && cargo build --profile dist -p leakwatch)
    binary="${CARGO_TARGET_DIR:-$root_dir/target}/dist/leakwatch"
fi
if [ ! -x "$binary" ]; then
    echo "deb.sh: $binary is not an executable" >&2
    exit 2
fi
version="$("$binary" --version | awk '{print $2}')"
arch="$(dpkg --print-architecture)"
stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
pkg="$stage/leakwatch_${version}_${arch}"

install -d "$pkg/DEBIAN" "$pkg/usr/bin" "$pkg/lib/systemd/system" "$pkg/etc/leakwatch" \
    "$pkg/usr/share/doc/leakwatch/examples"
install -m 0755 "$binary" "$pkg/usr/bin/leakwatch"
if command -v strip >/dev/null; then
    strip --strip-unneeded "$pkg/usr/bin/leakwatch"
fi
install -m 0644 "$here/leakwatch@.service" "$pkg/lib/systemd/system/"
install -m 0644 "$here/rig.env.example" "$pkg/usr/share/doc/leakwatch/examples/"
"$pkg/usr/bin/leakwatch" init --out "$pkg/usr/share/doc/leakwatch/examples/rig.toml" >/dev/null
for doc in README.md CHANGELOG.md docs/service.md docs/rig.md docs/plant.md docs/live.md docs/config.md; do
    install -m 0644 "$root_dir/$doc" "$pkg/usr/share/doc/leakwatch/"
done
install -m 0755 "$here/postinst" "$pkg/DEBIAN/postinst"
size_kib="$(du -sk "$pkg" --exclude=DEBIAN | cut -f1)"
cat > "$pkg/DEBIAN/control" <<CONTROL
Package: leakwatch
Version: $version
Architecture: $arch
Maintainer: leakwatch developers <leakwatch@localhost>
Installed-Size: $size_kib
Depends: libc6, adduser
Section: misc
Priority: optional
Description: online leak detection for servovalve-driven hydraulic cylinders
 leakwatch tracks a hydraulic actuator at 1 kHz with an extended Kalman
 filter and names a leak out of either chamber or across the piston, with
 its size in L/min. The package holds the binary, the systemd unit
 leakwatch@.service (one instance per rig) and the docs.
CONTROL
mkdir -p "$out"
deb="$out/leakwatch_${version}_${arch}.deb"
dpkg-deb --root-owner-group -Z"$compress" --build "$pkg" "$deb" >/dev/null
echo "$deb"
