#!/bin/sh
# Installs the Debian packages surge needs (when missing; apt-get, as root), installs the Python package surgepy
# (pyproject.toml, python/surgepy) editable into Debian's python3, and builds surge in Release into build/.
set -e
cd "$(dirname "$0")/.."
packages="build-essential cmake pkg-config libosmesa6-dev libpng-dev libfreetype-dev fonts-dejavu-core ffmpeg libzmq3-dev libcjson-dev libhypre-dev liblapacke-dev python3 python3-numpy python3-zmq python3-matplotlib"
# what installs surgepy, offline: Debian's pip and setuptools (without pip's recommended python3-dev)
python_build="python3-pip python3-setuptools python3-wheel"
missing_of() {
    for p in "$@"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || printf ' %s' "$p"
    done
}
missing=$(missing_of $packages)
missing_python_build=$(missing_of $python_build)
# apt-get install with its arguments, saying every 10 s how far it got; its whole log on failure
apt_install() {
    log=$(mktemp)
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q -o Dpkg::Use-Pty=0 "$@" >"$log" 2>&1 &
    pid=$!
    while kill -0 "$pid" 2>/dev/null; do
        sleep 10
        echo "setup: $(grep -c '^Get:' "$log") packages downloaded, $(grep -c '^Unpacking' "$log") unpacked, $(grep -c '^Setting up' "$log") set up"
    done
    if ! wait "$pid"; then
        cat "$log" >&2
        rm -f "$log"
        echo "setup: apt-get install failed (its log is above)" >&2
        exit 1
    fi
    echo "setup: $(grep -c '^Setting up' "$log") packages set up"
    rm -f "$log"
}
if [ -n "$missing$missing_python_build" ]; then
    echo "setup: installing$missing$missing_python_build and what they need (on a bare machine a download of a few" \
         "hundred MB and a few minutes)"
    apt-get update -qq
    [ -z "$missing" ] || apt_install $missing
    [ -z "$missing_python_build" ] || apt_install --no-install-recommends $missing_python_build
fi
# surgepy, editable: this tree's python/ goes on Debian's python3 path (a .pth file and surgepy's dist-info in its
# site-packages, /usr/local/lib/python3.*/dist-packages as root), so tools, studies and tests import this tree's
# files. Its dependencies are the apt packages above; nothing is fetched (--no-index). Skipped when this tree's
# surgepy, at pyproject.toml's version, is the one installed.
installed() {
    (cd / && env -u PYTHONPATH /usr/bin/python3 -c '
import importlib.metadata, os, sys, tomllib
import surgepy
root = sys.argv[1]
with open(os.path.join(root, "pyproject.toml"), "rb") as f:
    version = tomllib.load(f)["project"]["version"]
here = os.path.samefile(os.path.dirname(surgepy.__file__), os.path.join(root, "python", "surgepy"))
sys.exit(0 if here and importlib.metadata.version("surgepy") == version else 1)' "$1") >/dev/null 2>&1
}
if ! installed "$PWD"; then
    /usr/bin/python3 -m pip install --quiet --no-deps --no-build-isolation --no-index --break-system-packages \
        --root-user-action=ignore --disable-pip-version-check --editable .
    installed "$PWD" || { echo "setup: surgepy is installed, but /usr/bin/python3 imports" \
        "$(cd / && /usr/bin/python3 -c 'import surgepy; print(surgepy.__file__)' 2>&1)" >&2; exit 1; }
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
