#!/usr/bin/env bash
# Installs what the Cortex-M4F simulation needs, idempotently:
# - Debian's Rust 1.96 with its library sources (builds `core` for thumbv7em-none-eabihf with
#   -Zbuild-std=core; rustup cannot download targets here) and lld-22;
# - QEMU's runtime libraries, and qemu-system-arm unpacked from its .deb into .tools/qemu
#   (never apt-installed: its dependencies would replace the machine's newer qemu-utils).
# Prints the paths it set up. Safe to run any number of times.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
tools="$root/.tools"
qemu_dir="$tools/qemu"
qemu="$qemu_dir/usr/bin/qemu-system-arm"

sudo_if_needed() {
    if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

packages=(rustc-web cargo-web rust-web-src lld-22
          libfdt1 libcapstone4 libpmem1 librdmacm1 libibverbs1 libslirp0 libvdeplug2)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing: ${missing[*]}"
    sudo_if_needed apt-get update -qq
    sudo_if_needed env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ ! -x "$qemu" ]; then
    # apt's sandbox user must be able to write where it downloads.
    download=$(mktemp -d)
    chmod 777 "$download"
    (cd "$download" && apt-get download qemu-system-arm >/dev/null)
    rm -rf "$qemu_dir"
    mkdir -p "$qemu_dir"
    dpkg-deb -x "$download"/qemu-system-arm_*.deb "$qemu_dir"
    rm -rf "$download"
fi

"$qemu" --version | head -n 1
/usr/bin/rustc --version
echo "QEMU=$qemu"
echo "RUSTC=/usr/bin/rustc CARGO=/usr/bin/cargo LLD=/usr/lib/llvm-22/bin/ld.lld"
