#!/usr/bin/env python3
"""Cross-validates gradtrace against Mitsuba 3 (`scalar_rgb`) on shared scenes.

    python3 scripts/validate_mitsuba.py [--gradtrace BINARY] [--scenes NAME ...] [--spp N]
                                        [--mitsuba-only]

For every validation scene (scenes/validation/*.toml, written by this script when
missing) it renders gradtrace's image (EXR: `R,G,B` plus `variance.R/G/B`, the
variance of each pixel mean) and Mitsuba's image of the converted scene
(scripts/mitsuba_scene.py) at the same resolution and spp, then checks

  1. the image means: |mean_ours - mean_mts| / mean_mts < 1 % per channel;
  2. a per-pixel z-test as in Mitsuba's src/render/tests/test_renders.py:
     z = (a - b) / sqrt(var_a + var_b), two-sided p-value from Student's t with
     Welch-Satterthwaite degrees of freedom (both variances are estimates: ours
     from spp samples, Mitsuba's from K passes; the normal approximation gave
     false alarms in Mitsuba-vs-Mitsuba runs), Sidak correction over all N
     pixel-channels, p_corr = 1 - (1 - min p)^N; fail if p_corr < 0.01.
Mitsuba's per-pixel variance of the mean comes from rendering it in K = 32
independent passes (different seeds): var = sample variance of the passes / K.
Images land in out/validation/ (NAME.exr ours, NAME_mitsuba.exr, NAME_z.exr = |z|
when a scene fails).

Before any of that the checker checks itself: the converter's camera and
environment conventions against our formulas, Mitsuba-vs-Mitsuba (two disjoint
seed sets of the same scene: must pass) and Mitsuba-vs-(Mitsuba x 1.03) (must
fail), and the converted Cornell box against `mi.cornell_box()` itself.

Exits 0 when everything passes, 1 otherwise. `--mitsuba-only` runs just the
Mitsuba side (self-tests and controls) for when gradtrace is not buildable.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mitsuba_scene as ms  # noqa: E402

ms.ensure_venv()

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("scalar_rgb")

VALIDATION_DIR = ms.REPO / "scenes" / "validation"
OUT_DIR = ms.REPO / "out" / "validation"
DEFAULT_SCENES = ["cornell", "spheres", "env_constant", "env_image"]
ALPHA = 0.01
REL_TOL = 0.01
PASSES = 32  # K independent Mitsuba passes for the variance estimate


# --------------------------------------------------------------------------- scenes

CUBE_VERTS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
# Counter-clockwise seen from outside (outward geometric normals).
CUBE_FACES = [
    (0, 1, 3), (0, 3, 2),  # -x
    (4, 6, 7), (4, 7, 5),  # +x
    (0, 4, 5), (0, 5, 1),  # -y
    (2, 3, 7), (2, 7, 6),  # +y
    (0, 2, 6), (0, 6, 4),  # -z
    (1, 5, 7), (1, 7, 3),  # +z
]


def cube_obj(matrix=None) -> str:
    """A cube [-1,1]^3 (flat, no normals); `matrix` (4x4) bakes a transform in."""
    lines = ["# cube, counter-clockwise faces seen from outside; written by validate_mitsuba.py"]
    for v in CUBE_VERTS:
        p = v if matrix is None else [sum(matrix[i][j] * v[j] for j in range(3)) + matrix[i][3] for i in range(3)]
        lines.append("v " + " ".join(f"{c:.9g}" for c in p))
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in CUBE_FACES]
    return "\n".join(lines) + "\n"


def _fmt(v) -> str:
    return "[" + ", ".join(f"{x:.9g}" for x in v) + "]"


def cornell_files() -> dict[str, str]:
    """mi.cornell_box() in our format: the same walls, light, boxes, colours and
    camera; only the pixel filter differs (box, as our EXR holds pixel means)."""
    d = mi.cornell_box()
    files = {}
    quads = []
    for key in ("floor", "ceiling", "back", "green-wall", "red-wall", "light"):
        m = np.array(d[key]["to_world"].matrix, dtype=np.float64)
        c, hu, hv = m[:3, 3], m[:3, 0], m[:3, 1]
        corner, eu, ev = c - hu - hv, 2 * hu, 2 * hv
        mat = d[key]["bsdf"]["id"]
        q = f'[[shapes]]\nname = "{key}"\ntype = "quad"\ncorner = {_fmt(corner)}\nedge_u = {_fmt(eu)}\nedge_v = {_fmt(ev)}\nmaterial = "{mat}"\n'
        if "emitter" in d[key]:
            q += f'emission = {_fmt(d[key]["emitter"]["radiance"]["value"])}\n'
        quads.append(q)
    for key in ("large-box", "small-box"):
        m = np.array(d[key]["to_world"].matrix, dtype=np.float64).tolist()
        files[f"models/cornell_{key.replace('-', '_')}.obj"] = cube_obj(m)
        quads.append(
            f'[[shapes]]\nname = "{key}"\ntype = "mesh"\nfile = "models/cornell_{key.replace("-", "_")}.obj"\nmaterial = "white"\n'
        )
    mats = "".join(
        f'[materials.{n}]\ntype = "lambert"\nalbedo = {_fmt(d[n]["reflectance"]["value"])}\n\n' for n in ("white", "red", "green")
    )
    files["cornell.toml"] = (
        "# Mitsuba 3's mi.cornell_box() in gradtrace's format (written by scripts/validate_mitsuba.py).\n"
        "[camera]\nfrom = [0, 0, 3.9]\nto = [0, 0, 0]\nup = [0, 1, 0]\nfov = 39.3077\nresolution = [128, 128]\n\n"
        '[render]\nspp = 256\nmax_depth = 8\nrr_depth = 5\nseed = 0\nintegrator = "path"\n\n'
        + mats
        + "\n".join(quads)
    )
    return files


SPHERES_TOML = """\
# Diffuse + mirror spheres on a floor, a rectangular and a spherical light
# (written by scripts/validate_mitsuba.py). Asymmetric on purpose: the sphere
# light and the mirror sphere are on the right, the red sphere on the left.
[camera]
from = [0, 1.3, 4.5]
to = [0, 0.6, 0]
up = [0, 1, 0]
fov = 40
resolution = [128, 96]

[render]
spp = 256
max_depth = 6
rr_depth = 5
seed = 0
integrator = "path"

[materials.grey]
type = "lambert"
albedo = [0.7, 0.7, 0.7]

[materials.red]
type = "lambert"
albedo = [0.75, 0.2, 0.15]

[materials.chrome]
type = "mirror"
reflectance = [0.9, 0.85, 0.8]

[[shapes]]
name = "floor"
type = "quad"
corner = [-3, 0, 3]
edge_u = [6, 0, 0]
edge_v = [0, 0, -6]
material = "grey"

[[shapes]]
name = "back wall"
type = "quad"
corner = [-3, 0, -2]
edge_u = [6, 0, 0]
edge_v = [0, 3, 0]
material = "grey"

[[shapes]]
name = "red ball"
type = "sphere"
center = [-0.9, 0.5, 0]
radius = 0.5
material = "red"

[[shapes]]
name = "mirror ball"
type = "sphere"
center = [0.7, 0.6, 0.3]
radius = 0.6
material = "chrome"

[[lights]]
type = "rect"
corner = [-0.75, 2.8, -0.75]
edge_u = [1.5, 0, 0]
edge_v = [0, 0, 1.5]
radiance = [6, 6, 6]

[[lights]]
type = "sphere"
center = [1.9, 0.35, 1.1]
radius = 0.25
radiance = [12, 7, 3]
"""

_ENV_SCENE = """\
# Diffuse objects (sphere, rotated OBJ cube, floor) and a mirror ball lit only by
# {what} (written by scripts/validate_mitsuba.py).
[camera]
from = [0.4, 1.1, 4]
to = [0, 0.5, 0]
up = [0, 1, 0]
fov = 38
resolution = [128, 96]

[render]
spp = 256
max_depth = 5
rr_depth = 5
seed = 0
integrator = "path"

[materials.floor]
type = "lambert"
albedo = [0.5, 0.45, 0.4]

[materials.white]
type = "lambert"
albedo = [0.8, 0.8, 0.8]

[materials.chrome]
type = "mirror"
reflectance = [0.95, 0.95, 0.95]

[[shapes]]
name = "floor"
type = "quad"
corner = [-2.5, 0, 2.5]
edge_u = [5, 0, 0]
edge_v = [0, 0, -5]
material = "floor"

[[shapes]]
name = "ball"
type = "sphere"
center = [-0.7, 0.5, 0]
radius = 0.5
material = "white"

[[shapes]]
name = "cube"
type = "mesh"
file = "models/cube.obj"
transform = {{ scale = 0.35, rotate = [0, 1, 0, 30], translate = [0.6, 0.35, -0.2] }}
material = "white"

[[shapes]]
name = "mirror ball"
type = "sphere"
center = [0.2, 0.25, 0.9]
radius = 0.25
material = "chrome"

{env}
"""


def env_image() -> np.ndarray:
    """A smooth but asymmetric lat-long sky (64x32): a warm sun-like lobe at
    u = 0.3, v = 0.3, a blue gradient towards the zenith, a darker ground."""
    h, w = 32, 64
    v = (np.arange(h) + 0.5)[:, None] / h
    u = (np.arange(w) + 0.5)[None, :] / w
    phi, theta = u * 2 * np.pi, v * np.pi
    d = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta) + 0 * phi, -np.cos(phi) * np.sin(theta)], -1)
    sun = np.array(ms.latlong_to_direction(0.3, 0.3))
    lobe = np.exp(6.0 * (d @ sun - 1.0))[..., None]
    sky = np.where(d[..., 1:2] > 0, 0.3 + 0.7 * d[..., 1:2], 0.15)
    img = sky * np.array([0.35, 0.5, 0.9]) + lobe * np.array([6.0, 4.5, 2.5])
    img = img + 0.1 * (d[..., 0:1] > 0) * np.array([0.2, 0.05, 0.0])  # +x half slightly warmer
    return img.astype(np.float32)


def validation_files() -> dict[str, str | np.ndarray]:
    files: dict[str, str | np.ndarray] = dict(cornell_files())
    # The benchmark scene of scripts/bench_mitsuba.py: 256x256, 64 spp, max depth 8.
    files["cornell_256.toml"] = (
        files["cornell.toml"]
        .replace("resolution = [128, 128]", "resolution = [256, 256]")
        .replace("spp = 256", "spp = 64")
        .replace("(written by", "at 256x256, 64 spp: the benchmark scene (written by")
    )
    files["spheres.toml"] = SPHERES_TOML
    files["models/cube.obj"] = cube_obj()
    files["env_constant.toml"] = _ENV_SCENE.format(
        what="a constant environment", env='[environment]\ntype = "constant"\nradiance = [0.8, 0.9, 1.0]'
    )
    files["env_image.toml"] = _ENV_SCENE.format(
        what="a lat-long image environment (sky.hdr)",
        env='[environment]\ntype = "image"\nfile = "sky.hdr"\nscale = 1.0',
    )
    files["sky.hdr"] = env_image()
    return files


def write_validation_scenes(directory: Path) -> None:
    """Writes the scenes when missing (existing files are left alone, so edits to
    the committed scenes are not overwritten)."""
    for rel, content in validation_files().items():
        p = directory / rel
        if p.exists():
            continue
        p.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, np.ndarray):
            mi.Bitmap(content).write(str(p))
        else:
            p.write_text(content)
        print(f"wrote {p.relative_to(ms.REPO)}")


# --------------------------------------------------------------------------- rendering


def render_mitsuba(scene_dict: dict, spp: int, passes: int = PASSES, seed0: int = 0):
    """(mean, variance of the mean) per pixel and channel, float64, from `passes`
    independent renders of ceil(spp/passes) samples each (so Mitsuba takes at
    least `spp` samples; the z-test does not need equal counts)."""
    passes = max(2, min(passes, spp))
    per = -(-spp // passes)
    scene = mi.load_dict(scene_dict)
    acc = acc2 = None
    for k in range(passes):
        img = np.array(mi.render(scene, spp=per, seed=seed0 + k), dtype=np.float64)[..., :3]
        acc = img if acc is None else acc + img
        acc2 = img * img if acc2 is None else acc2 + img * img
    mean = acc / passes
    var_pass = np.maximum(acc2 / passes - mean * mean, 0.0) * passes / (passes - 1)
    return mean, var_pass / passes, passes - 1


def read_exr(path: Path) -> dict[str, np.ndarray]:
    """All channels of an EXR by name, via mi.Bitmap."""
    bmp = mi.Bitmap(str(path))
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    arr = np.array(bmp, dtype=np.float64)
    if arr.ndim == 2:
        arr = arr[..., None]
    return {n: arr[..., i] for i, n in enumerate(names)}


def load_ours(path: Path):
    ch = read_exr(path)
    missing = [n for n in ("R", "G", "B", "variance.R", "variance.G", "variance.B") if n not in ch]
    if missing:
        raise RuntimeError(f"{path}: missing channels {missing} (has {sorted(ch)})")
    mean = np.stack([ch[c] for c in "RGB"], -1)
    var = np.stack([ch["variance." + c] for c in "RGB"], -1)
    return mean, var


# --------------------------------------------------------------------------- the checker


def _betacf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        for aa in (m * (b - m) * x / ((qam + m2) * (a + m2)), -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + aa / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-15:
            break
    return h


def betainc(a: float, b: float, x: float) -> float:
    """Regularised incomplete beta I_x(a, b)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    lbt = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(lbt) * _betacf(a, b, x) / a
    return 1.0 - math.exp(lbt) * _betacf(b, a, 1.0 - x) / b


def t_pvalue(t: float, dof: float) -> float:
    """Two-sided p-value of Student's t with `dof` degrees of freedom."""
    if not math.isfinite(t):
        return 0.0
    if dof > 1e6:
        return math.erfc(abs(t) / math.sqrt(2.0))
    return betainc(0.5 * dof, 0.5, dof / (dof + t * t))


def compare(a, var_a, b, var_b, dof_a: float, dof_b: float) -> dict:
    """Compares image a (ours) with reference b (Mitsuba); see the module doc.

    Both variances are estimates (a's from its spp samples, b's from K passes), so
    z = (a - b) / sqrt(var_a + var_b) follows Student's t with the Welch-Satterthwaite
    degrees of freedom rather than a normal distribution; with a plain normal
    p-value, 50 000 pixel tests with K = 32 passes would fail now and then on
    identical renderers (seen in Mitsuba-vs-Mitsuba runs)."""
    if a.shape != b.shape:
        return {"pass": False, "why": f"shape {a.shape} vs {b.shape}"}
    ma, mb = a.reshape(-1, 3).mean(0), b.reshape(-1, 3).mean(0)
    rel = np.abs(ma - mb) / np.maximum(np.abs(mb), 1e-12)
    # Floor the variance so pixels with no noise at all (emitters seen directly,
    # background) compare up to float rounding rather than exactly.
    floor = (1e-4 * np.maximum(np.abs(a), np.abs(b))) ** 2 + 1e-12
    var = np.maximum(var_a + var_b, floor)
    z = np.abs(a - b) / np.sqrt(var)
    # Welch-Satterthwaite; noise-free pixels (floored variance) count as normal.
    dof = var**2 / np.maximum(var_a**2 / dof_a + var_b**2 / dof_b, var**2 / 1e9)
    n = z.size
    finite = bool(np.isfinite(a).all() and np.isfinite(b).all())
    sidak_alpha = -math.expm1(math.log1p(-ALPHA) / n)
    # p-values only where they can matter: |z| <= 3 gives p >= 0.0027 for any dof
    # (the normal has the lightest tails), above the Sidak threshold once n > 4.
    idx = np.flatnonzero(z.ravel() > 3.0) if finite else np.arange(0)
    pvals = np.array([t_pvalue(float(z.flat[i]), float(dof.flat[i])) for i in idx])
    p_min = float(pvals.min()) if pvals.size else 1.0
    if not finite:
        p_min = 0.0
    # Sidak: probability that at least one of n independent tests is this extreme.
    p_corr = -math.expm1(n * math.log1p(-p_min)) if p_min < 1.0 else 1.0
    rejected = float((pvals < sidak_alpha).sum() / n)
    ok_mean = bool((rel < REL_TOL).all())
    ok_z = finite and p_corr >= ALPHA
    return {
        "pass": ok_mean and ok_z,
        "mean_ours": ma.tolist(),
        "mean_mts": mb.tolist(),
        "rel": rel.tolist(),
        "z_max": float(z.max()) if finite else math.inf,
        "p_min_corrected": p_corr,
        "rejected_fraction": rejected,
        "why": "" if ok_mean and ok_z else ("mean" if not ok_mean else "") + (" z-test" if not ok_z else ""),
    }


def row(name: str, r: dict, expect: bool = True) -> str:
    verdict = "PASS" if r["pass"] == expect else "FAIL"
    if "rel" not in r:
        return f"{name:<28} {verdict}  {r['why']}"
    rel = " ".join(f"{x * 100:6.3f}" for x in r["rel"])
    return (
        f"{name:<28} {verdict}  rel% R,G,B {rel}   z_max {r['z_max']:7.2f}  "
        f"p_sidak {r['p_min_corrected']:.3g}  rejected {r['rejected_fraction'] * 100:.3f}%"
        + ("" if expect else "  (expected to fail)")
    )


# --------------------------------------------------------------------------- self-tests


def self_test_camera() -> tuple[bool, str]:
    """A small bright sphere up and to the right: Mitsuba must draw it where OUR
    camera projects it (catches a mirrored x or flipped y)."""
    cam = {"from": [0.3, 0.2, 5.0], "to": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov": 30.0, "width": 64, "height": 48}
    target = [0.9, 0.55, 0.2]
    spec = ms.SceneSpec(
        path=ms.REPO / "selftest_camera.toml",
        data={
            "camera": {**{k: cam[k] for k in ("from", "to", "up", "fov")}, "resolution": [64, 48]},
            "render": {"max_depth": 1},
            "lights": [{"type": "sphere", "center": target, "radius": 0.06, "radiance": [1, 1, 1]}],
        },
    )
    img = np.array(mi.render(mi.load_dict(ms.to_mitsuba_dict(spec, spp=16))))[..., 0]
    ys, xs = np.nonzero(img > 0.5 * img.max())
    got = (xs.mean() + 0.5, ys.mean() + 0.5)
    want = ms.project(cam, target)
    ok = abs(got[0] - want[0]) < 1.0 and abs(got[1] - want[1]) < 1.0
    return ok, f"bright spot at ({got[0]:.2f}, {got[1]:.2f}) px, our camera projects it to ({want[0]:.2f}, {want[1]:.2f})"


def self_test_envmap() -> tuple[bool, str]:
    """Mitsuba's envmap lookup against the lat-long convention gradtrace documents
    (u = atan2(x, -z)/2pi, v = acos(y)/pi) with Mitsuba's texel placement: u texel
    centres at (i + 1/2)/W wrapping, v rows at i/(H - 1) (row 0 = zenith)."""
    h, w = 8, 16
    tex = np.random.default_rng(7).uniform(0.1, 1.0, (h, w, 3)).astype(np.float32)
    path = OUT_DIR / "selftest_env.exr"
    mi.Bitmap(tex).write(str(path))
    env = mi.load_dict({"type": "scene", "env": {"type": "envmap", "filename": str(path)}}).environment()

    def expected(u, v):
        x = ((u - 0.5 / w) % 1.0) * w
        y = v * (h - 1)
        x0, y0 = min(int(x), w - 1), min(int(y), h - 2)
        fx, fy = x - x0, y - y0
        t = lambda i, j: tex[j, i % w].astype(np.float64)  # noqa: E731
        return (t(x0, y0) * (1 - fx) + t(x0 + 1, y0) * fx) * (1 - fy) + (t(x0, y0 + 1) * (1 - fx) + t(x0 + 1, y0 + 1) * fx) * fy

    worst = 0.0
    for u, v in [(0.1, 0.3), (0.37, 0.61), (0.8, 0.9), (0.97, 0.05), (0.5, 0.5), (0.26, 0.74)]:
        d = ms.latlong_to_direction(u, v)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(-d[0], -d[1], -d[2])
        got = np.array(env.eval(si), dtype=np.float64)
        worst = max(worst, float(np.abs(got - expected(u, v)).max()))
    return worst < 1e-4, f"max |mitsuba - convention| = {worst:.2e}"


def self_test_rejects() -> tuple[bool, str]:
    """Features with no Mitsuba equivalent must be refused, naming the key."""
    base = {"camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov": 40, "resolution": [4, 4]}}
    bad = [
        ({"materials": {"m": {"type": "blinn_phong", "kd": 0.5, "ks": 0.5, "exponent": 10}}}, "materials.m.type"),
        ({"materials": {"m": {"type": "cook_torrance", "kd": 0.5, "ks": 0.5, "exponent": 10}}}, "materials.m.type"),
        ({"shapes": [{"type": "sphere", "radius": 1, "bump": "b"}]}, "shapes[0].bump"),
        ({"environment": {"type": "gaussian_sky"}}, "environment.type"),
    ]
    for extra, key in bad:
        spec = ms.SceneSpec(path=Path("bad.toml"), data={**base, **extra})
        try:
            ms.to_mitsuba_dict(spec)
        except ms.ConversionError as e:
            if f"`{key}`" not in str(e):
                return False, f"error for {key} does not name it: {e}"
            continue
        return False, f"{key} was not rejected"
    return True, "blinn_phong, cook_torrance, bump, gaussian_sky rejected with the key named"


# --------------------------------------------------------------------------- main


def gradtrace_render(binary: str | None, scene: Path, out: Path, spp: int) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.exists():
        out.unlink()
    args = ["render", str(scene), "--out", str(out), "--spp", str(spp), "--quiet"]
    cmd = [binary, *args] if binary else ["cargo", "run", "--release", "--quiet", "--", *args]
    subprocess.run(cmd, cwd=ms.REPO, check=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gradtrace", help="gradtrace binary (default: cargo run --release)")
    ap.add_argument("--scenes", nargs="+", default=DEFAULT_SCENES, help="scene names under scenes/validation/")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--mitsuba-only", action="store_true", help="self-tests and controls only")
    args = ap.parse_args()
    if args.spp < 2:
        ap.error("--spp must be at least 2")
    if args.gradtrace is None and shutil.which("cargo") is None and not args.mitsuba_only:
        ap.error("cargo not found; pass --gradtrace BINARY or --mitsuba-only")

    t_start = time.time()
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    write_validation_scenes(VALIDATION_DIR)
    lines, failed = [], False

    def record(name, ok, msg):
        nonlocal failed
        failed |= not ok
        lines.append(f"{name:<28} {'PASS' if ok else 'FAIL'}  {msg}")
        print(lines[-1], flush=True)

    print("== self-tests")
    for name, fn in [("camera orientation", self_test_camera), ("envmap convention", self_test_envmap), ("unsupported features", self_test_rejects)]:
        record(name, *fn())

    print("== checker controls (Mitsuba only)")
    cornell = ms.load_scene(VALIDATION_DIR / "cornell.toml")
    w, h = cornell.resolution()
    conv = ms.to_mitsuba_dict(cornell, spp=args.spp)
    a, va, dof = render_mitsuba(conv, args.spp, seed0=1_000_000)
    b, vb, _ = render_mitsuba(conv, args.spp, seed0=2_000_000)
    for name, r, expect in [
        ("mitsuba vs mitsuba", compare(a, va, b, vb, dof, dof), True),
        ("mitsuba x1.03 vs mitsuba", compare(1.03 * a, 1.03**2 * va, b, vb, dof, dof), False),
    ]:
        ok = r["pass"] == expect
        failed |= not ok
        lines.append(row(name, r, expect))
        print(lines[-1], flush=True)
    orig = mi.cornell_box()
    orig["sensor"]["film"].update({"width": w, "height": h, "rfilter": {"type": "box"}})
    orig["sensor"]["sampler"]["sample_count"] = args.spp
    c, vc, _ = render_mitsuba(orig, args.spp, seed0=3_000_000)
    r = compare(a, va, c, vc, dof, dof)
    failed |= not r["pass"]
    lines.append(row("converted vs cornell_box()", r))
    print(lines[-1], flush=True)

    if not args.mitsuba_only:
        print("== gradtrace vs Mitsuba")
        for name in args.scenes:
            path = VALIDATION_DIR / f"{name}.toml"
            try:
                spec = ms.load_scene(path)
                scene_dict = ms.to_mitsuba_dict(spec, spp=args.spp)
                out = OUT_DIR / f"{name}.exr"
                t0 = time.time()
                gradtrace_render(args.gradtrace, path, out, args.spp)
                t1 = time.time()
                ours, var_ours = load_ours(out)
                ref, var_ref, dof_ref = render_mitsuba(scene_dict, args.spp)
                t2 = time.time()
                mi.Bitmap(ref.astype(np.float32)).write(str(OUT_DIR / f"{name}_mitsuba.exr"))
                # Our variance is the sample variance of spp samples over spp.
                r = compare(ours, var_ours, ref, var_ref, args.spp - 1, dof_ref)
                lines.append(row(name, r) + f"   [gradtrace {t1 - t0:.1f}s, mitsuba {t2 - t1:.1f}s]")
                failed |= not r["pass"]
                if not r["pass"]:
                    diff = np.abs(ours - ref) / np.sqrt(np.maximum(var_ours + var_ref, 1e-12))
                    mi.Bitmap(diff.astype(np.float32)).write(str(OUT_DIR / f"{name}_z.exr"))
            except (ms.ConversionError, subprocess.CalledProcessError, RuntimeError) as e:
                failed = True
                lines.append(f"{name:<28} FAIL  {e}")
            print(lines[-1], flush=True)

    print(f"\n== summary ({time.time() - t_start:.0f} s; mean tolerance {REL_TOL * 100:.0f} %, Sidak-corrected alpha {ALPHA})")
    print("\n".join(lines))
    print("VALIDATION " + ("FAILED" if failed else "PASSED"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
