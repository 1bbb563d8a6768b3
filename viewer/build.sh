#!/bin/sh
# Bundles the viewer page's JavaScript (src/page.js with three.js and urdf-loader) into
# DESTDIR/viewer.js, which `featherdrive view` inlines into its pages.
#
#   viewer/build.sh DESTDIR
#
# Copies package.json, package-lock.json, .npmrc and src/ into DESTDIR, runs `npm ci` there when
# DESTDIR/node_modules is missing or the lock file changed since the last install, then esbuild.
# Quiet when it succeeds; one line on stderr when it fails.
set -eu

if [ "$#" -ne 1 ] || [ -z "$1" ]; then
    echo "usage: $0 DESTDIR" >&2
    exit 2
fi
DEST=$1
case $0 in */*) SRC=${0%/*} ;; *) SRC=. ;; esac
SRC=$(cd "$SRC" && pwd)

for tool in node npm; do
    command -v $tool >/dev/null 2>&1 || {
        echo "viewer/build.sh: error: '$tool' not found on PATH (it bundles the viewer page:" \
             "apt-get install -y nodejs npm)" >&2
        exit 1
    }
done

mkdir -p "$DEST/src"

# Copy a file only when its content differs, so that timestamps stay put when nothing changed.
copy() {
    if ! cmp -s "$SRC/$1" "$DEST/$1"; then
        cp "$SRC/$1" "$DEST/$1.tmp.$$" && mv -f "$DEST/$1.tmp.$$" "$DEST/$1"
    fi
}
for f in package.json package-lock.json .npmrc src/page.js; do
    copy "$f"
done

STAMP="$DEST/node_modules/.featherdrive-viewer-lock"
if ! { [ -x "$DEST/node_modules/.bin/esbuild" ] && [ -f "$STAMP" ] &&
       cmp -s "$STAMP" "$DEST/package-lock.json"; }; then
    if ! (cd "$DEST" && npm ci --no-audit --no-fund --loglevel=error >npm-ci.log 2>&1); then
        echo "viewer/build.sh: error: 'npm ci' failed in $DEST (see $DEST/npm-ci.log)" >&2
        exit 1
    fi
    rm -f "$DEST/npm-ci.log"
    cp "$DEST/package-lock.json" "$STAMP"
fi

# An IIFE for a classic inline <script>; minified: the bundle is in every page written.
if ! (cd "$DEST" && node_modules/.bin/esbuild src/page.js --bundle --minify --format=iife \
        --target=es2020 --legal-comments=none --log-level=error \
        --outfile=viewer.js.tmp >esbuild.log 2>&1); then
    echo "viewer/build.sh: error: esbuild failed in $DEST (see $DEST/esbuild.log)" >&2
    exit 1
fi
rm -f "$DEST/esbuild.log"
mv -f "$DEST/viewer.js.tmp" "$DEST/viewer.js"
