#!/usr/bin/env bash
# Builds oneTBB with -fsanitize=thread for the ThreadSanitizer stage of tools/test.sh and prints
# the directory to pass as -DTBB_DIR. Why: Debian's libtbb is not instrumented, so TSan cannot see
# the synchronisation by which oneTBB hands a task from one thread to another, and every parallel
# loop or flow graph then "races". The source is Debian 12's own (the same 2021.8.0 that
# libtbb-dev ships), fetched from deb.debian.org and checked against the sha256 in its .dsc.
# Cached: a second call with the install present does nothing (about 35 s on 2 cores otherwise).
#   bash tools/install_tsan_tbb.sh [DIR]      (default build-tbb-tsan; prints DIR/install/lib/cmake/TBB)
set -euo pipefail
cd "$(dirname "$0")/.."
root=${1:-build-tbb-tsan}
version=2021.8.0
sha256=7e9111b8bb59c8800bf6d0b06afe7b0891937443d2dae1ee1101c8e2ede6a7ef
url=http://deb.debian.org/debian/pool/main/o/onetbb/onetbb_${version}.orig.tar.xz
install="$PWD/$root/install"
stamp="$install/.sph-tsan-$sha256"

if [ -f "$stamp" ] && [ -f "$install/lib/cmake/TBB/TBBConfig.cmake" ]; then
  echo "$install/lib/cmake/TBB"
  exit 0
fi
mkdir -p "$root"
rm -rf "$root/src" "$root/build" "$install"
# Fetch, check and unpack in python3 (tools/install_deps.sh installs it): curl, wget and xz-utils
# are not on a minimal Debian.
python3 - "$url" "$root/onetbb_${version}.orig.tar.xz" "$sha256" "$root/src" <<'EOF' >&2
import hashlib, os, sys, tarfile, urllib.request
url, tarball, sha, dest = sys.argv[1:]
def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest() if os.path.exists(path) else ""
if digest(tarball) != sha:
    with urllib.request.urlopen(url, timeout=120) as r, open(tarball + ".part", "wb") as f:
        f.write(r.read())
    if digest(tarball + ".part") != sha:
        sys.exit(f"install_tsan_tbb.sh: {url} does not match sha256 {sha} (from Debian 12's .dsc)")
    os.replace(tarball + ".part", tarball)
with tarfile.open(tarball, "r:xz") as t:
    top = t.getnames()[0].split("/")[0]
    t.extractall(os.path.dirname(dest))
os.rename(os.path.join(os.path.dirname(dest), top), dest)
print(f"unpacked {tarball} into {dest}")
EOF
# Only libtbb (the scheduler and the flow graph): no tests, no tbbmalloc (the engine uses the
# standard allocator), no hwloc (tbbbind is not needed).
cmake -S "$root/src" -B "$root/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DTBB_SANITIZE=thread -DTBB_TEST=OFF \
  -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON \
  -DCMAKE_INSTALL_PREFIX="$install" >/dev/null
cmake --build "$root/build" -j"$(nproc)" >/dev/null
cmake --install "$root/build" >/dev/null
touch "$stamp"
echo "$install/lib/cmake/TBB"
