#!/bin/sh
# Installs the Debian packages surge needs (when missing; apt-get, as root) and builds it in Release into build/.
set -e
cd "$(dirname "$0")/.."
packages="build-essential cmake pkg-config libosmesa6-dev libpng-dev libfreetype-dev fonts-dejavu-core ffmpeg libzmq3-dev libcjson-dev libhypre-dev python3 python3-numpy python3-zmq python3-matplotlib"
missing=""
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
    echo "setup: installing$missing"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
