//! seed → scene TOML text: small random scenes for tests that must hold on scenes
//! nobody wrote by hand (every layer finite, no panic). The text goes through the
//! real parser (`scene::load_from_str`, or a file for the binary), so the tests
//! cover the format as users write it.
//!
//! A scene is a camera looking at a floor quad (a back wall half the time), 1–4
//! objects (spheres, quads, cubes, and meshes from `scenes/models`: cow and teapot,
//! the large bunny rarely and scaled down), 1–3 lights and, or not, a sky. Lights
//! are rect lights of random size (0.02–1), tilt (including grazing, up to edge-on
//! to the floor) and height (including a few hundredths above a surface) and
//! sphere lights (close or far); materials are lambert, blinn_phong and
//! cook_torrance of random exponent (1–10⁴) and mirror, some with a sinusoid bump
//! map (spheres and quads; the models have no texture coordinates). Skies:
//! `constant`, `gaussian_sky` or the bundled `envs/sky.hdr` image.
//!
//! [`Options`]:
//! * `diffuse_only`: lambert materials, no bumps, sphere lights only, no mirror,
//!   no quad objects besides the floor and wall (scenes kept as the bounds in
//!   `tests/shadow_field_generated.rs` were measured on); skies constant, image or
//!   none.
//! * `glossy_only`: what `preview glossy` models: no lights, a constant or image
//!   sky always, lambert, blinn_phong and cook_torrance materials of exponent
//!   2–128 (the paper's range: low-frequency transfer) on the objects, a lambert
//!   floor and wall (the paper's diffuse plane), no bumps, and meshes only (cubes,
//!   the cow and the teapot; no spheres, no quad objects: a vertex holds one
//!   side's transfer).
//! * `asset_dir`: the folder that holds `models/` and `envs/`, as the scene names
//!   it: `None` writes `models/cow.obj`, right for a scene file in `scenes/` (or
//!   parsed with a path there); a test writing its file elsewhere passes the
//!   absolute `scenes` folder.
//! * `resolution`, `spp`, `max_depth`: the `[camera]` and `[render]` values.
//! * `meshes`: whether OBJ models may appear (loading them costs milliseconds).
//!
//! Deterministic: the same seed and options give the same text on every machine
//! (splitmix64, formatting of f32 by `{:?}`), so a failing seed is a reproducer.

use std::fmt::Write;

/// What the generator may put in a scene (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub diffuse_only: bool,
    pub glossy_only: bool,
    pub asset_dir: Option<String>,
    pub resolution: [u32; 2],
    pub spp: u32,
    pub max_depth: u32,
    pub meshes: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            diffuse_only: false,
            glossy_only: false,
            asset_dir: None,
            resolution: [32, 24],
            spp: 4,
            max_depth: 4,
            meshes: true,
        }
    }
}

/// splitmix64 (Steele, Lea & Flood 2014): a tiny, well-mixed generator with no
/// dependency, identical on every platform.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 24 bits.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Log-uniform in [lo, hi) (lo > 0): sizes and exponents over decades.
    pub fn log_range(&mut self, lo: f32, hi: f32) -> f32 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.f32()).exp()
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * n as u64) >> 32) as u32
    }

    pub fn chance(&mut self, p: f32) -> bool {
        self.f32() < p
    }

    fn colour(&mut self, lo: f32, hi: f32) -> [f32; 3] {
        [0; 3].map(|_| self.range(lo, hi))
    }
}

/// Three numbers as a TOML array, each rounded to 4 decimals (short, exact text).
fn v3(v: [f32; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// An asset's path as the scene names it (see [`Options::asset_dir`]).
fn asset(opts: &Options, rel: &str) -> String {
    match &opts.asset_dir {
        Some(dir) => format!("{}/{rel}", dir.trim_end_matches('/')),
        None => rel.to_string(),
    }
}

fn num(x: f32) -> String {
    let r = (x as f64 * 1e4).round() / 1e4;
    format!("{r:?}")
}

/// The scene of `seed` under `opts`, as TOML text.
pub fn scene_toml(seed: u64, opts: &Options) -> String {
    Generator {
        rng: Rng::new(seed),
        opts,
        out: String::new(),
        materials: 0,
        bumps: 0,
    }
    .scene(seed)
}

struct Generator<'a> {
    rng: Rng,
    opts: &'a Options,
    out: String,
    materials: u32,
    bumps: u32,
}

impl Generator<'_> {
    fn scene(mut self, seed: u64) -> String {
        let r = &mut self.rng;
        let [w, h] = self.opts.resolution;
        // The camera circles the origin, above the floor, looking at the objects.
        let azimuth = r.range(-1.2, 1.2);
        let dist = r.range(2.0, 4.0);
        let height = r.range(0.3, 2.2);
        let from = [dist * azimuth.sin(), height, dist * azimuth.cos()];
        let to = [r.range(-0.3, 0.3), r.range(0.0, 0.5), r.range(-0.3, 0.3)];
        let fov = r.range(25.0, 55.0);
        let _ = writeln!(
            self.out,
            "# gradtrace::scene::generate, seed {seed}\n\n[camera]\nfrom = {}\nto = {}\nfov = {}\nresolution = [{w}, {h}]\n\n[render]\nspp = {}\nmax_depth = {}\n",
            v3(from),
            v3(to),
            num(fov),
            self.opts.spp,
            self.opts.max_depth
        );
        self.sky();
        // The floor, and half the time a wall behind the objects.
        let m = self.receiver_material();
        self.shape(
            "quad",
            &format!("corner = [-3.0, 0.0, 3.0]\nedge_u = [6.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, -6.0]\n{m}"),
        );
        if self.rng.chance(0.5) {
            let m = self.receiver_material();
            let z = self.rng.range(-1.6, -0.6);
            self.shape(
                "quad",
                &format!("corner = [-3.0, 0.0, {}]\nedge_u = [6.0, 0.0, 0.0]\nedge_v = [0.0, 3.0, 0.0]\n{m}", num(z)),
            );
        }
        let objects = 1 + self.rng.below(if self.opts.glossy_only { 3 } else { 4 });
        let mut tops = Vec::new();
        for _ in 0..objects {
            tops.push(self.object());
        }
        let lights = if self.opts.glossy_only {
            0
        } else {
            1 + self.rng.below(3)
        };
        for _ in 0..lights {
            self.light(&tops);
        }
        self.out
    }

    fn sky(&mut self) {
        let opts = self.opts;
        let r = &mut self.rng;
        let kind = if opts.glossy_only {
            if r.chance(0.5) {
                1
            } else {
                3
            }
        } else {
            r.below(4)
        };
        let text = match kind {
            1 => format!(
                "type = \"constant\"\nradiance = {}",
                v3(r.colour(0.05, 1.0))
            ),
            2 if !self.opts.diffuse_only => format!(
                "type = \"gaussian_sky\"\ndirection = {}\nsharpness = {}\npeak = {}\nambient = {}",
                v3([r.range(-1.0, 1.0), r.range(0.05, 1.0), r.range(-1.0, 1.0)]),
                num(r.log_range(0.5, 200.0)),
                v3(r.colour(0.5, 8.0)),
                v3(r.colour(0.0, 0.2))
            ),
            3 => format!(
                "type = \"image\"\nfile = \"{}\"\nscale = {}",
                asset(opts, "envs/sky.hdr"),
                num(r.range(0.2, 2.0))
            ),
            _ => return,
        };
        let _ = writeln!(self.out, "[environment]\n{text}\n");
    }

    /// A new material (and sometimes, for `bumpable` shapes, a bump): the shape's
    /// `material` line, and its `bump` line when there is one.
    fn material(&mut self, bumpable: bool) -> String {
        let name = format!("m{}", self.materials);
        self.materials += 1;
        let r = &mut self.rng;
        let kind = if self.opts.diffuse_only {
            0
        } else if self.opts.glossy_only {
            r.below(3)
        } else {
            r.below(5)
        };
        let exponent = if self.opts.glossy_only {
            (2.0, 128.0)
        } else {
            (1.0, 1e4)
        };
        let body = match kind {
            1 | 2 => {
                let kd = r.colour(0.0, 0.6);
                let ks = r.colour(0.0, 0.4);
                format!(
                    "type = \"{}\"\nkd = {}\nks = {}\nexponent = {}",
                    if kind == 1 {
                        "blinn_phong"
                    } else {
                        "cook_torrance"
                    },
                    v3(kd),
                    v3(ks),
                    num(r.log_range(exponent.0, exponent.1))
                )
            }
            3 => format!(
                "type = \"mirror\"\nreflectance = {}",
                v3(r.colour(0.3, 0.95))
            ),
            _ => format!("type = \"lambert\"\nalbedo = {}", v3(r.colour(0.02, 0.9))),
        };
        let _ = writeln!(self.out, "[materials.{name}]\n{body}\n");
        if bumpable && !self.opts.diffuse_only && !self.opts.glossy_only && self.rng.chance(0.3) {
            let b = format!("b{}", self.bumps);
            self.bumps += 1;
            let r = &mut self.rng;
            let terms: Vec<String> = (0..1 + r.below(2))
                .map(|_| {
                    // Integer frequency[0]: continuous across a sphere's seam.
                    format!(
                        "{{ amplitude = {}, frequency = [{}, {}], phase = {} }}",
                        num(r.log_range(0.001, 0.03)),
                        r.below(25) as i32 - 12,
                        num(r.range(-20.0, 20.0)),
                        num(r.range(0.0, std::f32::consts::TAU))
                    )
                })
                .collect();
            let _ = writeln!(
                self.out,
                "[bumps.{b}]\ntype = \"sinusoids\"\nterms = [{}]\n",
                terms.join(", ")
            );
            return format!("material = \"{name}\"\nbump = \"{b}\"");
        }
        format!("material = \"{name}\"")
    }

    /// The floor's or the wall's material: lambert in `glossy_only` scenes, as the
    /// paper's plane. A large glossy plane's highlight moves within faces that
    /// the spatial criterion sees no reason to split (the transfer, in each
    /// vertex's frame, is the same all over an open plane) and that the lookup at
    /// the vertices' view directions cannot hold: 132 % RMSE on one such scene.
    fn receiver_material(&mut self) -> String {
        if !self.opts.glossy_only {
            return self.material(false);
        }
        let name = format!("m{}", self.materials);
        self.materials += 1;
        let albedo = v3(self.rng.colour(0.02, 0.9));
        let _ = writeln!(
            self.out,
            "[materials.{name}]\ntype = \"lambert\"\nalbedo = {albedo}\n"
        );
        format!("material = \"{name}\"")
    }

    fn shape(&mut self, kind: &str, body: &str) {
        let _ = writeln!(self.out, "[[shapes]]\ntype = \"{kind}\"\n{body}\n");
    }

    /// One object on (or above) the floor; returns the top of its bounds, where a
    /// close light may hang.
    fn object(&mut self) -> [f32; 3] {
        let r = &mut self.rng;
        let (x, z) = (r.range(-1.2, 1.2), r.range(-1.0, 1.0));
        let lift = if r.chance(0.7) {
            0.0
        } else {
            r.range(0.0, 0.6)
        };
        let mut kind = r.below(if self.opts.meshes { 6 } else { 4 });
        if kind == 2 && self.opts.diffuse_only {
            kind = 0;
        }
        if self.opts.glossy_only && kind < 3 {
            kind = 3;
        }
        match kind {
            0 | 1 => {
                let radius = r.log_range(0.03, 0.5);
                let m = self.material(true);
                self.shape(
                    "sphere",
                    &format!(
                        "center = {}\nradius = {}\n{m}",
                        v3([x, radius + lift, z]),
                        num(radius)
                    ),
                );
                [x, 2.0 * radius + lift, z]
            }
            2 => {
                let size = [r.log_range(0.1, 1.2), r.log_range(0.1, 1.2)];
                let axis = [r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0)];
                let angle = r.range(0.0, 360.0);
                let y = 0.5 * size[0].max(size[1]) + lift;
                let m = self.material(true);
                self.shape(
                    "quad",
                    &format!(
                        "size = [{}, {}]\ntransform = {{ rotate = [{}, {}, {}, {}], translate = {} }}\n{m}",
                        num(size[0]),
                        num(size[1]),
                        num(axis[0]),
                        num(axis[1]),
                        num(axis[2] + 0.01),
                        num(angle),
                        v3([x, y, z])
                    ),
                );
                [x, 2.0 * y, z]
            }
            3 => {
                let s = [0; 3].map(|_| r.log_range(0.05, 0.4));
                let yaw = r.range(0.0, 90.0);
                let m = self.material(false);
                self.shape(
                    "cube",
                    &format!(
                        "transform = {{ scale = {}, rotate = [0, 1, 0, {}], translate = {} }}\n{m}",
                        v3(s),
                        num(yaw),
                        v3([x, s[1] + lift, z])
                    ),
                );
                [x, 2.0 * s[1] + lift, z]
            }
            _ => {
                // Model, scale range, height of its base below its origin, height.
                let pick = if self.opts.glossy_only {
                    1 + r.below(9)
                } else {
                    r.below(10)
                };
                let (file, lo, hi, base, tall) = match pick {
                    0 => ("models/stanford-bunny.obj", 2.0, 5.0, 0.033, 0.154),
                    1..=4 => ("models/cow.obj", 0.05, 0.15, 3.637, 6.397),
                    _ => ("models/teapot.obj", 0.06, 0.2, 0.0, 3.15),
                };
                let s = r.range(lo, hi);
                let yaw = r.range(0.0, 360.0);
                let smooth = r.chance(0.5);
                let file = asset(self.opts, file);
                let m = self.material(false);
                self.shape(
                    "mesh",
                    &format!(
                        "file = \"{file}\"\nsmooth_normals = {smooth}\ntransform = {{ scale = {}, rotate = [0, 1, 0, {}], translate = {} }}\n{m}",
                        num(s),
                        num(yaw),
                        v3([x, s * base + lift, z])
                    ),
                );
                [x, s * (base + tall) + lift, z]
            }
        }
    }

    /// One light: a rect (not with `diffuse_only`) or a sphere, close to an
    /// object's top, to the floor or far.
    fn light(&mut self, tops: &[[f32; 3]]) {
        let r = &mut self.rng;
        let rect = !self.opts.diffuse_only && r.chance(0.6);
        // Where: just above an object, low over the floor, or anywhere up high.
        let place = r.below(3);
        let [x, y, z] = match place {
            0 => {
                let t = tops[r.below(tops.len() as u32) as usize];
                [
                    t[0] + r.range(-0.1, 0.1),
                    t[1] + r.log_range(0.01, 0.4),
                    t[2] + r.range(-0.1, 0.1),
                ]
            }
            1 => [
                r.range(-1.5, 1.5),
                r.log_range(0.02, 0.5),
                r.range(-1.5, 1.0),
            ],
            _ => [r.range(-2.0, 2.0), r.range(0.8, 3.5), r.range(-1.5, 2.0)],
        };
        // Power 0.5–8 (in radiance × area), so that tiny lights are bright.
        let power = r.log_range(0.5, 8.0);
        let tint = r.colour(0.6, 1.0);
        if rect {
            let size = [r.log_range(0.02, 1.0), r.log_range(0.02, 1.0)];
            // Facing down (rotate +z to −y), then tilted: mostly a few degrees,
            // sometimes grazing, sometimes exactly edge-on to the floor.
            let tilt = match r.below(4) {
                0 | 1 => r.range(0.0, 10.0),
                2 => r.range(10.0, 80.0),
                _ => {
                    if r.chance(0.3) {
                        90.0
                    } else {
                        r.range(80.0, 90.0)
                    }
                }
            };
            let tilt_axis = r.range(0.0, std::f32::consts::TAU);
            let yaw = r.range(0.0, 360.0);
            let radiance = tint.map(|c| c * power / (size[0] * size[1]));
            let _ = writeln!(
                self.out,
                "[[lights]]\ntype = \"rect\"\nsize = [{}, {}]\ntransform = {{ rotate = [[1, 0, 0, 90], [0, 1, 0, {}], [{}, 0, {}, {}]], translate = {} }}\nradiance = {}\n",
                num(size[0]),
                num(size[1]),
                num(yaw),
                num(tilt_axis.cos()),
                num(tilt_axis.sin()),
                num(tilt),
                v3([x, y.max(0.01), z]),
                v3(radiance)
            );
        } else {
            let radius = r.log_range(0.01, 0.3);
            let radiance = tint.map(|c| c * power / (std::f32::consts::PI * radius * radius));
            let _ = writeln!(
                self.out,
                "[[lights]]\ntype = \"sphere\"\ncenter = {}\nradius = {}\nradiance = {}\n",
                v3([x, y.max(0.0) + radius + 0.005, z]),
                num(radius),
                v3(radiance)
            );
        }
    }
}
