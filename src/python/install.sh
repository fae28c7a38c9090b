#!/bin/sh
# Puts the checkout's Python package on /usr/bin/python3.11's path and a `hexmerge` command on
# the PATH. Idempotent: run it again after moving the checkout. Needs root (writes /usr/local).
# Build the module first (cmake ... && cmake --build ...): it lands in src/python/hexmerge.
set -eu

here=$(cd "$(dirname "$0")" && pwd)
python=/usr/bin/python3.11
site=${HEXMERGE_SITE_DIR:-/usr/local/lib/python3.11/dist-packages}
bindir=${HEXMERGE_BIN_DIR:-/usr/local/bin}

mkdir -p "$site" "$bindir"
printf '%s\n' "$here" > "$site/hexmerge.pth"

cat > "$bindir/hexmerge.tmp.$$" <<WRAPPER
#!/bin/sh
# Installed by $here/install.sh
exec $python -m hexmerge "\$@"
WRAPPER
chmod 755 "$bindir/hexmerge.tmp.$$"
mv -f "$bindir/hexmerge.tmp.$$" "$bindir/hexmerge"

if ! ls "$here"/hexmerge/_core*.so >/dev/null 2>&1; then
  echo "install.sh: note: hexmerge._core is not built yet; build the project before use" >&2
  exit 0
fi
# Smoke test from a neutral folder, so the import comes through the .pth file (only for the
# default folders: another site folder is not on the interpreter's path by itself).
if [ -z "${HEXMERGE_SITE_DIR:-}" ]; then
  (cd / && "$python" -c "import hexmerge" && "$bindir/hexmerge" --version)
fi
