"""KiCad's 3D models of electronic parts as STEP files, for bench/real_parts.py --extra (issue 13:
real parts of a kind the mesher was not developed on: component bodies with pins, connectors
with hundreds of small faces, threads, coils, assemblies of solids that touch or overlap).

The models come from Debian's `kicad-packages3d` (6,227 STEP files in 90 library folders; the
package is 379 MB, never installed: `apt-get download` fetches it into --cache, and only the
chosen files are taken out of it). One part per library folder, the one of median file size
(deterministic: the same 90 parts on every machine with the same package version), written as
`<folder>__<model>.step`.

    /usr/bin/python3.11 bench/kicad_parts.py [--out /tmp/kicad-parts] [--cache /tmp/kicad-deb]
    PYTHONPATH=src/python /usr/bin/python3.11 bench/real_parts.py --cad /nonexistent \\
        --extra /tmp/kicad-parts --no-generated --sizes 20k,100k

Results and what they showed: docs/benchmarks-real-parts.md, "KiCad's component models".
"""
import argparse
import collections
import glob
import os
import shutil
import subprocess
import sys
import tempfile

PACKAGE = "kicad-packages3d"


def package_file(cache):
    """The package's .deb in `cache`, downloaded with apt-get when it is not there yet."""
    os.makedirs(cache, exist_ok=True)
    found = sorted(glob.glob(os.path.join(cache, PACKAGE + "_*.deb")))
    if not found:
        run = subprocess.run(["apt-get", "download", PACKAGE], cwd=cache, capture_output=True,
                             text=True)
        found = sorted(glob.glob(os.path.join(cache, PACKAGE + "_*.deb")))
        if not found:
            sys.exit(f"could not download {PACKAGE} with apt-get: {run.stderr.strip()}")
    return found[-1]


def step_members(deb):
    """(size, path inside the package) of every STEP model."""
    listing = subprocess.run(["dpkg-deb", "--contents", deb], capture_output=True, text=True,
                             check=True).stdout
    members = []
    for line in listing.splitlines():
        fields = line.split()
        if len(fields) >= 6 and fields[5].lower().endswith(".step"):
            members.append((int(fields[2]), fields[5]))
    return members


def median_per_folder(members):
    """Per library folder (`Package_SO.3dshapes`, ...), the model of median size."""
    folders = collections.defaultdict(list)
    for size, path in members:
        folder = path.split("/3dmodels/", 1)[1].split("/", 1)[0]
        folders[folder].append((size, path))
    chosen = []
    for folder, files in sorted(folders.items()):
        files.sort()
        chosen.append((folder, files[len(files) // 2][1]))
    return chosen


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="/tmp/kicad-parts", help="folder for the STEP files")
    parser.add_argument("--cache", default="/tmp/kicad-deb", help="folder for the package")
    args = parser.parse_args()
    deb = package_file(args.cache)
    chosen = median_per_folder(step_members(deb))
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        listing = os.path.join(tmp, "members.txt")
        with open(listing, "w") as f:
            f.write("".join(path + "\n" for _, path in chosen))
        archive = subprocess.Popen(["dpkg-deb", "--fsys-tarfile", deb], stdout=subprocess.PIPE)
        subprocess.run(["tar", "-x", "-C", tmp, "-T", listing], stdin=archive.stdout, check=True)
        archive.stdout.close()
        if archive.wait() != 0:
            sys.exit(f"dpkg-deb could not read {deb}")
        for folder, path in chosen:
            name = folder.replace(".3dshapes", "") + "__" + os.path.basename(path)
            shutil.copyfile(os.path.join(tmp, path.lstrip("./")), os.path.join(args.out, name))
            print(os.path.join(args.out, name))
    print(f"{len(chosen)} parts from {os.path.basename(deb)} in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
