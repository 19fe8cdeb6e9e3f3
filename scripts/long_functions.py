#!/usr/bin/env python3
"""Lists Rust functions longer than a limit (default 120 lines), longest first.

Usage: scripts/long_functions.py [--limit N] [PATH ...]   (default PATH: src)
Relies on rustfmt layout: a function ends at the first `}` line with the
indentation of its `fn` line (closures and nested items are counted in).
"""
import argparse
import pathlib
import re

FN = re.compile(r"^(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)")


def functions(path):
    lines = path.read_text().split("\n")
    for i, line in enumerate(lines):
        m = FN.match(line)
        if not m or line.rstrip().endswith(";"):
            continue
        indent = m.group(1)
        for j in range(i + 1, len(lines)):
            if lines[j] == indent + "}":
                yield m.group(7), i + 1, j - i + 1
                break


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=int, default=120)
    ap.add_argument("paths", nargs="*", default=["src"])
    args = ap.parse_args()
    rows = []
    for root in args.paths:
        p = pathlib.Path(root)
        for f in [p] if p.is_file() else sorted(p.rglob("*.rs")):
            rows += [(n, f, name, line) for name, line, n in functions(f) if n > args.limit]
    for n, f, name, line in sorted(rows, reverse=True):
        print(f"{n:5} {f}:{line} {name}")


if __name__ == "__main__":
    main()
