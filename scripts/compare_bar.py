#!/usr/bin/env python3
"""The comparison bar of issue 13: `gradtrace compare` on every bundled scene at one
budget, with seeds, against the baselines at equal time; then one Markdown table of
the gradient strategy's mean RMSE against each baseline's.

    python3 scripts/compare_bar.py [--scale 0.5] [--seeds 4] [--equal wall|cpu] [--out out/bar] [--table-only]

Build first (`cargo build --release`, with `--features oidn` after
`eval "$(scripts/setup_oidn.sh)"` for the denoised baselines). `--scale` shrinks
every scene's own resolution (the bar's figures in benches/README.md say which);
`--equal cpu` matches the baselines on process CPU seconds (a shared machine).
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
BASELINES = ["uniform-all-pixels", "cycles-adaptive", "oidn-uniform", "cycles-adaptive+oidn", "gradient+oidn",
             "gradient-domain"]


def resolution(scene):
    m = re.search(r"^resolution\s*=\s*\[\s*(\d+)\s*,\s*(\d+)\s*\]", scene.read_text(), re.M)
    return (int(m.group(1)), int(m.group(2))) if m else None


def run(scene, args, out):
    w, h = resolution(scene)
    w, h = max(1, round(w * args.scale)), max(1, round(h * args.scale))
    cmd = [str(ROOT / "target/release/gradtrace"), "compare", str(scene),
           "--spp", str(args.spp), "--reference-spp", str(args.reference_spp),
           "--budgets", str(args.budget), "--strategies", "gradient",
           "--seeds", str(args.seeds), "--width", str(w), "--height", str(h),
           "--equal", args.equal, "--out", str(out)]
    t = time.time()
    log = subprocess.run(cmd, capture_output=True, text=True)
    (out.parent / f"{scene.stem}.log").write_text(log.stdout + log.stderr)
    if log.returncode != 0:
        sys.exit(f"{scene}: exit {log.returncode}\n{log.stderr}")
    print(f"{scene.stem} {w}x{h}: {time.time() - t:.0f} s", file=sys.stderr)


def fmt(r):
    ci = f" ± {r['rmse_ci95']:.1e}" if r.get("rmse_ci95") is not None else ""
    return f"{r['rmse']:.3e}{ci}"


def table(out_root, scenes):
    head = "| scene | size | gradient | " + " | ".join(BASELINES) + \
        " | lowest at equal time | gradient / best baseline | report | outside rendering |"
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for scene in scenes:
        d = out_root / scene.stem
        if not (d / "report.json").exists():
            continue
        j = json.loads((d / "report.json").read_text())
        runs = {r["name"]: r for r in j["runs"] if r["kind"] in ("adaptive", "baseline")}
        g = runs["gradient"]
        cells = [fmt(runs[b]) if b in runs else "—" for b in BASELINES]
        contenders = [runs[n] for n in ["gradient"] + BASELINES if n in runs]
        best = min(contenders, key=lambda r: r["rmse"])
        other = min((r for r in contenders if r["name"] not in ("gradient", "gradient+oidn")), key=lambda r: r["rmse"])
        size = sum(f.stat().st_size for f in d.rglob("*")
                   if f.is_file() and not f.name.startswith("reference-"))
        log = (out_root / f"{scene.stem}.log").read_text() if (out_root / f"{scene.stem}.log").exists() else ""
        m = re.findall(r"outside rendering .*?: ([\d.]+%)", log)
        cost = f"{g['cpu_s']:.2f} CPU s" if j.get("equal_cost") == "cpu" else f"{g['wall_s']:.2f} s"
        lines.append(f"| {scene.stem} | {j['width']}×{j['height']} | {fmt(g)} ({cost}) | "
                     + " | ".join(cells)
                     + f" | {best['name']} | {g['rmse'] / other['rmse']:.2f}× | {size / 1024:.0f} KB | {m[-1] if m else '?'} |")
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--reference-spp", type=int, default=1024)
    p.add_argument("--budget", type=float, default=0.17)
    p.add_argument("--equal", choices=["wall", "cpu"], default="wall")
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "out/bar")
    p.add_argument("--table-only", action="store_true")
    p.add_argument("scenes", nargs="*", help="scene files (default: every scenes/*.toml)")
    args = p.parse_args()
    scenes = [pathlib.Path(s) for s in args.scenes] or sorted((ROOT / "scenes").glob("*.toml"))
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.table_only:
        for scene in scenes:
            run(scene, args, args.out / scene.stem)
    print(table(args.out, scenes))


if __name__ == "__main__":
    main()
