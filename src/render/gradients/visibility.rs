//! Soft-shadow (visibility) gradients, Sec. 6–8 of the first-order paper.
//!
//! Direct light from one source is written in polar coordinates around an axis a:
//! B = ∫_φ ∫_0^{θmax(φ)} T(ω) V(x, ω) sin θ dθ dφ. For a fixed φ the visibility
//! along θ is a step function whose jumps α_j are where a ray grazes a blocker.
//! Moving x by δ moves each jump by dα_j (Eq. 44–46 for curved blockers, Eq. 72
//! for polygon edges), giving the visibility part of the gradient (Eq. 48–49):
//! ∂B = ∫_φ Σ_j sgn_j T(α_j) sin α_j dα_j dφ.
//!
//! Image-space ("semianalytic") method: one φ-line per camera sample, with
//! `n_theta` stratified shadow rays along θ. The same rays estimate the radiance
//! (a line estimator of B) and locate the jumps, so the gradient needs no extra
//! rays. A jump is placed between the two samples that differ (optionally refined
//! by bisection); the blocked sample's hit gives the blocker distance D_j and its
//! geometry (sphere normal, or the nearest triangle edge k for Eq. 72).
//!
//! Beyond the paper, the domain can be the cone of a sphere light or the solid
//! angle of a rectangular light, not only the hemisphere of an environment, so
//! soft shadows of local lights carry visibility gradients too.

use crate::accel::{Accel, PrimRef};
use crate::math::{Frame, Ray, Vec3};
use crate::render::interaction::offset_origin;
use crate::scene::Scene;
use std::f32::consts::TAU;

/// The angular domain of one light as seen from the shading point.
#[derive(Clone, Copy, Debug)]
pub enum Domain {
    /// θ ∈ [0, θmax] around `frame.n`, the same bound for every φ (hemisphere of
    /// an environment, cone of a sphere light). `light_dist` is `Some(sphere)` when
    /// rays must stop at a sphere light (centre, radius).
    Cone {
        frame: Frame,
        theta_max: f32,
        sphere: Option<(Vec3, f32)>,
    },
    /// A rectangle light (corner, edge_u, edge_v) whose centre direction is the
    /// axis; θmax(φ) is where the ray leaves the rectangle.
    Rect {
        frame: Frame,
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
    },
}

/// A blocker's hit distance and primitive, when a probe ray is blocked.
type BlockerHit = Option<(f32, PrimRef)>;

/// Result of one φ-line.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineEstimate {
    /// Visibility term of the gradient along the two image-space displacements.
    pub vis: [Vec3; 2],
    pub rays: u32,
    /// Number of visibility jumps found on the line.
    pub jumps: u32,
}

/// One sample point of a line, handed to the caller's transport.
#[derive(Clone, Copy, Debug)]
pub struct LinePoint {
    pub wi: Vec3,
    /// Solid-angle density of this point under the line sampling (φ uniform,
    /// θ stratified with `n_theta` strata): 1 / (2π · sin θ · θmax/n).
    pub pdf: f32,
    /// Point on the light and its normal, for area lights.
    pub light_point: Option<(Vec3, Vec3)>,
    pub visible: bool,
}

/// Marches one φ-line: casts `n_theta` shadow rays, reports each point (with its
/// visibility) to `on_point`, and returns the visibility gradient for the two
/// displacements `dx` of the shading point. `transport(ω)` is T: the integrand of
/// B in solid angle (L · f · cos), evaluated at jump directions.
#[allow(clippy::too_many_arguments)]
pub fn trace_line(
    scene: &Scene,
    accel: &Accel,
    x: Vec3,
    ng: Vec3,
    domain: &Domain,
    phi: f32,
    theta_jitter: f32,
    n_theta: u32,
    refine_steps: u32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
    on_point: &mut dyn FnMut(&LinePoint),
) -> LineEstimate {
    let frame = match domain {
        Domain::Cone { frame, .. } | Domain::Rect { frame, .. } => *frame,
    };
    let (sp, cp) = phi.sin_cos();
    let dphi = frame.s * cp + frame.t * sp;
    let dir = |theta: f32| {
        let (st, ct) = theta.sin_cos();
        frame.n * ct + dphi * st
    };
    let theta_max = match *domain {
        Domain::Cone { theta_max, .. } => theta_max,
        Domain::Rect {
            corner,
            edge_u,
            edge_v,
            ..
        } => rect_exit_angle(x, frame.n, dphi, corner, edge_u, edge_v),
    };
    let mut out = LineEstimate::default();
    if theta_max.is_nan() || theta_max <= 0.0 {
        return out;
    }
    let step = theta_max / n_theta as f32;
    // Probe one direction: visible?, and the point on the light. An any-hit
    // query suffices; the blocker itself is only looked up at jumps.
    let shadow_ray = |theta: f32| -> Option<(Ray, Option<(Vec3, Vec3)>)> {
        let w = dir(theta);
        let (t_max, lp) = light_extent(domain, x, w);
        // Below the geometric horizon the receiver itself blocks.
        if t_max <= 0.0 || w.dot(ng) <= 0.0 {
            return None;
        }
        // The segment must end short of the light as seen from the offset origin,
        // not from x: the offset moves the origin toward the light.
        let o = offset_origin(x, ng, w);
        let t_o = light_extent(domain, o, w).0;
        Some((Ray::segment(o, w, t_o * (1.0 - 1e-4)), lp))
    };
    let probe = |theta: f32| -> (bool, Option<(Vec3, Vec3)>) {
        match shadow_ray(theta) {
            Some((ray, lp)) => (!accel.occluded(&ray), lp),
            None => (false, None),
        }
    };
    let blocker = |theta: f32| -> BlockerHit {
        let (ray, _) = shadow_ray(theta)?;
        accel.intersect(&ray).map(|h| (h.t, h.prim))
    };
    // (θ, visible) of the previous sample on the line.
    let mut prev: Option<(f32, bool)> = None;
    for i in 0..n_theta {
        let theta = (i as f32 + theta_jitter) * step;
        let (visible, lp) = probe(theta);
        out.rays += 1;
        let (st, _) = theta.sin_cos();
        let pdf = 1.0 / (TAU * st.max(1e-12) * step);
        on_point(&LinePoint {
            wi: dir(theta),
            pdf,
            light_point: lp,
            visible,
        });
        if let Some((theta0, vis0)) = prev {
            if vis0 != visible {
                // Locate the jump: midpoint, refined by bisection if asked.
                let (mut lo, mut hi) = (theta0, theta);
                for _ in 0..refine_steps {
                    let mid = 0.5 * (lo + hi);
                    let (v, _) = probe(mid);
                    out.rays += 1;
                    if v == vis0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let alpha = 0.5 * (lo + hi);
                // Visible below the jump and blocked above: the visible region grows
                // with α (sgn = +1); the opposite transition has sgn = −1 (Fig. 8).
                let sgn = if vis0 { 1.0 } else { -1.0 };
                // The blocker: closest hit on the blocked side, next to the jump.
                out.rays += 1;
                if let Some((t, prim)) = blocker(if vis0 { hi } else { lo }) {
                    let w = dir(alpha);
                    let (sa, ca) = alpha.sin_cos();
                    let c = frame.n * (-sa) + dphi * ca;
                    if let Some((dalpha, d)) = jump_derivatives(scene, x, w, c, t, prim, dx) {
                        // Parallax of a local light: the points of the light seen along
                        // the jump also move (by the same formula at their distance R),
                        // and the shading terms already hold them fixed, so only the
                        // relative motion counts: dα (1 − D/R). R = ∞ for the
                        // environment (Eq. 49 as printed).
                        let r = light_extent(domain, x, w).0;
                        let parallax = if r.is_finite() && r > 0.0 {
                            (1.0 - d / r).max(0.0)
                        } else {
                            1.0
                        };
                        let tr = transport(w);
                        // Integrated over φ with density 1/2π: weight 2π.
                        for (v, da) in out.vis.iter_mut().zip(dalpha) {
                            *v += tr * (sgn * sa * da * parallax * TAU);
                        }
                        out.jumps += 1;
                    }
                }
            }
        }
        prev = Some((theta, visible));
    }
    out
}

/// dα/dδ for the two displacements δ = dx[k] of the shading point, for a jump
/// along the tangent ray `w` whose transverse direction (∂ω/∂θ) is `c`, and the
/// distance D to the grazing point.
///
/// The grazing point p = x + D w stays on the blocker: for a curved blocker on its
/// tangent plane (Eq. 43–46), for a polygon on its silhouette edge k (Eq. 72).
/// Both are the same solve with k = the silhouette's tangent: writing
/// dp = D dα c + dD w + δ = s k and taking components along c and the line
/// plane's normal v gives s = (δ·v)/(k·v) and dα = (s (k·c) − δ·c) / D
/// (δ in the line plane: dα = −cos α / D, Eq. 45; out of it: Eq. 46/72).
fn jump_derivatives(
    scene: &Scene,
    x: Vec3,
    w: Vec3,
    c: Vec3,
    t_hit: f32,
    prim: PrimRef,
    dx: [Vec3; 2],
) -> Option<([f32; 2], f32)> {
    let (d, k) = match prim {
        PrimRef::Sphere(i) => {
            let s = &scene.spheres[i as usize];
            // Grazing point: the ray's closest approach to the centre.
            let d = (s.center - x).dot(w);
            let p = x + w * d;
            let n = (p - s.center).normalize_or_zero();
            (d, n.cross(w).normalize_or_zero())
        }
        PrimRef::Triangle { mesh, tri } => {
            let m = &scene.meshes[mesh as usize];
            let v = m.triangles[tri as usize].map(|i| m.positions[i as usize]);
            // The silhouette edge: the triangle edge nearest to the grazing ray.
            let mut best = (f32::INFINITY, Vec3::ZERO, t_hit);
            for e in 0..3 {
                let (a, b) = (v[e], v[(e + 1) % 3]);
                let k = (b - a).normalize_or_zero();
                let (dist, tk) = ray_line_distance(x, w, a, k);
                if dist < best.0 {
                    best = (dist, k, tk);
                }
            }
            (best.2, best.1)
        }
    };
    if d.is_nan() || d <= 0.0 || k == Vec3::ZERO {
        return None;
    }
    let v = w.cross(c);
    let kv = k.dot(v);
    if kv.abs() < 1e-4 {
        // The silhouette lies in the line's plane: the jump slides along the
        // line and its derivative is unbounded (a degenerate configuration,
        // footnote 3 of the paper); it contributes nothing measurable.
        return None;
    }
    let kc = k.dot(c);
    let r = dx.map(|delta| {
        let s = delta.dot(v) / kv;
        (s * kc - delta.dot(c)) / d
    });
    (r[0].is_finite() && r[1].is_finite()).then_some((r, d))
}

/// Distance between the ray x + t w and the line a + s k, and the ray parameter
/// of the closest approach.
fn ray_line_distance(x: Vec3, w: Vec3, a: Vec3, k: Vec3) -> (f32, f32) {
    let n = w.cross(k);
    let nn = n.length_squared();
    if nn < 1e-12 {
        let t = (a - x).dot(w);
        return (((a - x) - w * t).length(), t);
    }
    let r = a - x;
    let dist = r.dot(n).abs() / nn.sqrt();
    // t = ((a − x) × k) · n / |n|²
    let t = r.cross(k).dot(n) / nn;
    (dist, t)
}

/// How far a shadow ray along `w` may go before it reaches the light, and the
/// point it reaches (none for the environment).
fn light_extent(domain: &Domain, x: Vec3, w: Vec3) -> (f32, Option<(Vec3, Vec3)>) {
    match *domain {
        Domain::Cone { sphere: None, .. } => (f32::INFINITY, None),
        Domain::Cone {
            sphere: Some((c, r)),
            ..
        } => {
            let oc = c - x;
            let b = oc.dot(w);
            let disc = r * r - (oc - b * w).length_squared();
            if disc < 0.0 {
                // Grazing the light's rim within rounding: take the tangent point.
                let p = x + w * b;
                return (b, Some((p, (p - c).normalize_or_zero())));
            }
            let t = b - disc.sqrt();
            let p = x + w * t;
            (t, Some((p, (p - c).normalize_or_zero())))
        }
        Domain::Rect {
            corner,
            edge_u,
            edge_v,
            ..
        } => {
            let n = edge_u.cross(edge_v).normalize();
            let denom = w.dot(n);
            if denom.abs() < 1e-12 {
                return (0.0, None);
            }
            let t = (corner - x).dot(n) / denom;
            (t, Some((x + w * t, n)))
        }
    }
}

/// θ at which the line's ray leaves the rectangle. The line's directions
/// cos θ a + sin θ d (a = `axis`, aimed at the rectangle's centre) sweep a plane,
/// which cuts the rectangle's plane along a straight line through the centre; the
/// exit is where that line leaves the (convex) rectangle, found in its edge
/// coordinates, and θmax is the angle between the axis and the exit point.
fn rect_exit_angle(x: Vec3, axis: Vec3, d: Vec3, corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> f32 {
    let n = edge_u.cross(edge_v);
    let centre = corner + 0.5 * (edge_u + edge_v);
    // Direction of the cut, oriented the way growing θ moves the hit point.
    let mut m = n.cross(axis.cross(d));
    if m.dot(d) < 0.0 {
        m = -m;
    }
    // Coordinates of m in the (possibly skewed) edge basis.
    let (uu, uv, vv) = (
        edge_u.length_squared(),
        edge_u.dot(edge_v),
        edge_v.length_squared(),
    );
    let det = uu * vv - uv * uv;
    if det.abs() < 1e-20 || m == Vec3::ZERO {
        return 0.0;
    }
    let (mu, mv) = (m.dot(edge_u), m.dot(edge_v));
    let coords = [(vv * mu - uv * mv) / det, (uu * mv - uv * mu) / det];
    // The centre is at (½, ½): leave through the nearer side along m.
    let mut s_exit = f32::INFINITY;
    for c in coords {
        if c.abs() > 1e-12 {
            s_exit = s_exit.min(0.5 / c.abs());
        }
    }
    if !s_exit.is_finite() {
        return 0.0;
    }
    let to_exit = centre + m * s_exit - x;
    let cos = to_exit.dot(axis);
    let sin = to_exit.cross(axis).length();
    sin.atan2(cos)
}

/// The object-space analytic method for sphere blockers (Sec. 8.1): on the
/// plane of one φ-line each sphere cuts a circle, which blocks the θ-interval
/// θ_c ± asin(r'/d'); the intervals of all spheres are merged (overlapping
/// blockers give one jump at each end of their union, not two each), and each
/// remaining jump gets its exact α, tangent distance D and blocker normal.
/// Computed in f64: near-tangent planes cancel catastrophically in f32.
///
/// Returns the visibility gradient for the displacements `dx` and the visible
/// measure ∫_visible sin θ dθ of the line (so B = 2π · mean over φ of it when
/// T = 1, Eq. 47), with no rays traced.
pub fn object_space_line(
    spheres: &[crate::scene::Sphere],
    x: Vec3,
    frame: &Frame,
    theta_max: f32,
    phi: f32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
) -> (LineEstimate, f32) {
    object_space_line_f64(spheres, x, frame, theta_max, phi as f64, dx, transport)
}

/// [`object_space_line`] with φ in f64: quadrature nodes next to a tangent φ sit
/// closer to it than an f32 can resolve.
fn object_space_line_f64(
    spheres: &[crate::scene::Sphere],
    x: Vec3,
    frame: &Frame,
    theta_max: f32,
    phi: f64,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
) -> (LineEstimate, f32) {
    use glam::DVec3;
    let (sp, cp) = phi.sin_cos();
    let a = frame.n.as_dvec3();
    let dphi = frame.s.as_dvec3() * cp + frame.t.as_dvec3() * sp;
    let v = a.cross(dphi);
    let xd = x.as_dvec3();
    let theta_max = theta_max as f64;
    // (start, end, sphere index) of each blocked θ-interval on this line.
    let mut intervals: Vec<(f64, f64, usize)> = Vec::new();
    for (i, s) in spheres.iter().enumerate() {
        let (c, r) = (s.center.as_dvec3(), s.radius as f64);
        let h = (c - xd).dot(v);
        if h.abs() >= r {
            continue;
        }
        let c2 = c - v * h;
        let r2 = ((r - h) * (r + h)).sqrt();
        let q = c2 - xd;
        let d2 = q.length();
        if d2 <= r2 {
            continue;
        }
        let theta_c = q.dot(dphi).atan2(q.dot(a));
        let beta = (r2 / d2).asin();
        let (lo, hi) = ((theta_c - beta).max(0.0), (theta_c + beta).min(theta_max));
        if lo < hi {
            intervals.push((lo, hi, i));
        }
    }
    intervals.sort_by(|p, q| p.0.total_cmp(&q.0));
    // Union of the intervals, remembering which sphere owns each end.
    let mut merged: Vec<(f64, usize, f64, usize)> = Vec::new();
    for (lo, hi, i) in intervals {
        match merged.last_mut() {
            Some(last) if lo <= last.2 => {
                if hi > last.2 {
                    last.2 = hi;
                    last.3 = i;
                }
            }
            _ => merged.push((lo, i, hi, i)),
        }
    }
    let mut est = LineEstimate::default();
    let mut blocked = 0.0f64;
    let jump = |alpha: f64, sphere: usize, sgn: f64, est: &mut LineEstimate| {
        // Jumps at the ends of the line's domain are the domain's own boundary.
        if alpha <= 0.0 || alpha >= theta_max {
            return;
        }
        let s = &spheres[sphere];
        let (c, sa, ca) = (s.center.as_dvec3(), alpha.sin(), alpha.cos());
        let w = a * ca + dphi * sa;
        let cdir = a * (-sa) + dphi * ca;
        let d = (c - xd).dot(w);
        let p = xd + w * d;
        let n = (p - c).normalize_or_zero();
        let k = n.cross(w).normalize_or_zero();
        let vv = w.cross(cdir);
        let kv = k.dot(vv);
        if kv.abs() < 1e-9 || d <= 0.0 {
            return;
        }
        let tr = transport(w.as_vec3());
        for (j, delta) in dx.iter().enumerate() {
            let delta: DVec3 = delta.as_dvec3();
            let s_k = delta.dot(vv) / kv;
            let dalpha = (s_k * k.dot(cdir) - delta.dot(cdir)) / d;
            est.vis[j] += tr * (sgn * sa * dalpha * std::f64::consts::TAU) as f32;
        }
        est.jumps += 1;
    };
    for &(lo, i_lo, hi, i_hi) in &merged {
        blocked += lo.cos() - hi.cos();
        jump(lo, i_lo, 1.0, &mut est);
        jump(hi, i_hi, -1.0, &mut est);
    }
    (est, ((1.0 - theta_max.cos()) - blocked) as f32)
}

/// The φ values where a line's plane is tangent to one of the spheres: there the
/// jump derivatives have their integrable (φ − φ0)^(−1/2) spikes (footnote 4).
/// Known in closed form for spheres: the plane's signed distance to the centre is
/// ρ cos(φ + ψ), equal to ±R at φ = −ψ ± acos(R/ρ) and π − ψ ± acos(R/ρ).
pub fn sphere_tangent_phis(spheres: &[crate::scene::Sphere], x: Vec3, frame: &Frame) -> Vec<f64> {
    let mut out = Vec::new();
    for s in spheres {
        let q = (s.center - x).as_dvec3();
        let (qs, qt) = (q.dot(frame.s.as_dvec3()), q.dot(frame.t.as_dvec3()));
        let rho = qs.hypot(qt);
        let r = s.radius as f64;
        if rho <= r {
            continue;
        }
        let psi = qs.atan2(qt);
        let a = (r / rho).acos();
        for base in [0.0, std::f64::consts::PI] {
            for sgn in [-1.0, 1.0] {
                out.push((base - psi + sgn * a).rem_euclid(std::f64::consts::TAU));
            }
        }
    }
    out.sort_by(|a, b| a.total_cmp(b));
    out
}

/// The object-space visibility gradient at x integrated over φ to high accuracy:
/// the circle is split at the tangent φ of every sphere and each piece is
/// integrated by Gauss–Legendre after the substitution φ = φa + (φb − φa)(1 − cos τ)/2,
/// whose Jacobian sin τ cancels the inverse-square-root spikes at both ends.
/// Returns (gradient pair, unblocked measure B of Eq. 47 times T = 1 weights).
pub fn object_space_gradient(
    spheres: &[crate::scene::Sphere],
    x: Vec3,
    frame: &Frame,
    theta_max: f32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
) -> ([Vec3; 2], f32) {
    let mut cuts = sphere_tangent_phis(spheres, x, frame);
    cuts.insert(0, 0.0);
    cuts.push(std::f64::consts::TAU);
    let (nodes, weights) = gauss_legendre_16();
    let mut g = [glam::DVec3::ZERO; 2];
    let mut b = 0.0f64;
    for w in cuts.windows(2) {
        let (pa, pb) = (w[0], w[1]);
        if pb - pa <= 1e-12 {
            continue;
        }
        // Composite over τ panels: the integrand also jumps where the sphere that
        // bounds a merged interval changes, which one Gauss rule would smear.
        const PANELS: usize = 24;
        for panel in 0..PANELS {
            let (ta, tb) = (
                std::f64::consts::PI * panel as f64 / PANELS as f64,
                std::f64::consts::PI * (panel + 1) as f64 / PANELS as f64,
            );
            for (&t, &wt) in nodes.iter().zip(&weights) {
                let tau = ta + (tb - ta) * 0.5 * (t + 1.0);
                let phi = pa + (pb - pa) * 0.5 * (1.0 - tau.cos());
                let jac = (pb - pa) * 0.5 * tau.sin() * 0.5 * (tb - ta);
                let (est, vis) =
                    object_space_line_f64(spheres, x, frame, theta_max, phi, dx, transport);
                for (gk, v) in g.iter_mut().zip(est.vis) {
                    *gk += v.as_dvec3() * (wt * jac);
                }
                b += vis as f64 * wt * jac;
            }
        }
    }
    let inv = 1.0 / std::f64::consts::TAU;
    ([(g[0] * inv).as_vec3(), (g[1] * inv).as_vec3()], b as f32)
}

/// 16-point Gauss–Legendre nodes and weights on [−1, 1].
fn gauss_legendre_16() -> ([f64; 16], [f64; 16]) {
    const X: [f64; 8] = [
        0.0950125098376374,
        0.2816035507792589,
        0.4580167776572274,
        0.6178762444026438,
        0.755404408355003,
        0.8656312023878318,
        0.9445750230732326,
        0.9894009349916499,
    ];
    const W: [f64; 8] = [
        0.1894506104550685,
        0.1826034150449236,
        0.1691565193950025,
        0.1495959888165767,
        0.1246289712555339,
        0.0951585116824928,
        0.0622535239386479,
        0.0271524594117541,
    ];
    let mut x = [0.0; 16];
    let mut w = [0.0; 16];
    for i in 0..8 {
        x[2 * i] = -X[i];
        x[2 * i + 1] = X[i];
        w[2 * i] = W[i];
        w[2 * i + 1] = W[i];
    }
    (x, w)
}

/// Integrates a per-φ quantity (a visibility gradient pair) over φ ∈ [0, 2π) by
/// adaptive Simpson quadrature. The integrand has integrable (φ − φ0)^(−1/2)
/// spikes where a line's plane is tangent to a blocker (footnote 4 of the paper);
/// adaptive subdivision concentrates evaluations there instead of refining the
/// whole circle. Returns the integral divided by 2π (the mean over φ, matching
/// the 2π weight already inside each line's value) and the evaluation count.
pub fn integrate_phi_adaptive(
    f: &mut dyn FnMut(f32) -> [Vec3; 2],
    initial: u32,
    tol: f32,
    max_depth: u32,
) -> ([Vec3; 2], u32) {
    fn add(a: [Vec3; 2], b: [Vec3; 2], s: f32) -> [Vec3; 2] {
        [a[0] + b[0] * s, a[1] + b[1] * s]
    }
    fn norm(a: [Vec3; 2]) -> f32 {
        a[0].abs().max_element().max(a[1].abs().max_element())
    }
    #[allow(clippy::too_many_arguments)]
    fn simpson(
        f: &mut dyn FnMut(f32) -> [Vec3; 2],
        a: f32,
        b: f32,
        fa: [Vec3; 2],
        fm: [Vec3; 2],
        fb: [Vec3; 2],
        whole: [Vec3; 2],
        tol: f32,
        depth: u32,
        evals: &mut u32,
    ) -> [Vec3; 2] {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        *evals += 2;
        let h = (b - a) / 12.0;
        let left = add(add(fa, fm, 1.0), flm, 4.0).map(|v| v * h);
        let right = add(add(fm, fb, 1.0), frm, 4.0).map(|v| v * h);
        let both = add(left, right, 1.0);
        let err = norm(add(both, whole, -1.0));
        if depth == 0 || err <= 15.0 * tol {
            // Richardson extrapolation of the two Simpson estimates.
            return add(both, add(both, whole, -1.0), 1.0 / 15.0);
        }
        let l = simpson(f, a, m, fa, flm, fm, left, tol * 0.5, depth - 1, evals);
        let r = simpson(f, m, b, fm, frm, fb, right, tol * 0.5, depth - 1, evals);
        add(l, r, 1.0)
    }
    let n = initial.max(2);
    let step = TAU / n as f32;
    let mut evals = 0u32;
    let mut total = [Vec3::ZERO; 2];
    let mut f0 = f(0.0);
    evals += 1;
    let first = f0;
    for i in 0..n {
        let (a, b) = (i as f32 * step, (i + 1) as f32 * step);
        let fm = f(0.5 * (a + b));
        let fb = if i + 1 == n { first } else { f(b) };
        evals += 1 + (i + 1 != n) as u32;
        let whole = add(add(f0, fb, 1.0), fm, 4.0).map(|v| v * (step / 6.0));
        let part = simpson(
            f,
            a,
            b,
            f0,
            fm,
            fb,
            whole,
            tol / n as f32,
            max_depth,
            &mut evals,
        );
        total = add(total, part, 1.0);
        f0 = fb;
    }
    (total.map(|v| v / TAU), evals)
}

/// Whether anything in the scene can shadow a point of the scene. A single convex
/// object (sphere or flat quad) lit by a single light source cannot: its own
/// far side is below every point's horizon. Then the visibility term is zero
/// everywhere (the paper's Fig. 4 case "no occluders") and line sampling, which
/// exists to find visibility jumps, is skipped.
pub fn scene_can_cast_shadows(scene: &Scene) -> bool {
    use glam::Vec3 as V;
    let objects: Vec<bool> = scene
        .meshes
        .iter()
        .filter(|m| m.emission == V::ZERO)
        .map(|m| m.rect.is_some())
        .chain(
            scene
                .spheres
                .iter()
                .filter(|s| s.emission == V::ZERO)
                .map(|_| true),
        )
        .collect();
    let sources = scene.emitter_count() + scene.environment.is_some() as usize;
    !(objects.len() <= 1 && objects.iter().all(|&convex| convex) && sources <= 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The analytic exit angle agrees with a bisection on ray/rectangle hits.
    #[test]
    fn rect_exit_angle_matches_bisection() {
        let (corner, eu, ev) = (
            Vec3::new(-0.7, 2.0, -0.4),
            Vec3::new(1.3, 0.1, 0.0),
            Vec3::new(0.2, 0.0, 0.9),
        );
        for x in [
            Vec3::new(0.3, 0.0, 0.2),
            Vec3::new(2.8, 0.0, 2.5),
            Vec3::new(-2.0, 0.5, 0.1),
        ] {
            let centre = corner + 0.5 * (eu + ev);
            let frame = Frame::from_normal((centre - x).normalize());
            let inside = |w: Vec3| {
                let n = eu.cross(ev);
                let t = (corner - x).dot(n) / w.dot(n);
                let q = x + w * t - corner;
                let (uu, uv, vv) = (eu.length_squared(), eu.dot(ev), ev.length_squared());
                let det = uu * vv - uv * uv;
                let a = (vv * q.dot(eu) - uv * q.dot(ev)) / det;
                let b = (uu * q.dot(ev) - uv * q.dot(eu)) / det;
                t > 0.0 && (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)
            };
            for k in 0..32 {
                let phi = k as f32 / 32.0 * TAU;
                let d = frame.s * phi.cos() + frame.t * phi.sin();
                let (mut lo, mut hi) = (0.0f32, 1.5f32);
                for _ in 0..50 {
                    let mid = 0.5 * (lo + hi);
                    if inside(frame.n * mid.cos() + d * mid.sin()) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let analytic = rect_exit_angle(x, frame.n, d, corner, eu, ev);
                assert!(
                    (analytic - lo).abs() < 1e-4,
                    "x {x} φ {phi}: {analytic} vs {lo}"
                );
            }
        }
    }
}
