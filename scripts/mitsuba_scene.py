"""gradtrace scene TOML -> Mitsuba 3 scene dict (the one place that knows our format).

Only what both renderers share is converted; anything Mitsuba cannot reproduce
exactly (Blinn-Phong, Cook-Torrance, bump maps, the gaussian sky) raises
`ConversionError` with the offending key, so a validation never silently compares
two different scenes.

Conventions matched here (and checked by `validate_mitsuba.py --self-test`):
  * camera: ours is a pinhole look-at with a *vertical* fov, x to the right, row 0 at
    the top. Mitsuba's `perspective` with `fov_axis='y'` and `to_world =
    look_at(from, to, up)` produces the same image (not mirrored).
  * lambert -> `diffuse`, mirror -> `conductor` with `material='none'` (Fresnel = 1,
    so the reflectance is exactly `specular_reflectance`). Both are wrapped in
    `twosided` because our surfaces shade both sides; Mitsuba's BSDFs are black
    from the back otherwise. Emission stays one-sided, on the side of the normal.
  * quads `corner + s*edge_u + t*edge_v` -> `rectangle` (Mitsuba's is [-1,1]^2 in the
    xy plane with normal +z), normal = normalize(edge_u x edge_v).
  * environment image: both use u = atan2(x, -z)/2pi, v = acos(y)/pi (row 0 = zenith,
    u = 0 looks along -z).
  * integrator: Mitsuba's `path` `max_depth` counts path segments exactly as ours
    (1 = only directly visible emitters); `rr_depth` is the same threshold.

Usage as a library (after `mi.set_variant(...)`):
    import mitsuba_scene
    spec = mitsuba_scene.load_scene("scenes/validation/cornell.toml")
    scene_dict = mitsuba_scene.to_mitsuba_dict(spec, spp=64)
As a script it prints the dict: `python3 scripts/mitsuba_scene.py SCENE.toml`.
"""

from __future__ import annotations

import math
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


class ConversionError(ValueError):
    """A scene that cannot be converted; the message names file and key."""


# Keys that never change the image; accepted anywhere.
_HARMLESS = {"name", "id", "comment", "description"}

# Our `RenderSettings::default()`, used when the scene file omits a key.
_RENDER_DEFAULTS = {"spp": 16, "max_depth": 8, "seed": 0, "integrator": "path", "rr_depth": 5}


@dataclass
class SceneSpec:
    """The parsed TOML plus what the converter needs around it."""

    path: Path
    data: dict[str, Any]

    @property
    def name(self) -> str:
        return self.path.stem

    def camera(self) -> dict[str, Any]:
        return _camera(self)

    def render(self) -> dict[str, Any]:
        return _render(self)

    def resolution(self) -> tuple[int, int]:
        cam = self.camera()
        return cam["width"], cam["height"]


def load_scene(path: str | Path) -> SceneSpec:
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except OSError as e:
        raise ConversionError(f"{path}: cannot read: {e}") from e
    except tomllib.TOMLDecodeError as e:
        raise ConversionError(f"{path}: invalid TOML: {e}") from e
    return SceneSpec(path=path, data=data)


SCRIPTS = Path(__file__).resolve().parent
REPO = SCRIPTS.parent
VENV = SCRIPTS / ".venv"


def ensure_venv() -> None:
    """Re-executes the calling script inside scripts/.venv, creating it and
    installing scripts/requirements.txt first when needed (stdlib only)."""
    import os
    import subprocess

    py = VENV / "bin" / "python"
    if Path(sys.prefix).resolve() == VENV.resolve():
        return
    stamp = VENV / ".requirements.txt"
    req = (SCRIPTS / "requirements.txt").read_text()
    if not py.exists():
        print(f"creating {VENV}", file=sys.stderr, flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
    if not stamp.exists() or stamp.read_text() != req:
        print("installing scripts/requirements.txt", file=sys.stderr, flush=True)
        subprocess.run(
            [str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-r", str(SCRIPTS / "requirements.txt")],
            check=True,
        )
        stamp.write_text(req)
    os.execv(str(py), [str(py), *sys.argv])


def find_libllvm() -> str | None:
    """The libLLVM (19 or later) for Mitsuba's `llvm_ad_rgb` variant: DRJIT_LIBLLVM_PATH,
    Debian's libllvm19, or another system copy; None when there is none."""
    import glob
    import os
    import re
    import subprocess

    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    candidates = []
    try:
        listing = subprocess.run(["dpkg", "-L", "libllvm19"], capture_output=True, text=True).stdout
        candidates += [line for line in listing.splitlines() if "/libLLVM" in line and ".so" in line]
    except OSError:
        pass
    # Other system copies only from LLVM 19 on: with Debian 12's libLLVM-15,
    # Dr.Jit's kernels abort the process ("LLVM ERROR: Cannot select: fminimum").
    def major(path: str) -> int:
        m = re.search(r"libLLVM[-.]?(?:so\.)?(\d+)", os.path.basename(path))
        return int(m.group(1)) if m else 0

    system = glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM*.so*")
    candidates += sorted((c for c in system if major(c) >= 19), key=major, reverse=True)
    for c in candidates:
        if os.path.isfile(c):
            return c
    return None


# --------------------------------------------------------------------------- helpers


def _err(spec: SceneSpec, key: str, msg: str) -> ConversionError:
    return ConversionError(f"{spec.path}: `{key}`: {msg}")


def _vec3(spec: SceneSpec, key: str, v: Any) -> list[float]:
    """A 3-vector; a bare number means (v, v, v) as for colours."""
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return [float(v)] * 3
    if isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) for x in v):
        return [float(x) for x in v]
    raise _err(spec, key, f"expected a number or an array of 3 numbers, got {v!r}")


def _num(spec: SceneSpec, key: str, v: Any) -> float:
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return float(v)
    raise _err(spec, key, f"expected a number, got {v!r}")


def _check_keys(spec: SceneSpec, where: str, table: dict, allowed: set[str]) -> None:
    extra = set(table) - allowed - _HARMLESS
    if extra:
        raise _err(
            spec,
            f"{where}.{sorted(extra)[0]}",
            "not supported by the Mitsuba converter (accepted here: "
            + ", ".join(sorted(allowed))
            + ")",
        )


def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _add(a, b):
    return [a[i] + b[i] for i in range(3)]


def _scale(a, s):
    return [x * s for x in a]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def _norm(a):
    return math.sqrt(_dot(a, a))


def _normalize(a):
    n = _norm(a)
    return [x / n for x in a]


def _matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def _identity():
    return [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def _rotation(axis, deg):
    """Rodrigues rotation matrix (right-handed, counter-clockwise for positive deg)."""
    x, y, z = _normalize(axis)
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    C = 1.0 - c
    return [
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s, 0.0],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s, 0.0],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]


def transform_matrix(spec: SceneSpec, key: str, t: dict | None) -> list[list[float]]:
    """Our `transform = {scale, rotate=[ax,ay,az,deg], translate}` as a 4x4 matrix,
    applied in the order scale, then rotate, then translate (M = T * R * S).
    `rotate` may also be a list of such rotations, applied first to last."""
    if t is None:
        return _identity()
    if not isinstance(t, dict):
        raise _err(spec, key, f"expected a table {{scale, rotate, translate}}, got {t!r}")
    _check_keys(spec, key, t, {"scale", "rotate", "translate"})
    m = _identity()
    if "scale" in t:
        s = _vec3(spec, key + ".scale", t["scale"])
        m = [[s[0], 0, 0, 0], [0, s[1], 0, 0], [0, 0, s[2], 0], [0, 0, 0, 1.0]]
    if "rotate" in t:
        rot = t["rotate"]
        rots = rot if rot and isinstance(rot[0], list) else [rot]
        for r in rots:
            if not (isinstance(r, list) and len(r) == 4):
                raise _err(spec, key + ".rotate", f"expected [ax, ay, az, degrees], got {r!r}")
            axis = [_num(spec, key + ".rotate", x) for x in r[:3]]
            if _norm(axis) == 0.0:
                raise _err(spec, key + ".rotate", "rotation axis must not be zero")
            m = _matmul(_rotation(axis, _num(spec, key + ".rotate", r[3])), m)
    if "translate" in t:
        tr = _vec3(spec, key + ".translate", t["translate"])
        tm = _identity()
        for i in range(3):
            tm[i][3] = tr[i]
        m = _matmul(tm, m)
    return m


def _apply_point(m, p):
    return [sum(m[i][j] * p[j] for j in range(3)) + m[i][3] for i in range(3)]


def _apply_vector(m, v):
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


# --------------------------------------------------------------------------- sections


def _camera(spec: SceneSpec) -> dict[str, Any]:
    cam = spec.data.get("camera")
    if not isinstance(cam, dict):
        raise _err(spec, "camera", "missing [camera] table")
    _check_keys(spec, "camera", cam, {"from", "to", "up", "fov", "resolution", "width", "height"})
    for k in ("from", "to", "fov"):
        if k not in cam:
            raise _err(spec, f"camera.{k}", "missing")
    if "resolution" in cam:
        res = cam["resolution"]
        if not (isinstance(res, list) and len(res) == 2 and all(isinstance(x, int) for x in res)):
            raise _err(spec, "camera.resolution", f"expected [width, height], got {res!r}")
        w, h = res
    else:
        w, h = cam.get("width", 512), cam.get("height", 512)
    fov = _num(spec, "camera.fov", cam["fov"])
    if not 0.0 < fov < 180.0:
        raise _err(spec, "camera.fov", f"must be in (0, 180) degrees, got {fov}")
    return {
        "from": _vec3(spec, "camera.from", cam["from"]),
        "to": _vec3(spec, "camera.to", cam["to"]),
        "up": _vec3(spec, "camera.up", cam.get("up", [0.0, 1.0, 0.0])),
        "fov": fov,
        "width": int(w),
        "height": int(h),
    }


def _render(spec: SceneSpec) -> dict[str, Any]:
    r = dict(_RENDER_DEFAULTS)
    table = spec.data.get("render", {})
    _check_keys(spec, "render", table, set(_RENDER_DEFAULTS) | {"threads"})
    r.update({k: v for k, v in table.items() if k in _RENDER_DEFAULTS})
    if r["integrator"] not in ("path", "direct"):
        raise _err(spec, "render.integrator", f'expected "path" or "direct", got {r["integrator"]!r}')
    return r


def _material(spec: SceneSpec, key: str, m: dict) -> dict:
    if not isinstance(m, dict) or "type" not in m:
        raise _err(spec, key, "expected a table with a `type`")
    t = m["type"]
    if t == "lambert":
        _check_keys(spec, key, m, {"type", "albedo"})
        inner = {
            "type": "diffuse",
            "reflectance": {"type": "rgb", "value": _vec3(spec, key + ".albedo", m.get("albedo", 0.5))},
        }
    elif t == "mirror":
        _check_keys(spec, key, m, {"type", "reflectance"})
        inner = {
            "type": "conductor",
            "material": "none",
            "specular_reflectance": {
                "type": "rgb",
                "value": _vec3(spec, key + ".reflectance", m.get("reflectance", 1.0)),
            },
        }
    elif t in ("blinn_phong", "cook_torrance"):
        raise _err(spec, key + ".type", f'"{t}" has no exact Mitsuba 3 equivalent; cannot validate it')
    else:
        raise _err(spec, key + ".type", f'unknown material "{t}" (expected lambert or mirror)')
    return {"type": "twosided", "bsdf": inner}


_BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}


def _materials(spec: SceneSpec) -> dict[str, dict]:
    mats = spec.data.get("materials", {})
    out = {}
    if isinstance(mats, dict):
        for name, m in mats.items():
            out[name] = _material(spec, f"materials.{name}", m)
    elif isinstance(mats, list):  # [[materials]] with a name key
        for i, m in enumerate(mats):
            if "name" not in m:
                raise _err(spec, f"materials[{i}].name", "missing")
            out[m["name"]] = _material(spec, f"materials[{i}]", {k: v for k, v in m.items() if k != "name"})
    else:
        raise _err(spec, "materials", "expected a table of named materials")
    return out


def _bsdf_ref(spec: SceneSpec, key: str, mat: Any, materials: dict) -> dict:
    if isinstance(mat, dict):
        return _material(spec, key, mat)
    if isinstance(mat, str):
        if mat not in materials:
            raise _err(spec, key, f'unknown material "{mat}" (defined: {", ".join(materials) or "none"})')
        return {"type": "ref", "id": "mat_" + mat}
    raise _err(spec, key, f"expected a material name, got {mat!r}")


def _area(radiance: list[float]) -> dict:
    return {"type": "area", "radiance": {"type": "rgb", "value": radiance}}


def rect_to_world(corner, edge_u, edge_v) -> list[list[float]]:
    """Matrix mapping Mitsuba's rectangle ([-1,1]^2, z = 0, normal +z) onto
    corner + s*edge_u + t*edge_v; its third column is the unit normal
    edge_u x edge_v, so the transformed normal (and the emitting side) agree."""
    n = _cross(edge_u, edge_v)
    if _norm(n) == 0.0:
        raise ValueError("degenerate quad: edge_u and edge_v are parallel")
    n = _normalize(n)
    c = _add(corner, _scale(_add(edge_u, edge_v), 0.5))
    hu, hv = _scale(edge_u, 0.5), _scale(edge_v, 0.5)
    return [[hu[i], hv[i], n[i], c[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]


def _quad_geometry(spec: SceneSpec, key: str, s: dict):
    """(corner, edge_u, edge_v) in world space; accepts `corner` or `center`, and an
    optional `transform` on top."""
    if "edge_u" not in s or "edge_v" not in s:
        raise _err(spec, key, "a quad needs `edge_u` and `edge_v` (plus `corner` or `center`)")
    eu = _vec3(spec, key + ".edge_u", s["edge_u"])
    ev = _vec3(spec, key + ".edge_v", s["edge_v"])
    if "corner" in s:
        corner = _vec3(spec, key + ".corner", s["corner"])
    elif "center" in s:
        corner = _sub(_vec3(spec, key + ".center", s["center"]), _scale(_add(eu, ev), 0.5))
    else:
        raise _err(spec, key, "a quad needs `corner` (or `center`)")
    if "transform" in s:
        m = transform_matrix(spec, key + ".transform", s["transform"])
        corner, eu, ev = _apply_point(m, corner), _apply_vector(m, eu), _apply_vector(m, ev)
    if _norm(_cross(eu, ev)) == 0.0:
        raise _err(spec, key, "degenerate quad: edge_u and edge_v are parallel")
    return corner, eu, ev


def _obj_has_normals(path: Path) -> bool:
    with open(path, "r", errors="replace") as f:
        return any(line.startswith("vn ") for line in f)


def _shape(spec: SceneSpec, key: str, s: dict, materials: dict, mi) -> dict:
    if not isinstance(s, dict) or "type" not in s:
        raise _err(spec, key, "expected a table with a `type`")
    t = s["type"]
    common = {"type", "material", "emission", "bump"}
    if "bump" in s:
        raise _err(spec, key + ".bump", "bump maps have no exact Mitsuba 3 equivalent; cannot validate them")
    if t == "sphere":
        _check_keys(spec, key, s, common | {"center", "radius"})
        out = {
            "type": "sphere",
            "center": _vec3(spec, key + ".center", s.get("center", [0, 0, 0])),
            "radius": _num(spec, key + ".radius", s.get("radius", 1.0)),
        }
    elif t in ("quad", "rect", "rectangle"):
        _check_keys(spec, key, s, common | {"corner", "center", "edge_u", "edge_v", "transform"})
        corner, eu, ev = _quad_geometry(spec, key, s)
        out = {"type": "rectangle", "to_world": mi.ScalarTransform4f(rect_to_world(corner, eu, ev))}
    elif t == "mesh":
        _check_keys(spec, key, s, common | {"file", "transform"})
        if "file" not in s:
            raise _err(spec, key + ".file", "missing")
        f = (spec.path.parent / s["file"]).resolve()
        if not f.is_file():
            raise _err(spec, key + ".file", f"no such file {f}")
        if f.suffix.lower() != ".obj":
            raise _err(spec, key + ".file", "only OBJ meshes are converted")
        out = {
            "type": "obj",
            "filename": str(f),
            # Without `vn` lines we shade flat; Mitsuba would otherwise smooth.
            "face_normals": not _obj_has_normals(f),
            "to_world": mi.ScalarTransform4f(transform_matrix(spec, key + ".transform", s.get("transform"))),
        }
    else:
        raise _err(spec, key + ".type", f'unknown shape "{t}" (expected sphere, quad or mesh)')
    out["bsdf"] = _bsdf_ref(spec, key + ".material", s["material"], materials) if "material" in s else _BLACK
    if "emission" in s:
        e = _vec3(spec, key + ".emission", s["emission"])
        if any(e):
            out["emitter"] = _area(e)
    return out


def _light(spec: SceneSpec, key: str, light: dict, mi) -> dict:
    if not isinstance(light, dict) or "type" not in light:
        raise _err(spec, key, "expected a table with a `type`")
    t = light["type"]
    if "radiance" not in light:
        raise _err(spec, key + ".radiance", "missing")
    radiance = _vec3(spec, key + ".radiance", light["radiance"])
    if t == "sphere":
        _check_keys(spec, key, light, {"type", "center", "radius", "radiance"})
        out = {
            "type": "sphere",
            "center": _vec3(spec, key + ".center", light.get("center", [0, 0, 0])),
            "radius": _num(spec, key + ".radius", light.get("radius", 1.0)),
        }
    elif t in ("rect", "quad", "rectangle"):
        _check_keys(spec, key, light, {"type", "corner", "center", "edge_u", "edge_v", "transform", "radiance"})
        corner, eu, ev = _quad_geometry(spec, key, light)
        out = {"type": "rectangle", "to_world": mi.ScalarTransform4f(rect_to_world(corner, eu, ev))}
    else:
        raise _err(spec, key + ".type", f'unknown light "{t}" (expected sphere or rect)')
    # Lights do not reflect.
    out["bsdf"] = _BLACK
    out["emitter"] = _area(radiance)
    return out


def _environment(spec: SceneSpec) -> dict | None:
    env = spec.data.get("environment")
    if env is None:
        return None
    if not isinstance(env, dict) or "type" not in env:
        raise _err(spec, "environment", "expected a table with a `type`")
    t = env["type"]
    if t == "constant":
        _check_keys(spec, "environment", env, {"type", "radiance"})
        return {"type": "constant", "radiance": {"type": "rgb", "value": _vec3(spec, "environment.radiance", env["radiance"])}}
    if t == "image":
        _check_keys(spec, "environment", env, {"type", "file", "scale"})
        f = (spec.path.parent / env["file"]).resolve()
        if not f.is_file():
            raise _err(spec, "environment.file", f"no such file {f}")
        return {"type": "envmap", "filename": str(f), "scale": _num(spec, "environment.scale", env.get("scale", 1.0))}
    if t == "gaussian_sky":
        raise _err(spec, "environment.type", '"gaussian_sky" has no Mitsuba 3 equivalent; cannot validate it')
    raise _err(spec, "environment.type", f'unknown environment "{t}" (expected constant or image)')


# --------------------------------------------------------------------------- entry point


def to_mitsuba_dict(
    spec: SceneSpec,
    *,
    spp: int | None = None,
    width: int | None = None,
    height: int | None = None,
    max_depth: int | None = None,
    seed: int | None = None,
) -> dict:
    """Mitsuba scene dict for `spec`; the keyword arguments override the scene file
    like gradtrace's command-line options do. Needs a Mitsuba variant set."""
    import mitsuba as mi

    cam = spec.camera()
    r = spec.render()
    w = width or cam["width"]
    h = height or cam["height"]
    depth = int(max_depth if max_depth is not None else r["max_depth"])
    if r["integrator"] == "direct":
        # Directly visible emitters plus one bounce = Mitsuba path with 2 segments.
        depth = min(depth, 2)
    unknown = set(spec.data) - {"camera", "render", "materials", "shapes", "lights", "environment"} - _HARMLESS
    if unknown:
        raise _err(spec, sorted(unknown)[0], "unknown top-level table for the Mitsuba converter")

    scene: dict[str, Any] = {
        "type": "scene",
        "integrator": {
            "type": "path",
            "max_depth": depth,
            "rr_depth": int(r["rr_depth"]),
            "hide_emitters": False,
        },
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": cam["fov"],
            "near_clip": 1e-4,
            "far_clip": 1e7,
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["from"], target=cam["to"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": int(w),
                "height": int(h),
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
            "sampler": {
                "type": "independent",
                "sample_count": int(spp or r["spp"]),
                "seed": int(seed if seed is not None else r["seed"]),
            },
        },
    }
    materials = _materials(spec)
    for name, m in materials.items():
        scene["mat_" + name] = m
    shapes = spec.data.get("shapes", [])
    if not isinstance(shapes, list):
        raise _err(spec, "shapes", "expected [[shapes]] entries")
    for i, s in enumerate(shapes):
        scene[f"shape_{i:03d}"] = _shape(spec, f"shapes[{i}]", s, materials, mi)
    lights = spec.data.get("lights", [])
    if not isinstance(lights, list):
        raise _err(spec, "lights", "expected [[lights]] entries")
    for i, light in enumerate(lights):
        scene[f"light_{i:03d}"] = _light(spec, f"lights[{i}]", light, mi)
    env = _environment(spec)
    if env is not None:
        scene["environment"] = env
    return scene


# Pure-Python copies of our conventions, for the self-tests (no Mitsuba involved).


def project(cam: dict, x: list[float]) -> tuple[float, float] | None:
    """Pixel position of world point x under OUR camera (src/scene/camera.rs)."""
    fwd = _normalize(_sub(cam["to"], cam["from"]))
    right = _normalize(_cross(fwd, cam["up"]))
    up = _cross(right, fwd)
    d = _sub(x, cam["from"])
    z = _dot(d, fwd)
    if z <= 0:
        return None
    tan_half = math.tan(math.radians(cam["fov"]) / 2)
    aspect = cam["width"] / cam["height"]
    sx = _dot(d, right) / (z * tan_half * aspect)
    sy = _dot(d, up) / (z * tan_half)
    return (sx + 1) * 0.5 * cam["width"], (1 - sy) * 0.5 * cam["height"]


def latlong_to_direction(u: float, v: float) -> list[float]:
    """OUR lat-long convention (src/scene/environment.rs)."""
    phi, theta = u * 2 * math.pi, v * math.pi
    return [math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta)]


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__)
        return 2
    ensure_venv()
    import pprint

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    try:
        pprint.pprint(to_mitsuba_dict(load_scene(argv[1])))
    except ConversionError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
