#!/usr/bin/env python3
"""Speed and error of gradtrace against Mitsuba 3, each at its best sampler.

    python3 scripts/bench_mitsuba.py [--gradtrace BINARY] [--native [BINARY]] [--pgo [BINARY]]
                                     [--before BINARY] [--no-mitsuba]
                                     [--runs 10]
                                     [--ref-spp 1024] [--scenes cornell,bunny]
                                     [--no-gradtrace] [--no-llvm]

Scenes: `cornell` = scenes/validation/cornell_256.toml (mi.cornell_box() in our
format), 256x256, 64 spp, max depth 8; `bunny` = the Stanford bunny (diffuse, on a
floor) under a constant environment, written to out/bench/, 128x128, 256 spp, max
depth 5. Box filter. Timed at equal spp:
  * gradtrace (Owen-scrambled Sobol): its render time (`gradtrace.render_time_s`
    in the EXR header: light set-up, rendering and the film, as `mi.render`
    covers), median of --runs; the rest of the `render` process (scene load, BVH
    build, EXR and PNG writing) is reported separately as its scene load;
    with --native, a `dist` build for this machine's CPU (`RUSTFLAGS="-C
    target-cpu=native"`, in target/native/; what Mitsuba's LLVM JIT and Embree's
    ISA dispatch do for theirs) as a further row, and with --pgo the PGO build
    of scripts/build_pgo.sh (each built here unless a BINARY is given); their
    ratios against the Mitsuba rows follow each table; with --before, a build from
    before a change, timed in the same rounds, and the default build's render
    time over its (median and per round: a refactor's "no speed lost" check);
  * Mitsuba 3 `scalar_rgb` (independent sampler) and `llvm_ad_rgb` with each of
    its `independent`, `multijitter` and `ldsampler` samplers: `mi.render` wall
    time, median of --runs; scene loading (`mi.load_dict`) and, for LLVM, the
    first render that JIT-compiles the kernels are reported separately.
  The renderers take turns, round by round (each renders once per round), so that
  a change in the machine's load during the run reaches every row alike.
Error: RMSE (all pixels and channels) against a converged reference (Mitsuba
`scalar_rgb` at --ref-spp; its own noise is subtracted), cached in out/bench/.
Efficiency ratio = (t·RMSE²)_gradtrace / (t·RMSE²)_Mitsuba: the ratio of the times
both would need for equal error (Monte Carlo error² ∝ 1/t); below 1 gradtrace is
more efficient. RMSE: the median of the rounds' (each round has its own seed); a
further column takes the rounds' mean MSE instead (the expected MSE that
efficiency is defined with), with its 95 % bootstrap interval over the rounds.
Writes out/bench/bench_mitsuba.json and, when gradtrace and the
LLVM rows both ran, the table between the markers in benches/README.md.

The LLVM variant needs libLLVM (Debian: `apt-get install -y libllvm19`);
DRJIT_LIBLLVM_PATH is set from `dpkg -L libllvm19` when not already set; with
no libLLVM found the script stops at once, unless --no-llvm leaves it out.
"""

from __future__ import annotations

import argparse
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


LIBLLVM = ms.find_libllvm()
if LIBLLVM:
    # Must be set before Dr.Jit initialises its LLVM backend.
    os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

OUT = ms.REPO / "out" / "bench"
README = ms.REPO / "benches" / "README.md"
BEGIN, END = "<!-- bench_mitsuba:begin -->", "<!-- bench_mitsuba:end -->"
LLVM_SAMPLERS = ["independent", "multijitter", "ldsampler"]

BUNNY_TOML = """# Written by scripts/bench_mitsuba.py: the Stanford bunny under a constant environment.
[camera]
from = [0.0, 0.75, 2.6]
to = [0.0, 0.5, 0.0]
up = [0, 1, 0]
fov = 30
resolution = [128, 128]

[render]
spp = 256
max_depth = 5
rr_depth = 5
seed = 0
integrator = "path"

[materials.floor]
type = "lambert"
albedo = [0.5, 0.45, 0.4]

[materials.bunny]
type = "lambert"
albedo = [0.8, 0.8, 0.8]

[[shapes]]
name = "floor"
type = "quad"
corner = [-3, 0, 3]
edge_u = [6, 0, 0]
edge_v = [0, 0, -6]
material = "floor"

[[shapes]]
name = "bunny"
type = "mesh"
file = "{obj}"
material = "bunny"
transform = {{ scale = 8, translate = [0.134, -0.2639, 0.012] }}

[environment]
type = "constant"
radiance = [1.0, 1.0, 1.0]
"""


class Bench:
    """One benchmark scene: its file, resolution, spp and depth."""

    def __init__(self, key: str, path: Path, label: str):
        spec = ms.load_scene(path)
        cam, r = spec.camera(), spec.render()
        self.key, self.path, self.label, self.spec = key, path, label, spec
        self.w, self.h, self.spp, self.depth = int(cam["width"]), int(cam["height"]), int(r["spp"]), int(r["max_depth"])

    def mitsuba_dict(self, spp: int, sampler: str = "independent") -> dict:
        d = ms.to_mitsuba_dict(self.spec, spp=spp, width=self.w, height=self.h, max_depth=self.depth)
        d["sensor"]["sampler"]["type"] = sampler
        return d


def benches(keys: list[str]) -> list[Bench]:
    OUT.mkdir(parents=True, exist_ok=True)
    out = []
    for key in keys:
        if key == "cornell":
            out.append(Bench(key, ms.REPO / "scenes" / "validation" / "cornell_256.toml", "Cornell box (`mi.cornell_box()`)"))
        elif key == "bunny":
            path = OUT / "bunny_env_constant.toml"
            obj = (ms.REPO / "scenes" / "models" / "stanford-bunny.obj").as_posix()
            path.write_text(BUNNY_TOML.format(obj=obj))
            out.append(Bench(key, path, "Stanford bunny (69k triangles, diffuse) under a constant environment"))
        else:
            raise SystemExit(f"unknown scene {key!r} (expected cornell or bunny)")
    return out


def cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


class Reference:
    """Converged image plus the variance of its pixel means (from 16 passes), so
    that the reference's own noise can be taken out of the RMSE:
    E|x - ref|^2 = E|x - truth|^2 + var(ref)."""

    def __init__(self, mean: np.ndarray, var: np.ndarray, spp: int):
        self.mean, self.var, self.spp = mean, var, spp

    def rmse(self, img: np.ndarray) -> float:
        mse = float(np.mean((img[..., :3].astype(np.float64) - self.mean) ** 2) - np.mean(self.var))
        return math.sqrt(max(mse, 0.0))


def reference(b: Bench, ref_spp: int) -> Reference:
    path = OUT / f"{b.key}_{b.w}_ref_{ref_spp}spp.npz"
    if path.exists():
        z = np.load(path)
        return Reference(z["mean"], z["var"], ref_spp)
    mi.set_variant("scalar_rgb")
    print(f"rendering the {b.key} reference ({ref_spp} spp, scalar_rgb; cached in {path.relative_to(ms.REPO)}) ...", flush=True)
    t = time.time()
    scene = mi.load_dict(b.mitsuba_dict(ref_spp))
    passes = 16
    imgs = [np.array(mi.render(scene, spp=ref_spp // passes, seed=12345 + k), dtype=np.float64)[..., :3] for k in range(passes)]
    stack = np.stack(imgs)
    mean, var = stack.mean(0), stack.var(0, ddof=1) / passes
    np.savez(path, mean=mean, var=var)
    mi.Bitmap(mean.astype(np.float32)).write(str(path.with_suffix(".exr")))
    print(f"  done in {time.time() - t:.0f} s", flush=True)
    return Reference(mean, var, ref_spp)


class MitsubaRenderer:
    """One Mitsuba variant and sampler on one scene: loaded (and, for LLVM, its
    kernels JIT-compiled by a first render) once, then timed round by round."""

    def __init__(self, b: Bench, variant: str, sampler: str):
        self.b, self.variant, self.sampler = b, variant, sampler
        self.jit = variant.startswith(("llvm", "cuda"))
        mi.set_variant(variant)
        t = time.perf_counter()
        self.scene = mi.load_dict(b.mitsuba_dict(b.spp, sampler))
        self.load_s = time.perf_counter() - t
        self.warm_s = self.render(0)[0] if self.jit else None
        self.times: list[float] = []
        self.errs: list[float] = []

    def render(self, seed: int) -> tuple[float, np.ndarray]:
        mi.set_variant(self.variant)
        t0 = time.perf_counter()
        img = mi.render(self.scene, spp=self.b.spp, seed=seed)
        if self.jit:
            dr.eval(img)
            dr.sync_thread()
        arr = np.array(img)
        return time.perf_counter() - t0, arr

    def run(self, i: int, ref: Reference) -> None:
        s, img = self.render(100 + i)
        self.times.append(s)
        self.errs.append(ref.rmse(img))

    def row(self) -> dict:
        return {
            "name": f"Mitsuba 3 {self.variant}, {self.sampler}",
            "variant": self.variant,
            "sampler": self.sampler,
            "spp": self.b.spp,
            "render_s": statistics.median(self.times),
            "times_s": self.times,
            "load_s": self.load_s,
            "warmup_s": self.warm_s,
            "rmse": statistics.median(self.errs),
            "rmses": self.errs,
        }


def gradtrace_binary(binary: str | None) -> str:
    """The binary to time: by default the `dist` profile's (fat LTO, one codegen
    unit; Cargo.toml), the build a user would time or ship."""
    if binary is None:
        subprocess.run(["cargo", "build", "--profile", "dist", "--quiet"], cwd=ms.REPO, check=True)
        binary = str(ms.REPO / "target" / "dist" / "gradtrace")
    return binary


def native_binary(binary: str) -> str:
    """`--native`'s binary: the `dist` profile compiled for this CPU, unless
    `binary` names one."""
    if binary != "build":
        return binary
    env = dict(os.environ, RUSTFLAGS="-C target-cpu=native")
    subprocess.run(["cargo", "build", "--profile", "dist", "--quiet", "--target-dir", "target/native"], cwd=ms.REPO, env=env, check=True)
    return str(ms.REPO / "target" / "native" / "dist" / "gradtrace")


#: The builds beside the default one: variant -> (row label, output tag).
EXTRA_BUILDS = {
    "gradtrace-native": ("gradtrace, native build (`RUSTFLAGS=\"-C target-cpu=native\"`, `--profile dist`)", "native"),
    "gradtrace-pgo": ("gradtrace, PGO build (`scripts/build_pgo.sh`)", "pgo"),
    "gradtrace-before": ("gradtrace, the build before the change (`--before`)", "before"),
}


class GradtraceRenderer:
    """The `gradtrace render` process, round by round: its render time (what
    `mi.render` covers) and, apart, the rest of the process. `variant` is
    `gradtrace` (the default build) or a key of EXTRA_BUILDS."""

    def __init__(self, b: Bench, binary: str, variant: str = "gradtrace"):
        self.b, self.binary, self.variant = b, binary, variant
        self.times: list[float] = []
        self.process_times: list[float] = []
        self.errs: list[float] = []

    def run(self, i: int, ref: Reference) -> None:
        b = self.b
        tag = f"_{EXTRA_BUILDS[self.variant][1]}" if self.variant in EXTRA_BUILDS else ""
        out = OUT / f"gradtrace{tag}_{b.key}_{i}.exr"
        t0 = time.perf_counter()
        subprocess.run(
            [self.binary, "render", str(b.path), "--out", str(out), "--spp", str(b.spp), "--seed", str(100 + i), "--no-aovs", "--quiet"],
            cwd=ms.REPO,
            check=True,
        )
        self.process_times.append(time.perf_counter() - t0)
        bmp = mi.Bitmap(str(out))
        self.times.append(float(bmp.metadata()["gradtrace.render_time_s"]))
        names = [bmp.struct_()[k].name for k in range(bmp.channel_count())]
        arr = np.array(bmp, dtype=np.float64)
        img = np.stack([arr[..., names.index(c)] for c in "RGB"], -1)
        self.errs.append(ref.rmse(img))

    def row(self) -> dict:
        return {
            "name": EXTRA_BUILDS[self.variant][0] if self.variant in EXTRA_BUILDS else "gradtrace (Owen-scrambled Sobol; `--profile dist`)",
            "variant": self.variant,
            "sampler": "sobol",
            "spp": self.b.spp,
            "render_s": statistics.median(self.times),
            "times_s": self.times,
            "process_s": self.process_times,
            "load_s": statistics.median(p - t for p, t in zip(self.process_times, self.times)),
            "warmup_s": None,
            "rmse": statistics.median(self.errs),
            "rmses": self.errs,
            "note": "render time from the EXR header; load_s: the rest of the process (load, BVH, EXR+PNG)",
        }


def efficiency(a: dict, b: dict) -> tuple[float | None, list[float | None], float | None]:
    """(t·RMSE²)_a / (t·RMSE²)_b from the medians; the same within each round
    (the rows of a round ran back to back: its spread shows how far the
    machine's noise moves the figure); and (t·MSE)_a / (t·MSE)_b with the
    median times and the rounds' mean MSE (`pooled_ratio`)."""
    cost = b["render_s"] * b["rmse"] ** 2
    ratio = a["render_s"] * a["rmse"] ** 2 / cost if cost > 0 else None
    rounds = [t0 * e0**2 / (t * e**2) if t * e > 0 else None for t0, e0, t, e in zip(a["times_s"], a["rmses"], b["times_s"], b["rmses"])]
    return ratio, rounds, pooled_ratio(a, b, range(len(a["rmses"])))


def pooled_ratio(a: dict, b: dict, rounds) -> float | None:
    """(t·MSE)_a / (t·MSE)_b over `rounds` (indices, repeats allowed): median
    times, and the mean of the rounds' squared errors: each round renders with
    its own seed, so that mean estimates the expected MSE that efficiency
    (1 / (t·MSE)) is defined with; the median of the RMSEs moves with one
    seed's luck (±4 % in RMSE per seed on cornell at 64 spp, ±8 % in a ratio)."""
    t = lambda r: statistics.median(r["times_s"][i] for i in rounds)  # noqa: E731
    m = lambda r: statistics.fmean(r["rmses"][i] ** 2 for i in rounds)  # noqa: E731
    cost = t(b) * m(b)
    return t(a) * m(a) / cost if cost > 0 else None


#: Bootstrap resamples for the mean-MSE ratio's interval; a fixed seed, so a
#: table's interval is reproducible from its rounds.
BOOTSTRAP = 4000


def pooled_interval(a: dict, b: dict) -> tuple[float, float] | None:
    """The 95 % bootstrap interval of the mean-MSE efficiency ratio: rounds
    resampled with replacement, each round's two renders kept together (they
    ran back to back, under the same load). One 64-spp cornell render's MSE
    moves by ±8 % with its seed, so ten rounds pin a ratio only to about
    ±9 %: a figure of 1.05× may be the same efficiency as 1.00×."""
    n = min(len(a["rmses"]), len(b["rmses"]))
    if n < 2:
        return None
    rng = np.random.default_rng(2026)
    vals = [pooled_ratio(a, b, rng.integers(0, n, n)) for _ in range(BOOTSTRAP)]
    vals = np.array([v for v in vals if v is not None])
    return (float(np.quantile(vals, 0.025)), float(np.quantile(vals, 0.975))) if len(vals) else None


def add_ratios(rows: list[dict]) -> None:
    """Speed at equal spp against scalar_rgb, and the efficiency ratio against
    gradtrace: (t·RMSE²)_gradtrace / (t·RMSE²)_this."""
    scalar = next((r for r in rows if r["variant"] == "scalar_rgb"), None)
    ours = next((r for r in rows if r["variant"] == "gradtrace"), None)
    for r in rows:
        r["speed_vs_scalar"] = scalar["render_s"] / r["render_s"] if scalar else None
        (r["efficiency_ratio"], r["efficiency_ratio_rounds"], r["efficiency_ratio_mean_mse"]) = (
            efficiency(ours, r) if ours else (None, [], None)
        )
        r["efficiency_ratio_mean_mse_95"] = pooled_interval(ours, r) if ours and r is not ours else None


def extra_notes(label: str, rows: list[dict]) -> list[str]:
    """Each further build's efficiency ratios against the Mitsuba rows (the
    table's ratio column is the default build's)."""
    notes = []
    for extra in (r for r in rows if r["variant"] in EXTRA_BUILDS):
        parts = []
        for r in rows:
            if r["variant"].startswith("gradtrace"):
                continue
            ratio, rounds, pooled = efficiency(extra, r)
            vals = ", ".join("—" if v is None else f"{v:.2f}" for v in rounds)
            parts.append(
                f"{r['variant']} {r['sampler']} {'—' if ratio is None else f'{ratio:.2f}'}× [{vals}], "
                f"mean MSE {'—' if pooled is None else f'{pooled:.2f}'}×{interval(pooled_interval(extra, r))}"
            )
        if not parts:
            continue
        build = EXTRA_BUILDS[extra["variant"]][1]
        notes.append(f"{label}, the {build} build's efficiency ratio ({build} / row): " + "; ".join(parts) + ".")
    return notes


def before_notes(label: str, rows: list[dict]) -> list[str]:
    """The default build's render time over `--before`'s: the median of the
    per-round ratios (the two ran back to back in each round, under the same
    load) and the ratio of the medians."""
    ours = next((r for r in rows if r["variant"] == "gradtrace"), None)
    before = next((r for r in rows if r["variant"] == "gradtrace-before"), None)
    if ours is None or before is None:
        return []
    per_round = [a / b for a, b in zip(ours["times_s"], before["times_s"]) if b > 0]
    vals = ", ".join(f"{v:.3f}" for v in per_round)
    return [
        f"{label}, render time of this build / the build before (`--before`): median per round "
        f"{statistics.median(per_round):.3f} [{vals}], ratio of medians {ours['render_s'] / before['render_s']:.3f}; "
        f"RMSE {ours['rmse']:.4f} / {before['rmse']:.4f}."
    ]


def interval(ci: tuple[float, float] | None) -> str:
    """A 95 % interval as the tables print it after a ratio."""
    return "" if ci is None else f" ({ci[0]:.2f}–{ci[1]:.2f})"


def markdown(scene_rows: list[tuple[Bench, list[dict]]], meta: dict) -> str:
    f = lambda x, d=2: "—" if x is None else f"{x:.{d}f}"  # noqa: E731

    def rounds(r: dict) -> str:
        vals = r.get("efficiency_ratio_rounds") or []
        return "—" if r["variant"] == "gradtrace" or not vals else "[" + ", ".join(f(v) for v in vals) + "]"

    lines = [
        f"Median of {meta['runs']} runs on {meta['cpus']} CPU threads ({meta['cpu']}); RMSE against Mitsuba "
        f"`scalar_rgb` at {meta['ref_spp']} spp (its own noise subtracted). Efficiency ratio = "
        "(t·RMSE²)_gradtrace / (t·RMSE²)_row: the ratio of the times both need for equal error; "
        "below 1.00× gradtrace is the more efficient. Its RMSE is the median of the rounds' (each round "
        "renders with its own seed, 100 + round); the *mean MSE* column takes the mean of the rounds' "
        "squared errors instead, the expected MSE that efficiency is defined with, which one seed's luck "
        "moves less; in brackets its 95 % bootstrap interval over the rounds (each round's renders kept "
        f"together). Measured {meta['date']}, load average "
        f"{meta['load_avg']:.1f} (shared, loaded machine: compare within a table).",
    ]
    for b, rows in scene_rows:
        lines += [
            "",
            f"**{b.label}**, {b.w}x{b.h}, {b.spp} spp, max depth {b.depth}, box filter.",
            "",
            "| renderer, sampler | time (s) | speed vs scalar_rgb | RMSE | efficiency ratio (ours / row) | per round | mean MSE (95 %) | scene load (s) | JIT warm-up (s) |",
            "|---|---:|---:|---:|---:|---|---:|---:|---:|",
        ]
        for r in rows:
            lines.append(
                f"| {r['name']} | {r['render_s']:.2f} | {f(r['speed_vs_scalar'])}× | {r['rmse']:.4f} | "
                f"{f(r['efficiency_ratio'])}× | {rounds(r)} | {f(r['efficiency_ratio_mean_mse'])}×{interval(r.get('efficiency_ratio_mean_mse_95'))} | "
                f"{f(r['load_s'])} | {f(r['warmup_s'])} |"
            )
        for note in extra_notes(b.label, rows) + before_notes(b.label, rows):
            lines += ["", note]
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
    ap.add_argument("--gradtrace", help="gradtrace binary (default: cargo build --profile dist, target/dist/gradtrace)")
    ap.add_argument("--native", nargs="?", const="build", metavar="BINARY", help="also time a dist build for this CPU (default: built here into target/native)")
    ap.add_argument("--pgo", nargs="?", const="build", metavar="BINARY", help="also time the PGO build (default: scripts/build_pgo.sh builds it)")
    # Ten rounds: one 64-spp cornell render's RMSE moves by ±4 % from seed to
    # seed, ±8 % in a round's efficiency ratio before any timing noise; with
    # five, cornell read 1.08× from the median RMSE and 1.02× from the mean MSE
    # in one run (2026-12-05 16:26), and 1.08× from both with ten. Ten rounds
    # still leave cornell's ratio a 95 % interval of about ±9 % (printed).
    ap.add_argument("--runs", type=int, default=10, help="rounds (each renders every row once with seed 100 + round)")
    ap.add_argument("--ref-spp", type=int, default=1024, help="reference spp, a multiple of 16 (its noise is subtracted from the RMSE, so 1024 suffices)")
    ap.add_argument("--scenes", default="cornell,bunny", help="comma-separated: cornell, bunny")
    ap.add_argument("--before", metavar="BINARY", help="also time this build (e.g. main before a change) in the same rounds, and print this build's time over its")
    ap.add_argument("--no-gradtrace", action="store_true", help="time the Mitsuba variants only")
    ap.add_argument("--no-mitsuba", action="store_true", help="time gradtrace's builds only (the Mitsuba reference is still rendered or read from its cache)")
    ap.add_argument("--no-llvm", action="store_true", help="skip llvm_ad_rgb")
    args = ap.parse_args()
    if not args.no_llvm and not args.no_mitsuba and LIBLLVM is None:
        # Checked first: without the LLVM rows the run (~11 minutes on a fresh
        # machine, the reference included) cannot write its table.
        print(
            "error: llvm_ad_rgb needs libLLVM and none was found: apt-get install -y libllvm19 "
            "(or set DRJIT_LIBLLVM_PATH), or pass --no-llvm to time the other rows without writing benches/README.md",
            file=sys.stderr,
        )
        return 2
    notes = [
        "Times are render times: gradtrace's `gradtrace.render_time_s` (its EXR header: light set-up, rendering, film), "
        "Mitsuba's `mi.render`; gradtrace's scene load is the rest of its `gradtrace render --no-aovs` process "
        "(load, BVH build, EXR+PNG), Mitsuba's is `mi.load_dict`, and its first (JIT-compiling) LLVM render is listed apart. "
        "The renderers take turns: each round runs every row once."
    ]
    if not args.no_gradtrace and args.gradtrace is None and shutil.which("cargo") is None:
        ap.error("cargo not found; pass --gradtrace BINARY or --no-gradtrace")
    binary = None if args.no_gradtrace else gradtrace_binary(args.gradtrace)
    pgo_binary = None
    if args.pgo == "build":
        built = subprocess.run(["bash", "scripts/build_pgo.sh"], cwd=ms.REPO, check=True, stdout=subprocess.PIPE, text=True)
        pgo_binary = str(ms.REPO / built.stdout.strip().splitlines()[-1])
    elif args.pgo is not None:
        pgo_binary = args.pgo
    native = None if args.native is None else native_binary(args.native)
    scene_rows = []
    for b in benches(args.scenes.split(",")):
        ref = reference(b, args.ref_spp)
        renderers: list = [] if binary is None else [GradtraceRenderer(b, binary)]
        if native is not None:
            renderers.append(GradtraceRenderer(b, native, "gradtrace-native"))
        if pgo_binary is not None:
            renderers.append(GradtraceRenderer(b, pgo_binary, "gradtrace-pgo"))
        if args.before is not None:
            renderers.append(GradtraceRenderer(b, args.before, "gradtrace-before"))
        if not args.no_mitsuba:
            renderers.append(MitsubaRenderer(b, "scalar_rgb", "independent"))
        if not args.no_llvm and not args.no_mitsuba:
            renderers += [MitsubaRenderer(b, "llvm_ad_rgb", s) for s in LLVM_SAMPLERS]
        # Round by round, every renderer once per round: a change in the machine's
        # load then reaches all rows alike instead of whichever ran at the time.
        for i in range(args.runs):
            for r in renderers:
                r.run(i, ref)
            print(f"{b.key} round {i + 1}: " + ", ".join(f"{r.row()['name']} {r.times[-1]:.2f} s" for r in renderers), flush=True)
        rows = [r.row() for r in renderers]
        add_ratios(rows)
        scene_rows.append((b, rows))
    meta = {
        "scenes": {b.key: {"file": str(b.path.relative_to(ms.REPO)), "width": b.w, "height": b.h, "spp": b.spp, "max_depth": b.depth} for b, _ in scene_rows},
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
    results = {b.key: rows for b, rows in scene_rows}
    (OUT / "bench_mitsuba.json").write_text(json.dumps({"meta": meta, "results": results}, indent=2))
    table = markdown(scene_rows, meta)
    # benches/README.md holds issue 16's comparison: a table without gradtrace or
    # without the LLVM rows cannot stand for it, so it is printed, not written.
    missing = [what for what, gone in (("gradtrace", binary is None), ("llvm_ad_rgb", args.no_llvm or args.no_mitsuba)) if gone]
    if missing:
        print(f"benches/README.md left as it was: this table lacks {' and '.join(missing)}.", file=sys.stderr)
    else:
        write_readme(table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
