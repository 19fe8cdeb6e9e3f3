#!/usr/bin/env python3
"""What `--gradients` costs, part by part (issue 53): CPU seconds (user + sys of the
render process, so that a loaded machine still compares) of a plain render and of
gradient renders that add one part at a time, at the same spp, on each scene; the
median of `--rounds` rounds in which the variants take turns, and each as a
multiple of the plain render.

    python3 scripts/gradient_cost.py [--scenes a,b] [--size 160x120] [--spp 8] [--rounds 3]

Build first (`cargo build --release`).
"""
import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
VARIANTS = [
    ("plain", []),
    ("shading terms (--vis-samples 0)", ["--gradients", "--vis-samples", "0"]),
    ("+ lines, rings almost never (--vis-gate 1e-6)", ["--gradients", "--vis-gate", "1e-6"]),
    ("+ gated rings (the default)", ["--gradients"]),
    ("+ every ring (--vis-gate 1)", ["--gradients", "--vis-gate", "1"]),
    ("every ring, 32 rays per line (the old default)",
     ["--gradients", "--vis-gate", "1", "--vis-samples", "32"]),
]


def cpu_seconds(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="spheres_table,objects_bumpy,three_spheres_env,bunny_env")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", default="8")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    w, h = a.size.split("x")
    binary = str(ROOT / "target/release/gradtrace")
    out = os.path.join(tempfile.mkdtemp(), "cost.exr")
    names = a.scenes.split(",")
    print(f"| variant ({a.size}, {a.spp} spp; CPU s, median of {a.rounds}) | "
          + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    table = {v: {} for v, _ in VARIANTS}
    for scene in names:
        base = [binary, "render", str(ROOT / f"scenes/{scene}.toml"), "--width", w,
                "--height", h, "--spp", a.spp, "--quiet", "--no-aovs", "--out", out]
        times = {v: [] for v, _ in VARIANTS}
        for _ in range(a.rounds):
            for v, flags in VARIANTS:
                times[v].append(cpu_seconds(base + flags))
        plain = statistics.median(times["plain"])
        for v, _ in VARIANTS:
            t = statistics.median(times[v])
            table[v][scene] = f"{t:.2f} ({t / plain:.1f}×)"
    for v, _ in VARIANTS:
        print(f"| {v} | " + " | ".join(table[v][s] for s in names) + " |")


if __name__ == "__main__":
    main()
