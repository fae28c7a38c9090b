#!/usr/bin/python3.11
"""Seeded random-mutation fuzzer of the mesh readers and the command line (issue 14).

Each run takes a file of tests/fuzz/corpus/readers, mutates it (truncated, a line dropped or
doubled, a number replaced by a huge, negative, fractional or non-finite one, a byte changed) and
runs `hexmerge recombine` on it in this process. What must hold:
  - the command returns 0 or 1 and never raises (no traceback); on 1, stderr is one line
    "hexmerge: error: ..." and no output file is left behind;
  - on 0, `hexmerge check OUT --source MUTATED` calls the output valid;
  - a file cut short inside a line (or, for .vtk and .msh, anywhere) is refused.
Run i of base seed S is repeatable alone with --seed S --only i.

  /usr/bin/python3.11 tests/fuzz/fuzz_readers.py --seconds 30 [--seed S] [--only I] [--verbose]
"""
from __future__ import annotations

import argparse
import contextlib
import io
import random
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "src" / "python"))

from hexmerge import cli  # noqa: E402

CORPUS = HERE / "corpus" / "readers"
NUMBER = re.compile(rb"-?\d+(\.\d*)?([eE][-+]?\d+)?")
# Formats whose files say how long they are: any cut is detectable.
SELF_SIZED = {".vtk", ".msh"}


def mutate(data: bytes, rng: random.Random) -> tuple[bytes, str, bool]:
    """The mutated bytes, what was done, and whether the file must be refused."""
    kind = rng.randrange(6)
    if kind == 0:
        cut = rng.randrange(1, len(data) - 1)
        mid_line = data[cut - 1 : cut] != b"\n"
        return data[:cut], f"cut at byte {cut}", mid_line
    lines = data.split(b"\n")
    if kind == 1:
        i = rng.randrange(len(lines))
        return b"\n".join(lines[:i] + lines[i + 1 :]), f"drop line {i + 1}", False
    if kind == 2:
        i = rng.randrange(len(lines))
        return b"\n".join(lines[: i + 1] + lines[i:]), f"double line {i + 1}", False
    if kind in (3, 4):
        numbers = list(NUMBER.finditer(data))
        m = numbers[rng.randrange(len(numbers))]
        new = rng.choice([b"999999", b"-1", b"0", b"4294967296", b"1000000000000", b"1e308",
                          b"nan", b"inf", b"2.5", b"-0", str(rng.randrange(100)).encode()])
        return data[: m.start()] + new + data[m.end() :], f"number {m.group().decode()} at byte {m.start()} -> {new.decode()}", False
    i = rng.randrange(len(data))
    b = bytes([rng.randrange(32, 127)])
    return data[:i] + b + data[i + 1 :], f"byte {i} -> {b.decode()!r}", False


def run_cli(args: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli.main(args)
    return code, err.getvalue()


def one_run(seed: int, run: int, folder: Path) -> tuple[str, str | None]:
    rng = random.Random(seed * 1000003 + run)
    files = sorted(CORPUS.iterdir())
    src = rng.choice(files)
    data, what, must_fail = mutate(src.read_bytes(), rng)
    if what.startswith("cut") and src.suffix in SELF_SIZED:
        must_fail = True
    what = f"{src.name}: {what}"
    path = folder / f"in{run}{src.suffix}"
    path.write_bytes(data)
    out = folder / f"out{run}.vtu"
    try:
        code, err = run_cli(["recombine", str(path), "-o", str(out), "-q"])
    except BaseException as e:  # noqa: BLE001 (any escape is the failure looked for)
        return what, f"raised {type(e).__name__}: {e}"
    if code == 1:
        lines = err.strip().splitlines()
        if len(lines) != 1 or not lines[0].startswith("hexmerge: error:") or "Traceback" in err:
            return what, f"error output is not one line: {err!r}"
        if out.exists():
            return what, "exit 1 but the output was written"
        return what, None
    if code != 0:
        return what, f"exit status {code}: {err!r}"
    if must_fail:
        return what, "a truncated file was read as a smaller mesh"
    code, err = run_cli(["check", str(out), "--source", str(path)])
    if code != 0:
        return what, f"the output does not pass check ({code}): {err!r}"
    return what, None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", type=int)
    ap.add_argument("--verbose", action="store_true")
    args = ap.parse_args()
    start = time.monotonic()
    runs = failures = 0
    with tempfile.TemporaryDirectory(prefix="hexmerge-fuzz-") as tmp:
        run = args.only if args.only is not None else 0
        while True:
            if args.only is not None and run > args.only:
                break
            if args.only is None and time.monotonic() - start > args.seconds:
                break
            what, failure = one_run(args.seed, run, Path(tmp))
            runs += 1
            if args.verbose:
                print(f"run {run}: {what}: {failure or 'ok'}")
            if failure:
                failures += 1
                print(f"FAIL run {run} ({what}): {failure}\n  repeat: {sys.argv[0]} --seed {args.seed} --only {run} --verbose")
                if failures >= 5:
                    break
            for p in Path(tmp).iterdir():
                p.unlink()
            run += 1
    print(f"fuzz_readers: {runs} runs, {failures} failures, {time.monotonic() - start:.0f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
