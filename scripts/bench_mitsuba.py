#!/usr/bin/env python3
"""Speed and error of gradtrace against Mitsuba 3 on the Cornell box.

    python3 scripts/bench_mitsuba.py [--gradtrace BINARY] [--runs 3] [--ref-spp 1024]
                                     [--no-gradtrace] [--no-llvm]

Scene: scenes/validation/cornell_256.toml (mi.cornell_box() in our format) at
256x256, 64 spp, max depth 8, box filter. Timed at equal spp:
  * gradtrace: wall time of the whole `render` process (scene load, BVH build,
    rendering, EXR writing), median of --runs;
  * Mitsuba 3 `scalar_rgb` and `llvm_ad_rgb`: `mi.render` wall time, median of
    --runs; scene loading (`mi.load_dict`) and, for LLVM, the first render that
    JIT-compiles the kernels are reported separately.
Error: RMSE (all pixels and channels) of each 64-spp image against a converged
reference (Mitsuba `scalar_rgb` at --ref-spp (default 1024; its own noise is subtracted), cached in out/bench/). Writes
out/bench/bench_mitsuba.json and the table between the markers in
benches/README.md.

The LLVM variant needs libLLVM (Debian: `apt-get install -y libllvm19`);
DRJIT_LIBLLVM_PATH is set from `dpkg -L libllvm19` when not already set, and
the variant is skipped (with a note) when no libLLVM is found.
"""

from __future__ import annotations

import argparse
import glob
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mitsuba_scene as ms  # noqa: E402

ms.ensure_venv()


def find_libllvm() -> str | None:
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    candidates = []
    try:
        listing = subprocess.run(["dpkg", "-L", "libllvm19"], capture_output=True, text=True).stdout
        candidates += [line for line in listing.splitlines() if "/libLLVM" in line and ".so" in line]
    except OSError:
        pass
    candidates += sorted(glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM*.so*"), reverse=True)
    for c in candidates:
        if os.path.isfile(c):
            return c
    return None


LIBLLVM = find_libllvm()
if LIBLLVM:
    # Must be set before Dr.Jit initialises its LLVM backend.
    os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

SCENE = ms.REPO / "scenes" / "validation" / "cornell_256.toml"
OUT = ms.REPO / "out" / "bench"
README = ms.REPO / "benches" / "README.md"
BEGIN, END = "<!-- bench_mitsuba:begin -->", "<!-- bench_mitsuba:end -->"
W = H = 256
SPP = 64
DEPTH = 8


def cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def scene_dict(spp: int) -> dict:
    return ms.to_mitsuba_dict(ms.load_scene(SCENE), spp=spp, width=W, height=H, max_depth=DEPTH)


class Reference:
    """Converged image plus the variance of its pixel means (from 16 passes), so
    that the reference's own noise can be taken out of the RMSE:
    E|x - ref|^2 = E|x - truth|^2 + var(ref)."""

    def __init__(self, mean: np.ndarray, var: np.ndarray, spp: int):
        self.mean, self.var, self.spp = mean, var, spp

    def rmse(self, img: np.ndarray) -> float:
        mse = float(np.mean((img[..., :3].astype(np.float64) - self.mean) ** 2) - np.mean(self.var))
        return math.sqrt(max(mse, 0.0))


def reference(ref_spp: int) -> Reference:
    path = OUT / f"cornell_256_ref_{ref_spp}spp.npz"
    if path.exists():
        z = np.load(path)
        return Reference(z["mean"], z["var"], ref_spp)
    mi.set_variant("scalar_rgb")
    print(f"rendering the reference ({ref_spp} spp, scalar_rgb; cached in {path.relative_to(ms.REPO)}) ...", flush=True)
    t = time.time()
    scene = mi.load_dict(scene_dict(ref_spp))
    passes = 16
    imgs = [np.array(mi.render(scene, spp=ref_spp // passes, seed=12345 + k), dtype=np.float64)[..., :3] for k in range(passes)]
    stack = np.stack(imgs)
    mean, var = stack.mean(0), stack.var(0, ddof=1) / passes
    np.savez(path, mean=mean, var=var)
    mi.Bitmap(mean.astype(np.float32)).write(str(path.with_suffix(".exr")))
    print(f"  done in {time.time() - t:.0f} s", flush=True)
    return Reference(mean, var, ref_spp)


def bench_mitsuba(variant: str, runs: int, ref: Reference, spp: int = SPP) -> dict:
    mi.set_variant(variant)
    jit = variant.startswith(("llvm", "cuda"))
    t = time.perf_counter()
    scene = mi.load_dict(scene_dict(spp))
    load_s = time.perf_counter() - t

    def render(seed: int) -> tuple[float, np.ndarray]:
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        if jit:
            dr.eval(img)
            dr.sync_thread()
        arr = np.array(img)
        return time.perf_counter() - t0, arr

    warm_s, _ = render(0) if jit else (None, None)
    times, errs = [], []
    for i in range(runs):
        s, img = render(100 + i)
        times.append(s)
        errs.append(ref.rmse(img))
    return {
        "name": f"Mitsuba 3 {variant}" + ("" if spp == SPP else f" at {spp} spp"),
        "spp": spp,
        "render_s": statistics.median(times),
        "times_s": times,
        "load_s": load_s,
        "warmup_s": warm_s,
        "rmse": statistics.median(errs),
    }


def bench_gradtrace(binary: str | None, runs: int, ref: Reference) -> dict:
    OUT.mkdir(parents=True, exist_ok=True)
    if binary is None:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ms.REPO, check=True)
        binary = str(ms.REPO / "target" / "release" / "gradtrace")
    times, errs = [], []
    for i in range(runs):
        out = OUT / f"gradtrace_{i}.exr"
        t0 = time.perf_counter()
        subprocess.run(
            [binary, "render", str(SCENE), "--out", str(out), "--spp", str(SPP), "--no-aovs", "--quiet"],
            cwd=ms.REPO,
            check=True,
        )
        times.append(time.perf_counter() - t0)
        bmp = mi.Bitmap(str(out))
        names = [bmp.struct_()[k].name for k in range(bmp.channel_count())]
        arr = np.array(bmp, dtype=np.float64)
        img = np.stack([arr[..., names.index(c)] for c in "RGB"], -1)
        errs.append(ref.rmse(img))
    return {
        "name": "gradtrace",
        "spp": SPP,
        "render_s": statistics.median(times),
        "times_s": times,
        "load_s": None,
        "warmup_s": None,
        "rmse": statistics.median(errs),
        "note": "whole process: load + BVH + render + EXR",
    }


def markdown(rows: list[dict], meta: dict) -> str:
    base = next((r for r in rows if r["name"].endswith("scalar_rgb")), rows[0])
    lines = [
        f"Cornell box (`mi.cornell_box()`), {W}x{H}, {SPP} spp, max depth {DEPTH}, box filter; "
        f"median of {meta['runs']} runs on {meta['cpus']} CPU threads ({meta['cpu']}); "
        f"RMSE against Mitsuba `scalar_rgb` at {meta['ref_spp']} spp (its own noise subtracted). "
        f"Measured {meta['date']}, load average {meta['load_avg']:.1f} (shared machine: ratios are indicative).",
        "",
        "| renderer | spp | time (s) | vs scalar_rgb | RMSE | scene load (s) | JIT warm-up (s) |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        f = lambda x: "—" if x is None else f"{x:.2f}"  # noqa: E731
        lines.append(
            f"| {r['name']} | {r['spp']} | {r['render_s']:.2f} | {base['render_s'] / r['render_s']:.2f}× | {r['rmse']:.4f} | "
            f"{f(r['load_s'])} | {f(r['warmup_s'])} |"
        )
    for note in meta["notes"]:
        lines.append(f"\n{note}")
    return "\n".join(lines)


def write_readme(table: str) -> None:
    text = README.read_text() if README.exists() else "# Benchmarks\n"
    block = f"{BEGIN}\n{table}\n{END}"
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        text = head + block + rest.split(END, 1)[1]
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    README.parent.mkdir(parents=True, exist_ok=True)
    README.write_text(text)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gradtrace", help="gradtrace binary (default: cargo build --release, target/release/gradtrace)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=1024, help="reference spp, a multiple of 16 (its noise is subtracted from the RMSE, so 1024 suffices)")
    ap.add_argument("--no-gradtrace", action="store_true", help="time the Mitsuba variants only")
    ap.add_argument("--no-llvm", action="store_true", help="skip llvm_ad_rgb")
    ap.add_argument("--no-equal-error", action="store_true", help="skip the equal-error Mitsuba renders")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    notes = [
        "gradtrace's time is the whole `gradtrace render --no-aovs` process (load, BVH, render, EXR+PNG); "
        "Mitsuba's is `mi.render` alone, "
        "with `mi.load_dict` and the first (JIT-compiling) LLVM render listed separately."
    ]

    ref = reference(args.ref_spp)
    rows = []
    if not args.no_gradtrace:
        if args.gradtrace is None and shutil.which("cargo") is None:
            ap.error("cargo not found; pass --gradtrace BINARY or --no-gradtrace")
        rows.append(bench_gradtrace(args.gradtrace, args.runs, ref))
        print(rows[-1], flush=True)
    rows.append(bench_mitsuba("scalar_rgb", args.runs, ref))
    print(rows[-1], flush=True)
    if not args.no_llvm:
        if LIBLLVM is None:
            notes.append("llvm_ad_rgb skipped: no libLLVM found (apt-get install -y libllvm19).")
        else:
            rows.append(bench_mitsuba("llvm_ad_rgb", args.runs, ref))
            print(rows[-1], flush=True)
    # Equal error: Monte Carlo error falls as 1/sqrt(spp), so each Mitsuba variant
    # is rendered again at the spp that should bring its RMSE down to gradtrace's,
    # and measured (its RMSE is in the table, so the match can be checked).
    ours = next((r for r in rows if r["name"] == "gradtrace"), None)
    if ours is not None and not args.no_equal_error:
        for r in [r for r in rows if r["name"].startswith("Mitsuba")]:
            variant = r["name"].split()[2]
            spp_eq = max(SPP, int(math.ceil(SPP * (r["rmse"] / ours["rmse"]) ** 2 / 16.0)) * 16)
            rows.append(bench_mitsuba(variant, 1, ref, spp=spp_eq))
            print(rows[-1], flush=True)
        best = {r["name"].split()[2]: r for r in rows if r["name"].startswith("Mitsuba") and r["spp"] != SPP}
        for variant, r in best.items():
            notes.append(
                f"At equal error (RMSE {ours['rmse']:.4f} vs {r['rmse']:.4f}), gradtrace is "
                f"{r['render_s'] / ours['render_s']:.2f}× faster than Mitsuba 3 {variant}."
            )
    meta = {
        "scene": str(SCENE.relative_to(ms.REPO)),
        "width": W,
        "height": H,
        "spp": SPP,
        "max_depth": DEPTH,
        "runs": args.runs,
        "ref_spp": args.ref_spp,
        "cpus": os.cpu_count(),
        "cpu": cpu_name(),
        "mitsuba": mi.__version__,
        "libllvm": LIBLLVM,
        "load_avg": os.getloadavg()[0],
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "notes": notes,
    }
    (OUT / "bench_mitsuba.json").write_text(json.dumps({"meta": meta, "results": rows}, indent=2))
    table = markdown(rows, meta)
    write_readme(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
