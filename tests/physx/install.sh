#!/bin/sh
# Installs the PhysX comparison harness into a build-tree folder.
#
#   tests/physx/install.sh DESTDIR
#
# Copies package.json, package-lock.json, .npmrc and the harness scripts into DESTDIR
# and runs `npm ci` there when DESTDIR/node_modules is missing or the lock file changed
# since the last install. Quick and silent when everything is up to date.
set -eu

if [ "$#" -ne 1 ] || [ -z "$1" ]; then
    echo "usage: $0 DESTDIR" >&2
    exit 2
fi
DEST=$1
case $0 in */*) SRC=${0%/*} ;; *) SRC=. ;; esac
SRC=$(cd "$SRC" && pwd)

command -v node >/dev/null 2>&1 || { echo "install.sh: error: 'node' not found on PATH (Node.js >= 18 is needed for the PhysX harness)" >&2; exit 1; }
command -v npm >/dev/null 2>&1 || { echo "install.sh: error: 'npm' not found on PATH (needed to install physx-js-webidl for the PhysX harness)" >&2; exit 1; }
node -e 'process.exit(Number(process.versions.node.split(".")[0]) >= 18 ? 0 : 1)' ||
    { echo "install.sh: error: Node.js >= 18 is needed for the PhysX harness, found $(node --version)" >&2; exit 1; }

mkdir -p "$DEST"

# Copy a file only when its content differs, so that timestamps stay put when nothing changed.
copy() {
    if ! cmp -s "$SRC/$1" "$DEST/$1"; then
        cp "$SRC/$1" "$DEST/$1.tmp.$$" && mv -f "$DEST/$1.tmp.$$" "$DEST/$1"
    fi
}
for f in package.json package-lock.json .npmrc harness.js physx_loader.js selfcheck.js; do
    copy "$f"
done

STAMP="$DEST/node_modules/.featherdrive-physx-lock"
if [ -f "$DEST/node_modules/physx-js-webidl/physx-js-webidl.wasm" ] && [ -f "$STAMP" ] &&
   cmp -s "$STAMP" "$DEST/package-lock.json"; then
    exit 0
fi

if ! (cd "$DEST" && npm ci --no-audit --no-fund --loglevel=error >npm-ci.log 2>&1); then
    echo "install.sh: error: 'npm ci' failed in $DEST (see $DEST/npm-ci.log)" >&2
    exit 1
fi
rm -f "$DEST/npm-ci.log"
cp "$DEST/package-lock.json" "$STAMP"
