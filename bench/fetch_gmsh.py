#!/usr/bin/python3.11
"""A newer Gmsh for the benchmarks, unpacked beside the system (issue 13's Gmsh comparison).

Issue 13 compares hexmerge with Gmsh's own hex-dominant mesher, Gmsh >= 4.12
(`Mesh.Algorithm3D=9`, `Mesh.Recombine3DAll=1`); Debian 12 ships Gmsh 4.8.4. Debian 13
("trixie") ships 4.13.1. This script downloads trixie's `gmsh` package and every package it
depends on, recursively (glibc included: trixie's binaries need its C library), from Debian's
archive, unpacks them with `dpkg-deb -x` into a folder of their own (nothing is installed, the
system is not touched), and writes a `gmsh` script there that runs the binary with trixie's
dynamic loader and libraries:

    DEST/gmsh --version        # 4.13.1

About 140 packages, 115 MB downloaded. Run again, it keeps what is there (a working DEST/gmsh is
not fetched again; --force fetches anew). bench/gmsh_reference.py takes it with `--gmsh DEST/gmsh`
(or $HEXMERGE_GMSH).

Usage:
  /usr/bin/python3.11 bench/fetch_gmsh.py                      # into ~/.cache/hexmerge/gmsh-trixie
  /usr/bin/python3.11 bench/fetch_gmsh.py --dest /tmp/gmsh413
"""
import argparse
import concurrent.futures
import lzma
import os
import subprocess
import sys
import urllib.request

MIRROR = "http://deb.debian.org/debian"
DEFAULT_DEST = os.path.join(os.path.expanduser("~"), ".cache", "hexmerge", "gmsh-trixie")
# Packages a binary never loads (maintainer scripts' tools): their dependency trees are left out.
NOT_NEEDED = {"debconf", "perl-base", "dpkg"}
WRAPPER = """#!/bin/sh
# Gmsh from Debian {suite}, unpacked by bench/fetch_gmsh.py: run with {suite}'s loader and libraries.
R=$(dirname "$(readlink -f "$0")")
L=$R/usr/lib/x86_64-linux-gnu
exec "$L/ld-linux-x86-64.so.2" --library-path "$L:$R/usr/lib:$L/blas:$L/lapack" "$R/usr/bin/gmsh" "$@"
"""


def packages(suite: str) -> dict:
    """Debian's package index of a suite (main, amd64): name -> fields."""
    url = f"{MIRROR}/dists/{suite}/main/binary-amd64/Packages.xz"
    with urllib.request.urlopen(url, timeout=120) as r:
        text = lzma.decompress(r.read()).decode("utf-8", "replace")
    index = {}
    for stanza in text.split("\n\n"):
        fields = {}
        for line in stanza.splitlines():
            if line and not line[0].isspace() and ":" in line:
                key, _, value = line.partition(":")
                fields[key] = value.strip()
        if "Package" in fields:
            index[fields["Package"]] = fields
    return index


def closure(index: dict, root: str) -> list:
    """The packages `root` needs, recursively (Depends and Pre-Depends; the first of each
    alternative; a virtual package by the first package that provides it)."""
    provider = {}
    for name, fields in index.items():
        for item in fields.get("Provides", "").split(","):
            virtual = item.strip().split(" ")[0]
            if virtual:
                provider.setdefault(virtual, name)
    todo, seen = [root], set()
    while todo:
        name = todo.pop()
        name = name if name in index else provider.get(name, name)
        if name in seen or name in NOT_NEEDED:
            continue
        if name not in index:
            raise SystemExit(f"fetch_gmsh: {name} is in no package of the index")
        seen.add(name)
        for key in ("Depends", "Pre-Depends"):
            for alternatives in index[name].get(key, "").split(","):
                first = alternatives.split("|")[0].strip().split(" ")[0].split(":")[0]
                if first:
                    todo.append(first)
    return sorted(seen)


def works(gmsh: str) -> str:
    """`gmsh --version`'s text, or "" when the script does not run."""
    try:
        p = subprocess.run([gmsh, "--version"], capture_output=True, text=True, timeout=60)
    except OSError:
        return ""
    return (p.stdout + p.stderr).strip() if p.returncode == 0 else ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dest", default=DEFAULT_DEST, help="folder to unpack into (default: %(default)s)")
    ap.add_argument("--suite", default="trixie", help="Debian suite (default: %(default)s)")
    ap.add_argument("--force", action="store_true", help="fetch again even where DEST/gmsh works")
    args = ap.parse_args()
    gmsh = os.path.join(args.dest, "gmsh")
    version = "" if args.force else works(gmsh)
    if version:
        print(f"fetch_gmsh: {gmsh} is there: Gmsh {version}")
        return 0
    index = packages(args.suite)
    names = closure(index, "gmsh")
    debs = os.path.join(args.dest, "debs")
    os.makedirs(debs, exist_ok=True)
    size = sum(int(index[n].get("Size", 0)) for n in names)
    print(f"fetch_gmsh: Gmsh {index['gmsh']['Version']} from Debian {args.suite}: {len(names)} packages, "
          f"{size / 1e6:.0f} MB", flush=True)

    def fetch(name: str) -> str:
        path = os.path.join(debs, os.path.basename(index[name]["Filename"]))
        if not os.path.exists(path) or os.path.getsize(path) != int(index[name].get("Size", -1)):
            with urllib.request.urlopen(f"{MIRROR}/{index[name]['Filename']}", timeout=300) as r:
                data = r.read()
            with open(path + ".part", "wb") as f:
                f.write(data)
            os.replace(path + ".part", path)
        return path

    with concurrent.futures.ThreadPoolExecutor(max_workers=8) as pool:
        files = list(pool.map(fetch, names))
    for path in files:
        subprocess.run(["dpkg-deb", "-x", path, args.dest], check=True)
    with open(gmsh, "w") as f:
        f.write(WRAPPER.format(suite=args.suite))
    os.chmod(gmsh, 0o755)
    version = works(gmsh)
    if not version:
        print(f"fetch_gmsh: {gmsh} does not run", file=sys.stderr)
        return 1
    print(f"fetch_gmsh: {gmsh}: Gmsh {version}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
