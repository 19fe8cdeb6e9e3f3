//! Shared test support: deterministic quadrature, an independent random stream, and
//! (in [`chi2`]) the Pearson chi-square goodness-of-fit machinery for samplers.
//!
//! Use from a test file with `mod common;`. Not every test file uses every helper.
#![allow(dead_code)]

pub mod chi2;

/// SplitMix64: a small, statistically solid generator giving *independent* uniform
/// samples. The chi-square test assumes independent draws; low-discrepancy points
/// would match the expected counts too well and make p-values meaningless.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 random bits (every f32 in the grid is exact).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1], from the crate's one implementation
/// (`gradtrace::math::quadrature`).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let rule = gradtrace::math::quadrature::GaussLegendre::new(n);
    (rule.nodes().to_vec(), rule.weights().to_vec())
}

/// A composite Gauss-Legendre rule on [a, b]: `panels` equal panels of `order` nodes.
/// Returns (nodes, weights) so that Σ w f(x) ≈ ∫_a^b f.
pub fn composite_gl(a: f64, b: f64, panels: usize, order: usize) -> Vec<(f64, f64)> {
    gradtrace::math::quadrature::GaussLegendre::new(order).composite(a, b, panels)
}

/// Adaptive Simpson quadrature of `f` on [a, b] to absolute tolerance `tol`.
/// Deterministic and robust for the sharply peaked integrands of high exponents.
pub fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        f: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let delta = left + right - whole;
        if depth == 0 || delta.abs() <= 15.0 * tol {
            return left + right + delta / 15.0;
        }
        rec(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1)
            + rec(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
    }
    // Start from 64 panels so that a narrow peak cannot slip between the first nodes.
    let panels = 64;
    let h = (b - a) / panels as f64;
    (0..panels)
        .map(|i| {
            let (lo, hi) = (a + h * i as f64, a + h * (i + 1) as f64);
            let m = 0.5 * (lo + hi);
            let (fa, fm, fb) = (f(lo), f(m), f(hi));
            let whole = (hi - lo) / 6.0 * (fa + 4.0 * fm + fb);
            rec(f, lo, hi, fa, fm, fb, whole, tol / panels as f64, 40)
        })
        .sum()
}

/// A floor seen in perspective for the adaptive tests: inverse depth affine in the
/// image position, depth falling from 50 at the top to 28 at the bottom of a
/// 128-pixel image (2.7–4.8% per 8 pixels). Returns the depth and ∇(1/depth), the
/// floor raised towards the camera by `lift` (relative).
pub fn perspective_floor(p: glam::Vec2, lift: f32) -> (f32, glam::Vec2) {
    let q = 0.02 * (1.0 + 0.006 * p.y) * (1.0 + lift);
    (1.0 / q, glam::Vec2::new(0.0, 0.02 * 0.006 * (1.0 + lift)))
}

/// The `gradtrace` binary of this build.
pub const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

/// A fresh, empty directory in the system temp dir, unique per test file (the
/// test binary's name), test and process.
pub fn temp_dir(name: &str) -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap_or_default();
    let file = exe
        .file_stem()
        .map_or("test".into(), |s| s.to_string_lossy().into_owned());
    let dir = std::env::temp_dir().join(format!("gradtrace-{file}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the binary with `args` in `dir`, printing the call and what it printed.
pub fn run_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    let out = std::process::Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs");
    println!(
        "$ gradtrace {}\n-> {:?}\nstdout: {}stderr: {}",
        args.join(" "),
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A small bright sphere light (radiance 300) over a diffuse sphere on a floor
/// (noisy: the soft shadow, indirect light, the light's own edge) in front of a
/// constant sky seen directly (flat and noise-free): where per-pixel adaptive
/// sampling must pay off.
pub fn small_light_scene(width: u32, height: u32) -> String {
    format!(
        r#"
[camera]
from = [0, 1.2, 4.5]
to = [0, 0.5, 0]
fov = 35
resolution = [{width}, {height}]
[render]
spp = 16
max_depth = 4
[materials.grey]
type = "lambert"
albedo = [0.7, 0.7, 0.7]
[[shapes]]
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
material = "grey"
[[shapes]]
type = "quad"
corner = [-1.5, 0, 1.5]
edge_u = [3, 0, 0]
edge_v = [0, 0, -3]
material = "grey"
[[lights]]
type = "sphere"
center = [1.2, 1.8, 0.8]
radius = 0.08
radiance = [300, 300, 300]
[environment]
type = "constant"
radiance = [0.3, 0.3, 0.3]
"#
    )
}
