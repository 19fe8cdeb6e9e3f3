//! Real spherical harmonics to order 4 (bands l ≤ 3, 16 coefficients; the shadow-field
//! papers' "fourth-order"): evaluation, projection, rotation (Ivanic–Ruedenberg
//! recurrences), zonal functions (clamped cosine, caps) and products (the triple-product
//! tensor, as a generated straight-line function in `sh/product.rs`).
//!
//! Convention: orthonormal over the unit sphere (∫ Y_i Y_j dω = δ_ij, no hidden 4π),
//! no Condon–Shortley phase, index i = l(l+1) + m, so that band 1 is
//! √(3/4π)·(y, z, x) — the shadow-field paper's Appendix B with P_l^m ≥ 0 near the
//! pole. The polar axis is z: fields are functions of direction only, so the
//! world's y-up convention does not enter here.

// Index loops mirror the subscripts of the formulas.
#![allow(clippy::needless_range_loop)]

mod product;

use crate::math::scalar::Scalar;
use crate::math::Vec3;
use glam::{DMat3, DVec3};

pub use product::{product, product_f64};

/// Number of bands (l = 0 … 3).
pub const BANDS: usize = 4;
/// Number of coefficients, BANDS².
pub const COEFFS: usize = 16;

/// A function on the sphere as 16 coefficients, f64 (precomputation, tests).
pub type Sh = [f64; COEFFS];
/// The same in f32, for the run-time fields.
pub type ShF = [f32; COEFFS];

/// Coefficient index of (l, m), |m| ≤ l.
pub const fn index(l: usize, m: i32) -> usize {
    ((l * (l + 1)) as i32 + m) as usize
}

/// (l, m) of coefficient `i`.
pub fn band_of(i: usize) -> (usize, i32) {
    let l = (i as f64).sqrt().floor() as usize;
    (l, i as i32 - (l * (l + 1)) as i32)
}

/// The 16 basis functions at the unit direction `d` (Cartesian polynomials).
pub fn eval(d: DVec3) -> Sh {
    eval_xyz(d.x, d.y, d.z)
}

/// [`eval`] in f32, for run-time lookups (f32 arithmetic throughout).
pub fn eval_f32(d: Vec3) -> ShF {
    eval_xyz(d.x, d.y, d.z)
}

/// The basis at the unit direction (x, y, z), written once for every scalar type.
#[inline]
pub fn eval_xyz<T: Scalar>(x: T, y: T, z: T) -> [T; COEFFS] {
    let (z2, x2, y2) = (z * z, x * x, y * y);
    let c = |k: f64, v: T| v.mul_const(k);
    [
        T::constant(0.282_094_791_773_878_14),
        c(0.488_602_511_902_919_9, y),
        c(0.488_602_511_902_919_9, z),
        c(0.488_602_511_902_919_9, x),
        c(1.092_548_430_592_079_2, x) * y,
        c(1.092_548_430_592_079_2, y) * z,
        c(0.315_391_565_252_520_05, z2.mul_const(3.0).add_const(-1.0)),
        c(1.092_548_430_592_079_2, x) * z,
        c(0.546_274_215_296_039_6, x2 - y2),
        c(0.590_043_589_926_643_5, y) * (x2.mul_const(3.0) - y2),
        c(2.890_611_442_640_554, x) * y * z,
        c(0.457_045_799_464_465_8, y) * z2.mul_const(5.0).add_const(-1.0),
        c(0.373_176_332_590_115_4, z) * z2.mul_const(5.0).add_const(-3.0),
        c(0.457_045_799_464_465_8, x) * z2.mul_const(5.0).add_const(-1.0),
        c(1.445_305_721_320_277, z) * (x2 - y2),
        c(0.590_043_589_926_643_5, x) * (x2 - y2.mul_const(3.0)),
    ]
}

/// ∫_P Y_i(ω) dω over the spherical polygon P that a convex planar polygon
/// subtends from a point: `corners` are its corners relative to that point, in
/// order (either winding), the point not in its plane. Exact (no quadrature):
/// each band is written as 2l + 1 zonal harmonics P_l(w_j·ω) (the addition
/// theorem, `ZonalBasis`), and the axial moments ∫_P (w·ω)^k dω of each come
/// from the boundary by the recurrence of the divergence theorem on the sphere
/// (Arvo 1995; Belcour et al. 2018):
/// ∫_P Δ G(w·ω) = ∮ ∇G·ν  with G′(t) = t^k gives
/// τ_{k+1} = (k τ_{k−1} − Σ_edges (w·ν_e) ∫_e (w·ω)^k ds) / (k + 2),
/// τ_0 the solid angle, ν_e the edge's outward conormal.
pub fn polygon_projection<const N: usize>(corners: [Vec3; N]) -> ShF {
    let basis = ZonalBasis::get();
    let v = corners.map(|c| c.normalize_or_zero());
    let inside: Vec3 = v.iter().copied().sum();
    // Per edge: its start a, the unit tangent u at a towards its end, the
    // outward conormal ν, its arc length Θ, sin Θ and cos Θ.
    let mut edges = [(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0f32, 0.0f32, 0.0f32); N];
    for i in 0..N {
        let (a, b) = (v[i], v[(i + 1) % N]);
        let m = crate::math::cross(a, b);
        let (s, c) = (m.length(), a.dot(b));
        if s.is_nan() || s <= 1e-12 {
            continue; // a degenerate edge bounds nothing
        }
        let m = m / s;
        let nu = if m.dot(inside) > 0.0 { -m } else { m };
        edges[i] = (a, (b - c * a) / s, nu, s.atan2(c), s, c);
    }
    // τ_0, the solid angle: a fan of triangles (Van Oosterom & Strackee 1983).
    let mut omega = 0.0f32;
    for i in 1..N.saturating_sub(1) {
        let (a, b, c) = (v[0], v[i], v[i + 1]);
        let det = a.dot(crate::math::cross(b, c)).abs();
        omega += 2.0 * det.atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a));
    }
    // The integral of the zonal harmonic P_l(w·ω) over P, by the moments.
    let zonal = |l: usize, w: Vec3| -> f32 {
        let (mut s0, mut s1, mut s2) = (0.0f32, 0.0f32, 0.0f32);
        for &(a, u, nu, theta, s, c) in &edges {
            let (alpha, beta, wn) = (w.dot(a), w.dot(u), w.dot(nu));
            s0 += wn * theta;
            s1 += wn * (alpha * s + beta * (1.0 - c));
            s2 += wn
                * (0.5 * (alpha * alpha + beta * beta) * theta
                    + 0.5 * (alpha * alpha - beta * beta) * s * c
                    + alpha * beta * s * s);
        }
        let t1 = -0.5 * s0;
        match l {
            0 => omega,
            1 => t1,
            // (3τ_2 − τ_0)/2 and (5τ_3 − 3τ_1)/2, simplified.
            2 => -0.5 * s1,
            _ => -0.25 * t1 - 0.625 * s2,
        }
    };
    let mut out = [0.0f32; COEFFS];
    for l in 0..BANDS {
        let q: [f32; 2 * BANDS - 1] = std::array::from_fn(|j| {
            if j <= 2 * l {
                zonal(l, basis.dirs[l][j])
            } else {
                0.0
            }
        });
        for m in 0..=2 * l {
            out[l * l + m] = (0..=2 * l).map(|j| basis.coef[l][m][j] * q[j]).sum();
        }
    }
    out
}

/// Per band l, 2l + 1 directions w_j and the matrix C with
/// Y_lm(ω) = Σ_j C[m][j] P_l(w_j·ω), from the addition theorem
/// P_l(w·ω) = 4π/(2l+1) Σ_m Y_lm(w) Y_lm(ω): C = (2l+1)/4π · A⁻¹, A_jm = Y_lm(w_j).
/// The directions are a golden-angle spiral over one hemisphere per band: over the
/// whole sphere, its points are near antipodes of each other, which odd bands
/// cannot tell apart (A singular). Condition numbers 1, 2.6, 3.8, 6.1.
struct ZonalBasis {
    dirs: [[Vec3; 2 * BANDS - 1]; BANDS],
    coef: [[[f32; 2 * BANDS - 1]; 2 * BANDS - 1]; BANDS],
}

impl ZonalBasis {
    fn get() -> &'static Self {
        static BASIS: std::sync::OnceLock<ZonalBasis> = std::sync::OnceLock::new();
        BASIS.get_or_init(Self::new)
    }

    fn directions(l: usize) -> Vec<DVec3> {
        let n = 2 * l + 1;
        (0..n)
            .map(|j| {
                let z = 1.0 - (j as f64 + 0.5) / (2 * n) as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = j as f64 * 2.399_963_229_728_653;
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect()
    }

    /// C of band l in f64 (`None` if A is singular).
    fn matrix(l: usize) -> Option<Vec<Vec<f64>>> {
        let n = 2 * l + 1;
        let a: Vec<Vec<f64>> = Self::directions(l)
            .iter()
            .map(|w| eval(*w)[l * l..l * l + n].to_vec())
            .collect();
        // A⁻¹ by Gauss–Jordan with partial pivoting; C[m][j] = (2l+1)/4π A⁻¹[m][j].
        let mut m: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let mut row = a[i].clone();
                row.extend((0..n).map(|k| f64::from(u8::from(k == i))));
                row
            })
            .collect();
        for col in 0..n {
            let piv = (col..n).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))?;
            if m[piv][col].abs() < 1e-9 {
                return None;
            }
            m.swap(col, piv);
            let p = m[col][col];
            m[col].iter_mut().for_each(|x| *x /= p);
            for r in 0..n {
                if r != col {
                    let f = m[r][col];
                    let pivot_row = m[col].clone();
                    m[r].iter_mut()
                        .zip(&pivot_row)
                        .for_each(|(x, y)| *x -= f * y);
                }
            }
        }
        let k = (2 * l + 1) as f64 / (4.0 * std::f64::consts::PI);
        Some(
            (0..n)
                .map(|i| m[i][n..].iter().map(|x| k * x).collect())
                .collect(),
        )
    }

    fn new() -> Self {
        let mut out = Self {
            dirs: [[Vec3::ZERO; 2 * BANDS - 1]; BANDS],
            coef: [[[0.0; 2 * BANDS - 1]; 2 * BANDS - 1]; BANDS],
        };
        for l in 0..BANDS {
            let c = Self::matrix(l).expect("the spiral's directions give an invertible basis");
            for (j, w) in Self::directions(l).iter().enumerate() {
                out.dirs[l][j] = w.as_vec3a();
            }
            for (m, row) in c.iter().enumerate() {
                for (j, x) in row.iter().enumerate() {
                    out.coef[l][m][j] = *x as f32;
                }
            }
        }
        out
    }
}

/// Value of the function with coefficients `c` in direction `d`.
pub fn eval_sum(c: &Sh, d: DVec3) -> f64 {
    dot(c, &eval(d))
}

pub fn dot(a: &Sh, b: &Sh) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub fn dot_f32(a: &ShF, b: &ShF) -> f32 {
    let mut s = 0.0;
    for i in 0..COEFFS {
        s += a[i] * b[i];
    }
    s
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n): exact for
/// polynomials of degree ≤ 2n − 1.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(n, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, d) = legendre_and_derivative(n, x);
        if d.is_finite() {
            dp = d;
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

/// A product rule on the sphere: Gauss–Legendre in z = cos θ times the trapezoid
/// rule in φ. Exact for polynomials of degree ≤ 2·n_z − 1 in z and trigonometric
/// degree < n_phi in φ, e.g. every product of three order-4 SH with (5, 10).
pub fn sphere_quadrature(n_z: usize, n_phi: usize) -> Vec<(DVec3, f64)> {
    let mut pts = Vec::with_capacity(n_z * n_phi);
    let w_phi = 2.0 * std::f64::consts::PI / n_phi as f64;
    for (z, w) in gauss_legendre(n_z) {
        let s = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * w_phi;
            pts.push((DVec3::new(s * phi.cos(), s * phi.sin(), z), w * w_phi));
        }
    }
    pts
}

/// Projects `f` onto the basis with the given quadrature.
pub fn project_with(f: impl Fn(DVec3) -> f64, rule: &[(DVec3, f64)]) -> Sh {
    let mut c = [0.0; COEFFS];
    for &(d, w) in rule {
        let v = f(d) * w;
        if v != 0.0 {
            let y = eval(d);
            for i in 0..COEFFS {
                c[i] += v * y[i];
            }
        }
    }
    c
}

/// Projects a smooth function (64 × 128 points; exact to degree 127 in z).
pub fn project(f: impl Fn(DVec3) -> f64) -> Sh {
    project_with(f, &sphere_quadrature(64, 128))
}

/// A zonal (axially symmetric) function around `axis` given its zonal coefficients
/// z_l (the coefficients of the same function around +z): c_lm = √(4π/(2l+1)) z_l Y_lm(axis).
pub fn zonal(axis: DVec3, z: [f64; BANDS]) -> Sh {
    let y = eval(axis.normalize());
    let mut c = [0.0; COEFFS];
    for (i, ci) in c.iter_mut().enumerate() {
        let l = band_of(i).0;
        *ci = (4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * z[l] * y[i];
    }
    c
}

/// max(n·ω, 0): zonal coefficients √π/2, √(π/3), √(5π)/8, 0 (l = 3 vanishes).
pub fn clamped_cosine(n: DVec3) -> Sh {
    let pi = std::f64::consts::PI;
    zonal(
        n,
        [
            pi.sqrt() / 2.0,
            (pi / 3.0).sqrt(),
            (5.0 * pi).sqrt() / 8.0,
            0.0,
        ],
    )
}

/// The indicator of the cap {ω : ω·axis ≥ cos α}: z_l = 2π √((2l+1)/4π) ∫_{cos α}^1 P_l.
pub fn cap(axis: DVec3, cos_alpha: f64) -> Sh {
    let x = cos_alpha.clamp(-1.0, 1.0);
    let p = [
        1.0,
        x,
        0.5 * (3.0 * x * x - 1.0),
        0.5 * (5.0 * x * x * x - 3.0 * x),
    ];
    let p4 = (35.0 * x.powi(4) - 30.0 * x * x + 3.0) / 8.0;
    let integral = [
        1.0 - x,
        (p[0] - p[2]) / 3.0,
        (p[1] - p[3]) / 5.0,
        (p[2] - p4) / 7.0,
    ];
    let mut z = [0.0; BANDS];
    for l in 0..BANDS {
        z[l] = 2.0
            * std::f64::consts::PI
            * ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI)).sqrt()
            * integral[l];
    }
    zonal(axis, z)
}

/// The constant function 1.
pub fn one() -> Sh {
    let mut c = [0.0; COEFFS];
    c[0] = (4.0 * std::f64::consts::PI).sqrt();
    c
}

/// Rotation of SH coefficients: for g(ω) = f(R⁻¹ω), `apply(f) = g`. Band matrices
/// from Ivanic & Ruedenberg (1996, with the 1998 errata): band 1 is the rotation
/// matrix itself in (y, z, x) order, band l follows from bands 1 and l − 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Rotation {
    /// Band l's (2l+1)² matrix, row-major, at offset l(4l² − 1)/3 (0, 1, 10, 35).
    m: [f64; 84],
}

const BAND_OFFSET: [usize; BANDS] = [0, 1, 10, 35];

impl Rotation {
    pub fn new(r: DMat3) -> Self {
        let mut rot = Self { m: [0.0; 84] };
        rot.m[0] = 1.0;
        // (y, z, x) ↔ m = −1, 0, 1. glam is column-major: r.col(j)[i] = R_ij.
        let axis = [1usize, 2, 0];
        for a in 0..3 {
            for b in 0..3 {
                rot.m[1 + 3 * a + b] = r.col(axis[b])[axis[a]];
            }
        }
        for l in 2..BANDS {
            rot.band_from_previous(l);
        }
        rot
    }

    /// Element (m, n) of band l, centred indices.
    fn get(&self, l: usize, m: i32, n: i32) -> f64 {
        let w = 2 * l + 1;
        self.m[BAND_OFFSET[l] + (m + l as i32) as usize * w + (n + l as i32) as usize]
    }

    /// Ivanic–Ruedenberg's P: band 1 times band l − 1.
    fn p(&self, i: i32, a: i32, b: i32, l: usize) -> f64 {
        let li = l as i32;
        if b == li {
            self.get(1, i, 1) * self.get(l - 1, a, li - 1)
                - self.get(1, i, -1) * self.get(l - 1, a, 1 - li)
        } else if b == -li {
            self.get(1, i, 1) * self.get(l - 1, a, 1 - li)
                + self.get(1, i, -1) * self.get(l - 1, a, li - 1)
        } else {
            self.get(1, i, 0) * self.get(l - 1, a, b)
        }
    }

    fn band_from_previous(&mut self, l: usize) {
        let li = l as i32;
        let w = 2 * l + 1;
        for m in -li..=li {
            for n in -li..=li {
                let d0 = f64::from(m == 0);
                let den = if n.abs() == li {
                    (2 * li * (2 * li - 1)) as f64
                } else {
                    ((li + n) * (li - n)) as f64
                };
                let am = m.abs();
                let u = (((li + m) * (li - m)) as f64 / den).sqrt();
                let v = 0.5
                    * ((1.0 + d0) * ((li + am - 1) * (li + am)) as f64 / den).sqrt()
                    * (1.0 - 2.0 * d0);
                let wc = -0.5 * (((li - am - 1) * (li - am)) as f64 / den).sqrt() * (1.0 - d0);
                let mut e = 0.0;
                if u != 0.0 {
                    e += u * self.p(0, m, n, l);
                }
                if v != 0.0 {
                    e += v * self.big_v(m, n, l);
                }
                if wc != 0.0 {
                    e += wc * self.big_w(m, n, l);
                }
                self.m[BAND_OFFSET[l] + (m + li) as usize * w + (n + li) as usize] = e;
            }
        }
    }

    fn big_v(&self, m: i32, n: i32, l: usize) -> f64 {
        let s2 = std::f64::consts::SQRT_2;
        match m {
            0 => self.p(1, 1, n, l) + self.p(-1, -1, n, l),
            1 => s2 * self.p(1, 0, n, l),
            -1 => s2 * self.p(-1, 0, n, l),
            m if m > 0 => self.p(1, m - 1, n, l) - self.p(-1, 1 - m, n, l),
            m => self.p(1, m + 1, n, l) + self.p(-1, -m - 1, n, l),
        }
    }

    fn big_w(&self, m: i32, n: i32, l: usize) -> f64 {
        if m > 0 {
            self.p(1, m + 1, n, l) + self.p(-1, -m - 1, n, l)
        } else {
            self.p(1, m - 1, n, l) - self.p(-1, 1 - m, n, l)
        }
    }

    /// Rotated coefficients.
    pub fn apply(&self, c: &Sh) -> Sh {
        let mut out = [0.0; COEFFS];
        for l in 0..BANDS {
            let (w, first) = (2 * l + 1, l * l);
            for a in 0..w {
                let row = &self.m[BAND_OFFSET[l] + a * w..BAND_OFFSET[l] + (a + 1) * w];
                out[first + a] = row
                    .iter()
                    .zip(&c[first..first + w])
                    .map(|(r, x)| r * x)
                    .sum();
            }
        }
        out
    }

    /// [`Rotation::apply`] on f32 coefficients.
    pub fn apply_f32(&self, c: &ShF) -> ShF {
        self.apply(&c.map(f64::from)).map(|x| x as f32)
    }

    /// The dense 16 × 16 matrix (block diagonal), row-major.
    pub fn matrix(&self) -> [[f64; COEFFS]; COEFFS] {
        let mut out = [[0.0; COEFFS]; COEFFS];
        for l in 0..BANDS {
            let (w, first) = (2 * l + 1, l * l);
            for a in 0..w {
                for b in 0..w {
                    out[first + a][first + b] = self.m[BAND_OFFSET[l] + a * w + b];
                }
            }
        }
        out
    }
}

/// One non-zero entry C_ijk = ∫ Y_i Y_j Y_k dω of the triple-product tensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TripleEntry {
    pub i: usize,
    pub j: usize,
    pub k: usize,
    pub value: f64,
}

/// Every non-zero C_ijk (ordered indices), by exact quadrature (degree ≤ 9).
pub fn triple_tensor() -> Vec<TripleEntry> {
    let rule = sphere_quadrature(8, 16);
    let ys: Vec<(Sh, f64)> = rule.iter().map(|&(d, w)| (eval(d), w)).collect();
    let mut out = Vec::new();
    for i in 0..COEFFS {
        for j in 0..COEFFS {
            for k in 0..COEFFS {
                let value: f64 = ys.iter().map(|(y, w)| w * y[i] * y[j] * y[k]).sum();
                if value.abs() > 1e-12 {
                    out.push(TripleEntry { i, j, k, value });
                }
            }
        }
    }
    out
}

/// The order-4 projection of the product of two order-4 functions, by a generic
/// loop over the sparse tensor: the reference the generated [`product`] is tested
/// and benchmarked against.
pub fn product_sparse(a: &Sh, b: &Sh, tensor: &[TripleEntry]) -> Sh {
    let mut c = [0.0; COEFFS];
    for e in tensor {
        c[e.k] += e.value * a[e.i] * b[e.j];
    }
    c
}

/// Rust source of `sh/product.rs`: for each output k, the unordered pairs (i ≤ j)
/// with C_ijk ≠ 0; each pair's symmetric product a_i b_j + a_j b_i is formed once
/// and shared by every k it feeds. `tests/sh.rs` checks the file is this text.
pub fn product_source() -> String {
    let tensor = triple_tensor();
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    let mut terms: Vec<Vec<(usize, f64)>> = vec![Vec::new(); COEFFS];
    for e in tensor.iter().filter(|e| e.i <= e.j) {
        let p = match pairs.iter().position(|&q| q == (e.i, e.j)) {
            Some(p) => p,
            None => {
                pairs.push((e.i, e.j));
                pairs.len() - 1
            }
        };
        terms[e.k].push((p, e.value));
    }
    let mut s = String::from(
        "//! Generated by `crate::math::sh::product_source()` from the triple-product tensor;\n\
         //! do not edit (`GRADTRACE_REGENERATE=1 cargo test --release --test sh` rewrites it).\n\n",
    );
    for (name, ty) in [("product", "f32"), ("product_f64", "f64")] {
        s += &format!(
            "/// Order-4 projection of the product of two order-4 functions ({} pairs, {} terms).\n\
             #[rustfmt::skip]\n#[allow(clippy::all)]\n\
             pub fn {name}(a: &[{ty}; 16], b: &[{ty}; 16]) -> [{ty}; 16] {{\n",
            pairs.len(),
            terms.iter().map(Vec::len).sum::<usize>()
        );
        for (p, &(i, j)) in pairs.iter().enumerate() {
            if i == j {
                s += &format!("    let p{p} = a[{i}] * b[{i}];\n");
            } else {
                s += &format!("    let p{p} = a[{i}] * b[{j}] + a[{j}] * b[{i}];\n");
            }
        }
        s += "    [\n";
        for t in &terms {
            let body: Vec<String> = t
                .iter()
                .map(|&(p, v)| {
                    if ty == "f32" {
                        format!("{:?} * p{p}", v as f32)
                    } else {
                        format!("{v:?} * p{p}")
                    }
                })
                .collect();
            s += &format!("        {},\n", body.join(" + "));
        }
        s += "    ]\n}\n\n";
    }
    s.pop();
    s
}
