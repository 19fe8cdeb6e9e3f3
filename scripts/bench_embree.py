#!/usr/bin/env python3
"""Ray throughput of gradtrace's BVH against Embree and Mitsuba 3 on the same rays.

    python3 scripts/bench_embree.py [--rounds 5] [--runs 15] [--measurement-time 2] [--profile dist] [--no-cargo] [--no-mitsuba]

Runs `cargo bench --profile dist --bench accel` (closest_hit/*, shadow/*,
obvhs_baseline_*; `dist` is the build that ships and that bench_mitsuba times,
`--profile bench` the one of the runs before 2026-12-05 afternoon) with
GRADTRACE_ACCEL_RAYS set, so that the bench writes the Stanford bunny and its
exact ray sets (coherent camera grid, incoherent random rays; the bench's own
xorshift64* generators) to out/bench/accel_rays.bin, and the Cornell box of
bench_mitsuba with a path tracer's bounce rays (random points inside the box,
random directions) to out/bench/accel_rays_cornell.bin; then traces the same
rays with Embree 4 (PyPI `embreex`: one rtcIntersect1 / rtcOccluded1 per ray, in
a Cython loop, on the calling thread), with Embree called from C++
(`scripts/embree_rays.cpp`, compiled here with g++ against the Embree 3 that
Mitsuba's wheel ships and, with -DEMBREE4, against the Embree 4 library of the
`embreex` wheel, with Mitsuba's scene settings: build quality HIGH; one
`rtcIntersect1`/`rtcOccluded1` per ray, and `rtcIntersect16`/`rtcOccluded16` on
16 consecutive rays, the call Mitsuba's `llvm_ad_rgb` makes on AVX-512
machines; with Mitsuba's scene flags, and for Embree 3 again with
`RTC_SCENE_FLAG_ROBUST`, the watertight tests gradtrace keeps; skipped without
g++), and with Mitsuba
3's `llvm_ad_rgb` variant
(`ray_intersect_preliminary` / `ray_test` on the whole set as one wavefront, as
its path tracer traces them, one Dr.Jit thread, in a worker process of its own;
skipped without libLLVM 19) back to back, checks the hit counts, and prints the
ratios. Writes out/bench/bench_embree.json and the table between the markers in
benches/README.md.

gradtrace: criterion's median time per pass over the ray set. Embree and
Mitsuba: median of the passes over all rays in the same windows as criterion's,
1 s of warm-up then --measurement-time seconds (at least --runs passes); the
first pass (Embree: committing the scene, i.e. building its BVH; Mitsuba: also
JIT-compiling the kernel) is timed separately. One thread each. On a
shared machine the load drifts (seen here: the same binary 25 % slower from one
minute to the next), so after one full `cargo bench` (which builds, dumps the
rays and times obvhs' own traversal) each bench is timed in --rounds rounds,
gradtrace (the bench executable on that one id) and Embree on the same query
back to back, in alternating order; a row's ratio is the median of its
per-round ratios (each shown in brackets), its throughputs the medians over
rounds.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mitsuba_scene as ms  # noqa: E402

ms.ensure_venv()

import numpy as np  # noqa: E402

OUT = ms.REPO / "out" / "bench"
RAYS = OUT / "accel_rays.bin"
# (scene, ray dump): the bench writes the second next to the first.
DUMPS = [("Stanford bunny", RAYS), ("Cornell box", OUT / "accel_rays_cornell.bin")]
CRITERION = ms.REPO / "target" / "criterion"
README = ms.REPO / "benches" / "README.md"
BEGIN, END = "<!-- bench_embree:begin -->", "<!-- bench_embree:end -->"
# (criterion group, Embree query)
QUERIES = [("closest_hit", "INTERSECT"), ("shadow", "OCCLUDED")]
# The same queries as ray streams (batches of 256, `Accel::intersect_stream`):
# only on the Cornell box, the tree small enough for the lane shading to
# stream; compared with the same per-ray Embree and wavefront Mitsuba timings.
STREAM_QUERIES = [("closest_hit_stream", "INTERSECT"), ("shadow_stream", "OCCLUDED")]
# Embree called from C++ (`embree_rays.cpp`): (timer name, Embree version, rays
# per call, scene flags, column title). NONE is Mitsuba's setting, Embree's
# fastest; ROBUST has the watertight triangle and conservative box tests that
# gradtrace keeps. Embree 3 is Mitsuba's, Embree 4 `embreex`'s library.
EMBREE_CPP = [
    ("embree_c1", 3, 1, "NONE", "Embree 3 from C++, 1 ray"),
    ("embree_c16", 3, 16, "NONE", "Embree 3 from C++, 16-ray packets"),
    ("embree_c1_robust", 3, 1, "ROBUST", "the same, robust, 1 ray"),
    ("embree_c16_robust", 3, 16, "ROBUST", "the same, robust, 16-ray packets"),
    ("embree4_c1", 4, 1, "NONE", "Embree 4 from C++, 1 ray"),
    ("embree4_c16", 4, 16, "NONE", "Embree 4 from C++, 16-ray packets"),
]


def read_dump(path: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    data = path.read_bytes()
    if data[:8] != b"GTRAYS1\0":
        raise SystemExit(f"{path}: not a ray dump of benches/accel.rs")
    pos = 8

    def u32(n: int) -> tuple[int, ...]:
        nonlocal pos
        v = struct.unpack_from(f"<{n}I", data, pos)
        pos += 4 * n
        return v

    def array(dtype: str, n: int) -> np.ndarray:
        nonlocal pos
        a = np.frombuffer(data, dtype=dtype, count=3 * n, offset=pos).reshape(n, 3).copy()
        pos += 12 * n
        return a

    nv, nt = u32(2)
    verts, tris = array("<f4", nv), array("<u4", nt)
    sets = []
    for _ in range(u32(1)[0]):
        (name_len,) = u32(1)
        name = data[pos : pos + name_len].decode()
        pos += name_len
        n, closest, any_hit = u32(3)
        sets.append({"name": name, "origins": array("<f4", n), "dirs": array("<f4", n), "closest_hits": closest, "any_hits": any_hit})
    return verts, tris, sets


def run_ours(profile: str, measurement_time: float) -> None:
    """The full bench once: builds it, dumps the rays, times obvhs' traversal."""
    OUT.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, GRADTRACE_ACCEL_RAYS=str(RAYS))
    cmd = ["cargo", "bench", "--profile", profile, "--bench", "accel", "--", "--warm-up-time", "1", "--measurement-time", str(measurement_time), "closest_hit|shadow"]
    print("$ " + " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=ms.REPO, env=env, check=True)


def bench_executable(profile: str) -> str:
    cmd = ["cargo", "bench", "--profile", profile, "--bench", "accel", "--no-run", "--message-format=json"]
    out = subprocess.run(cmd, cwd=ms.REPO, capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("executable") and msg["target"]["name"] == "accel":
            return msg["executable"]
    raise SystemExit("cargo bench --bench accel --no-run: no executable")


def time_ours(exe: str, bench: str, measurement_time: float) -> float:
    """Criterion's median seconds per pass of one bench id."""
    cmd = [exe, "--bench", "--warm-up-time", "1", "--measurement-time", str(measurement_time), f"^{bench}$"]
    subprocess.run(cmd, cwd=ms.REPO, check=True, stdout=subprocess.DEVNULL)
    group, name = bench.split("/")
    return criterion_median_s(group, name)


def criterion_median_s(group: str, bench: str) -> float:
    est = json.loads((CRITERION / group / bench / "new" / "estimates.json").read_text())
    return est["median"]["point_estimate"] * 1e-9


def time_passes(run, runs: int, measurement_time: float) -> dict:
    """Median seconds per `run()` pass, over the same windows as criterion's:
    1 s of warm-up, then passes for `measurement_time` seconds (at least
    `runs`); the first pass is timed apart, and every pass must return what it
    returned."""
    t0 = time.perf_counter()
    first = run()
    first_s = time.perf_counter() - t0
    start = time.perf_counter()
    while time.perf_counter() - start < 1.0:
        run()
    times = []
    start = time.perf_counter()
    while len(times) < runs or time.perf_counter() - start < measurement_time:
        t0 = time.perf_counter()
        res = run()
        times.append(time.perf_counter() - t0)
        assert np.array_equal(first, res)
    return {"median_s": statistics.median(times), "first_s": first_s, "first": first}


def time_embree(scene, s: dict, query: str, runs: int, measurement_time: float) -> dict:
    """`time_passes` of Embree over the whole set (the first pass commits the
    scene, i.e. builds Embree's BVH)."""
    o, d = np.ascontiguousarray(s["origins"]), np.ascontiguousarray(s["dirs"])
    t = time_passes(lambda: scene.run(o, d, query=query), runs, measurement_time)
    hits = int(np.count_nonzero(t.pop("first") != -1))  # prim id, or 0 when occluded; -1: miss
    return t | {"hits": hits}


def build_embree_cpp() -> dict[int, Path]:
    """Compiles `embree_rays.cpp` against Mitsuba's Embree 3 (its wheel's
    headers and libembree3.so) and, with -DEMBREE4, against the Embree 4 of the
    `embreex` wheel (its libembree4; the declarations are the harness's own, the
    ray and hit types Mitsuba's Embree 3 headers'); the packages are located, not
    imported, so that their Embree stays out of this process. {version: binary}:
    empty without g++ or Mitsuba, without 4 where `embreex` has no library."""
    spec = importlib.util.find_spec("mitsuba")
    gxx = shutil.which("g++")
    if spec is None or not spec.submodule_search_locations or gxx is None:
        print("note: no g++ or no Mitsuba wheel: the Embree-from-C++ columns are skipped", file=sys.stderr)
        return {}
    pkg = Path(spec.submodule_search_locations[0])
    src = Path(__file__).with_name("embree_rays.cpp")
    libs = {3: (pkg, ["-lembree3"], [])}
    e4 = importlib.util.find_spec("embreex")
    e4_libs = Path(e4.submodule_search_locations[0]).with_name("embreex.libs") if e4 and e4.submodule_search_locations else None
    found = sorted(e4_libs.glob("libembree4*.so*")) if e4_libs and e4_libs.is_dir() else []
    if found:
        libs[4] = (e4_libs, [f"-l:{found[0].name}"], ["-DEMBREE4"])
    else:
        print("note: no libembree4 in the embreex wheel: the Embree 4 from C++ columns are skipped", file=sys.stderr)
    exes = {}
    for version, (libdir, link, defines) in libs.items():
        exe = OUT / f"embree{version}_rays"
        cmd = [gxx, "-O3", "-std=c++17", *defines, "-o", str(exe), str(src), f"-I{pkg / 'include'}", f"-L{libdir}", *link, f"-Wl,-rpath,{libdir}"]
        print("$ " + " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True)
        exes[version] = exe
    return exes


def last_json_line(cmd: list[str]) -> dict:
    """Runs a timing worker and reads the JSON object on its last stdout line."""
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def time_embree_cpp(exe: Path, dump: Path, set_name: str, query: str, width: int, flags: str, runs: int, measurement_time: float) -> dict:
    """`time_embree` for Embree called from C++ (`embree_rays.cpp`)."""
    cmd = [str(exe), str(dump), set_name, query, str(width), flags, str(runs), str(measurement_time)]
    return last_json_line(cmd)


def time_mitsuba(dump: Path, set_name: str, query: str, runs: int, measurement_time: float) -> dict:
    """`time_embree` for Mitsuba's `llvm_ad_rgb`, in a worker process (its own
    Embree must not meet embreex's in one process)."""
    cmd = [sys.executable, __file__, "--mitsuba-worker", str(dump), set_name, query, str(runs), str(measurement_time)]
    return last_json_line(cmd)


def mitsuba_worker(dump: str, set_name: str, query: str, runs: int, measurement_time: float) -> None:
    """Times one query of one ray set in Mitsuba and prints the result as JSON."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", ms.find_libllvm() or "")
    import drjit as dr
    import mitsuba as mi

    dr.set_thread_count(1)
    mi.set_variant("llvm_ad_rgb")
    verts, tris, sets = read_dump(Path(dump))
    s = next(s for s in sets if s["name"] == set_name)
    mesh = mi.Mesh("dump", vertex_count=len(verts), face_count=len(tris), has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(verts.astype(np.float32).ravel())
    params["faces"] = mi.UInt(tris.astype(np.uint32).ravel())
    params.update()
    scene = mi.load_dict({"type": "scene", "mesh": mesh})
    o, d = s["origins"].astype(np.float32), s["dirs"].astype(np.float32)
    ray = mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
    dr.eval(ray)

    def run() -> int:
        if query == "INTERSECT":
            hit = scene.ray_intersect_preliminary(ray).is_valid()
        else:
            hit = scene.ray_test(ray)
        n = dr.count(hit)
        dr.eval(n)
        dr.sync_thread()
        return int(n[0])

    t = time_passes(run, runs, measurement_time)
    hits = t.pop("first")
    print(json.dumps(t | {"hits": hits}))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=5, help="rounds of back-to-back timings per bench")
    ap.add_argument("--runs", type=int, default=15, help="at least this many Embree passes per bench and round")
    ap.add_argument("--measurement-time", type=float, default=2.0, help="criterion seconds per bench")
    ap.add_argument("--profile", default="dist", help="cargo profile of gradtrace's bench build (dist: the shipped build; bench: release settings)")
    ap.add_argument("--no-cargo", action="store_true", help="skip the full cargo bench run, reusing its ray dump and obvhs figures")
    ap.add_argument("--no-mitsuba", action="store_true", help="time Embree through embreex only (no Mitsuba, no Embree from C++)")
    ap.add_argument("--mitsuba-worker", nargs=5, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.mitsuba_worker:
        dump, set_name, query, runs, measurement_time = args.mitsuba_worker
        mitsuba_worker(dump, set_name, query, int(runs), float(measurement_time))
        return 0
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    # Mitsuba's rows need libLLVM (looked up once, not per round).
    args.mitsuba = not args.no_mitsuba and ms.find_libllvm() is not None
    args.embree_cpp = {} if args.no_mitsuba else build_embree_cpp()
    if not args.no_cargo:
        run_ours(args.profile, args.measurement_time)
    exe = bench_executable(args.profile)
    rows, triangles = [], {}
    for scene_name, dump in DUMPS:
        verts, tris, sets = read_dump(dump)
        triangles[scene_name] = len(tris)
        scene = rtcs.EmbreeScene()
        TriangleMesh(scene, verts.astype(np.float32), tris.astype(np.int32))
        streamed = STREAM_QUERIES if scene_name == "Cornell box" else []
        for group, query in QUERIES + streamed:
            for s in sets:
                rows.append(bench_row(args, exe, scene, dump, s, group, query))
    meta = {
        "triangles": triangles,
        "rounds": args.rounds,
        "runs": args.runs,
        "measurement_time": args.measurement_time,
        "profile": args.profile,
        "cpu": ms_cpu(),
        "load_avg": os.getloadavg()[0],
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }
    (OUT / "bench_embree.json").write_text(json.dumps({"meta": meta, "results": rows}, indent=2))
    table = markdown(rows, meta)
    write_readme(table)
    print(table)
    mismatch = [
        r["bench"]
        for r in rows
        if any(r[k] != r["hits_gradtrace"] for k in r if k.startswith("hits_") and k != "hits_gradtrace")
    ]
    if mismatch:
        print(f"note: hit counts differ for {mismatch} (see the table)", file=sys.stderr)
    return 0


def bench_row(args, exe: str, scene, dump: Path, s: dict, group: str, query: str) -> dict:
    """One bench id timed in --rounds rounds: gradtrace, Embree and Mitsuba back
    to back, the order turning round by round."""
    bench, n = f"{group}/{s['name']}", len(s["origins"])
    timers = {
        "ours": lambda: time_ours(exe, bench, args.measurement_time),
        "embree": lambda: time_embree(scene, s, query, args.runs, args.measurement_time),
    }
    cpp = [(name, version, width, flags) for name, version, width, flags, _ in EMBREE_CPP if version in args.embree_cpp]
    for name, version, width, flags in cpp:
        exe_cpp = args.embree_cpp[version]
        timers[name] = lambda e=exe_cpp, w=width, f=flags: time_embree_cpp(e, dump, s["name"], query, w, f, args.runs, args.measurement_time)
    if args.mitsuba:
        timers["mitsuba"] = lambda: time_mitsuba(dump, s["name"], query, args.runs, args.measurement_time)
    rounds = []
    for k in range(args.rounds):
        order = list(timers)
        order = order[k % len(order) :] + order[: k % len(order)]
        got = {name: timers[name]() for name in order}
        rounds.append(got)
        others = ", ".join(f"{name} {got[name]['median_s'] / got['ours']:.2f}x" for name in order if name != "ours")
        print(f"{bench} round {k + 1}: {others}", flush=True)
    ratios = [r["embree"]["median_s"] / r["ours"] for r in rounds]
    row = {
        "bench": bench,
        "rays": n,
        "gradtrace_mrays_s": statistics.median(n / r["ours"] * 1e-6 for r in rounds),
        "embree_mrays_s": statistics.median(n / r["embree"]["median_s"] * 1e-6 for r in rounds),
        "ratio": statistics.median(ratios),
        "ratios_per_round": ratios,
        "hits_gradtrace": s["closest_hits"] if query == "INTERSECT" else s["any_hits"],
        "hits_embree": rounds[0]["embree"]["hits"],
        "embree_first_pass_s": rounds[0]["embree"]["first_s"],
    }
    for name, _, _, _ in cpp:
        row |= peer_fields(name, rounds, n)
    if args.mitsuba:
        row |= peer_fields("mitsuba", rounds, n) | {"mitsuba_first_pass_s": rounds[0]["mitsuba"]["first_s"]}
    if group == "closest_hit":
        try:
            row["obvhs_baseline_mrays_s"] = n / criterion_median_s("obvhs_baseline_closest_hit", s["name"]) * 1e-6
        except FileNotFoundError:
            pass
    return row


def peer_fields(name: str, rounds: list[dict], n: int) -> dict:
    """A peer's figures in a row under the `{name}_*` keys that `markdown()`
    reads: its median throughput over the rounds, the median and per-round
    ratios of its time over ours, its hit count."""
    ratios = [r[name]["median_s"] / r["ours"] for r in rounds]
    return {
        f"{name}_mrays_s": statistics.median(n / r[name]["median_s"] * 1e-6 for r in rounds),
        f"{name}_ratio": statistics.median(ratios),
        f"{name}_ratios_per_round": ratios,
        f"hits_{name}": rounds[0][name]["hits"],
    }


def ms_cpu() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def markdown(rows: list[dict], meta: dict) -> str:
    scenes = " and ".join(f"the {name} ({n:,} triangles)" for name, n in meta["triangles"].items())
    cpp = [(name, title) for name, _, _, _, title in EMBREE_CPP if any(f"{name}_ratio" in r for r in rows)]
    lines = [
        f"{scenes[0].upper()}{scenes[1:]}, the `accel` bench's rays (65,536 per set), one thread; "
        f"gradtrace: criterion median, the `{meta.get('profile', 'bench')}` profile; "
        + ("Embree from C++ (`scripts/embree_rays.cpp` against Mitsuba's libembree3 and `embreex`'s libembree4, build quality HIGH as Mitsuba sets it: "
           "one `rtcIntersect1`/`rtcOccluded1` per ray, or `rtcIntersect16`/`rtcOccluded16` on 16 consecutive rays; "
           "Mitsuba's scene flags, and for Embree 3 also `RTC_SCENE_FLAG_ROBUST`, the watertight tests gradtrace keeps), " if cpp else "")
        + "Embree 4 through `embreex` (`rtcIntersect1`/`rtcOccluded1` per ray, in its Cython loop) and Mitsuba 3 "
        f"(`llvm_ad_rgb`, `ray_intersect_preliminary`/`ray_test` on the set as one wavefront, one Dr.Jit thread): median of the passes in "
        f"{meta['measurement_time']:g} s after 1 s of warm-up, as criterion's; "
        f"{meta['rounds']} rounds, each timing them back to back on one bench, the order turning; ratio = gradtrace's throughput over the peer's, "
        "median of the per-round ratios (in brackets); throughputs = medians over rounds. "
        f"{meta['cpu']}, measured {meta['date']}, load average {meta['load_avg']:.1f} (shared machine, loaded: compare within a row).",
        "",
    ]
    # (row key, column title); the C++ columns first: Embree's best configurations.
    peers = cpp + [("embree", "Embree 4 via `embreex`"), ("mitsuba", "Mitsuba LLVM")]
    head = "| bench | gradtrace (Mrays/s) | " + " | ".join(f"{t} (Mrays/s) | gradtrace / it" for _, t in peers)
    lines += [
        head + " | hits (gradtrace / " + " / ".join(t for _, t in peers) + ") | obvhs' own traversal (Mrays/s) |",
        "|---|---:|" + "---:|---:|" * len(peers) + "---:|---:|",
    ]

    def cells(r: dict, key: str) -> tuple[str, str]:
        if key == "embree":
            mrays, ratio, rounds, hits = r["embree_mrays_s"], r["ratio"], r["ratios_per_round"], r["hits_embree"]
        elif f"{key}_ratio" in r:
            mrays, ratio, rounds, hits = r[f"{key}_mrays_s"], r[f"{key}_ratio"], r[f"{key}_ratios_per_round"], r[f"hits_{key}"]
        else:
            return "— | —", "—"
        per_round = ", ".join(f"{x:.2f}" for x in rounds)
        return f"{mrays:.2f} | {ratio:.2f}× [{per_round}]", f"{hits:,}"

    for r in rows:
        base = f"{r['obvhs_baseline_mrays_s']:.2f}" if "obvhs_baseline_mrays_s" in r else "—"
        got = [cells(r, key) for key, _ in peers]
        lines.append(
            f"| `{r['bench']}` | {r['gradtrace_mrays_s']:.2f} | " + " | ".join(c for c, _ in got)
            + f" | {r['hits_gradtrace']:,} / " + " / ".join(h for _, h in got) + f" | {base} |"
        )
    return "\n".join(lines)


def write_readme(table: str) -> None:
    text = README.read_text()
    block = f"{BEGIN}\n{table}\n{END}"
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        text = head + block + rest.split(END, 1)[1]
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    README.write_text(text)


if __name__ == "__main__":
    sys.exit(main())
