"""The CAX-IF's test models and a few small test shapes as STEP, IGES and BREP files, for
bench/real_parts.py --extra (issue 13: real parts from another source than the shared folder:
the CAX-IF round-robin models dm1, io1, sg1, the as1 assembly in three exports, the s1 model's
thin-walled plastic housings in three exports, cubes in three units).

The files come from the npm package `occt-import-js` (its `test/testfiles` folder; LGPL-2.1
package, the CAX-IF's models as its tests carry them). `npm pack` fetches the package into
--cache; nothing is installed. Files with the same bytes are taken once; each is written as
`cax_<its path under testfiles, '/' as '_'>` (an IGES file whose name would repeat a STEP
file's gets `_iges`). Eleven of them are assembly files that only name their parts' files:
hexmerge refuses them, naming those files.

    /usr/bin/python3.11 bench/cax_parts.py [--out /tmp/cax] [--cache /tmp/cax-npm]
    PYTHONPATH=src/python /usr/bin/python3.11 bench/real_parts.py --cad /nonexistent \\
        --extra /tmp/cax --no-generated --sizes 5k,50k

Results and what they showed: docs/benchmarks-real-parts.md, "The CAX-IF's test models".
"""
import argparse
import glob
import hashlib
import os
import shutil
import subprocess
import sys
import tarfile

PACKAGE = "occt-import-js@0.0.23"
EXTENSIONS = (".stp", ".step", ".igs", ".iges", ".brep")


def package_file(cache):
    """The package's tarball in `cache`, fetched with npm pack when it is not there yet."""
    os.makedirs(cache, exist_ok=True)
    found = sorted(glob.glob(os.path.join(cache, "occt-import-js-*.tgz")))
    if not found:
        if shutil.which("npm") is None:
            sys.exit("npm is not installed (Debian: apt-get install npm)")
        run = subprocess.run(["npm", "pack", PACKAGE], cwd=cache, capture_output=True, text=True)
        found = sorted(glob.glob(os.path.join(cache, "occt-import-js-*.tgz")))
        if not found:
            sys.exit(f"could not fetch {PACKAGE} with npm pack: {run.stderr.strip()}")
    return found[-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="/tmp/cax", help="folder to write the parts into")
    parser.add_argument("--cache", default="/tmp/cax-npm", help="folder for the package")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    seen, written = set(), []
    with tarfile.open(package_file(args.cache)) as tar:
        members = sorted((m for m in tar.getmembers()
                          if m.isfile() and m.name.startswith("package/test/testfiles/")
                          and m.name.lower().endswith(EXTENSIONS)), key=lambda m: m.name)
        for member in members:
            data = tar.extractfile(member).read()
            digest = hashlib.sha256(data).hexdigest()
            if digest in seen:
                continue
            seen.add(digest)
            relative = member.name[len("package/test/testfiles/"):]
            stem, ext = os.path.splitext(relative.replace("cax-if/", "").replace("/", "_"))
            if ext.lower() in (".igs", ".iges"):
                stem += "_iges"
            name = f"cax_{stem}{ext}".replace(" ", "_")
            with open(os.path.join(args.out, name), "wb") as out:
                out.write(data)
            written.append(name)
    print(f"{len(written)} files in {args.out}")


if __name__ == "__main__":
    main()
