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
//! `n_theta` stratified shadow rays along θ, locates the jumps (the tests also
//! read its rays as a line estimator of B; the renderer takes the radiance from
//! its light sample, [`trace_gated`]). A jump is placed between the two samples
//! that differ (optionally refined by bisection); the blocked sample's hit gives the blocker distance D_j and its
//! geometry (sphere normal, or the nearest triangle edge k for Eq. 72).
//!
//! Beyond the paper, the domain can be the cone of a sphere light or the solid
//! angle of a rectangular light, not only the hemisphere of an environment, so
//! soft shadows of local lights carry visibility gradients too.
//!
//! A silhouette lying in a plane through the axis (a vertical blocker edge under
//! the sky) is parallel to every φ-line and never a θ-jump: Eq. 48 alone misses
//! it. The renderer therefore also marches a ring at fixed θ per camera sample,
//! whose φ-jumps see that boundary squarely, and combines the two families by the
//! balance heuristic on their crossing densities ([`trace_line_and_ring`]).

use super::sphere_light::{cone_flow, ConeLaw};
use crate::accel::{offset_ray_origin_with_error, Accel, PrimRef, SurfacePoint};
use crate::math::quadrature::GaussLegendre;
use crate::math::{cross, Frame, Ray, Vec3};
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
///
/// This is Eq. 48 as printed, the θ-jumps of one line alone: an edge lying in a
/// plane through the axis never shows up as a θ-jump and is missed (see
/// [`trace_line_and_ring`], which the renderer uses). Kept for the tests that
/// integrate single lines over φ against closed forms.
#[allow(clippy::too_many_arguments)]
pub fn trace_line(
    scene: &Scene,
    accel: &Accel,
    at: SurfacePoint,
    domain: &Domain,
    phi: f32,
    theta_jitter: f32,
    n_theta: u32,
    refine_steps: u32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
    on_point: &mut dyn FnMut(&LinePoint),
) -> LineEstimate {
    let m = Marcher::new(scene, accel, at, domain, refine_steps, dx, transport);
    m.line(phi, theta_jitter, n_theta, Families::Line, on_point)
}

/// One φ-line (as [`trace_line`], its points reported to `on_point`) plus one ring
/// of shadow rays at fixed θ_r (`ring_rays` of them), whose φ-jumps are the same boundary seen
/// in the other parametrisation (Eq. 48 with θ and φ exchanged:
/// ∂B = ∫_θ Σ_j sgn_j T sin θ ∂φ_j dθ). Both estimate one boundary integral,
/// ∂B = −∮ σ T v_n ds over the blockers' silhouettes on the sphere of directions
/// (v_n: the silhouette's normal velocity, σ = +1 where the visible side is along
/// its normal), and each crossing is weighted by the balance heuristic over the
/// two families' crossing densities per unit arc length,
/// p_line = |m·e_θ| / (2π sin θ) (φ uniform) and p_ring = |m·e_φ| / Θ (θ_r uniform
/// on [0, Θ]), m the silhouette's normal. Their sum is at least min(1/2π, 1/Θ), so
/// no orientation is missed and no crossing's weight blows up: edges in a plane
/// through the axis (a vertical blocker edge under the sky, issue 12 D1), which
/// lines never cross, are crossed squarely by rings, and the (φ − φ0)^(−1/2)
/// spikes of footnote 4, where a line grazes a curved blocker, are damped the
/// same way. The ring starts at φ (uniform) and takes θ_r = Θ · frac(jitter + ½),
/// uniform too: each family on its own is unbiased, so their correlation is not.
#[allow(clippy::too_many_arguments)]
pub fn trace_line_and_ring(
    scene: &Scene,
    accel: &Accel,
    at: SurfacePoint,
    domain: &Domain,
    phi: f32,
    theta_jitter: f32,
    n_theta: u32,
    refine_steps: u32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
    on_point: &mut dyn FnMut(&LinePoint),
) -> LineEstimate {
    let m = Marcher::new(scene, accel, at, domain, refine_steps, dx, transport);
    m.line_and_ring(phi, theta_jitter, n_theta, 1.0, true, on_point)
}

/// The penumbra gate (issue 53): whether a shading point's ring is marched. The
/// ring is ~2.5 `n_theta` of the ~3.5 `n_theta` shadow rays of a line and ring, and
/// only needed where a silhouette crosses the lines at a grazing angle; a point
/// fully lit or fully blocked needs neither. Two probe rays (plus the radiance's
/// own shadow ray, `seen`) tell a point in penumbra from one that probably is not:
/// where they disagree the ring is marched, where they agree with probability
/// `q_agree`. The coin and the probes are independent of the line, so the balance
/// heuristic stays exact with the ring's crossing density scaled by its
/// probability q: every crossing is weighted by 1 / (p_line + q p_ring), unbiased
/// for any q > 0; a penumbra the probes miss costs variance, not bias.
#[derive(Clone, Copy, Debug)]
pub struct Gate {
    /// Probability of marching the ring when every probe agrees, in (0, 1].
    pub q_agree: f32,
    /// Visibility of the light seen by the radiance's own shadow ray, if it cast one.
    pub seen: Option<bool>,
    /// Uniform numbers: the coin, then two (azimuth, polar) pairs for the probes.
    pub u: [f32; 5],
}

/// One φ-line and its ring as [`trace_line_and_ring`] (no points reported: the
/// radiance comes from the caller's own light sample), the ring behind the
/// penumbra [`Gate`].
#[allow(clippy::too_many_arguments)]
pub fn trace_gated(
    scene: &Scene,
    accel: &Accel,
    at: SurfacePoint,
    domain: &Domain,
    phi: f32,
    theta_jitter: f32,
    n_theta: u32,
    refine_steps: u32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
    gate: Gate,
) -> LineEstimate {
    let m = Marcher::new(scene, accel, at, domain, refine_steps, dx, transport);
    let [coin, probes @ ..] = gate.u;
    let (mut probe_rays, mut q) = (0, 1.0);
    if gate.q_agree < 1.0 && m.ring_extent() > 0.0 {
        let mut seen = gate.seen;
        let mut disagree = false;
        for pair in probes.chunks_exact(2) {
            let e = m.azimuth(pair[0] * TAU);
            let theta = m.theta_max(e) * pair[1];
            if theta.is_nan() {
                continue;
            }
            let (visible, _) = m.probe(m.dir(&Curve::Line { e }, theta));
            probe_rays += 1;
            disagree |= seen.is_some_and(|s| s != visible);
            seen = Some(visible);
        }
        q = if disagree { 1.0 } else { gate.q_agree };
    }
    let mut est = m.line_and_ring(phi, theta_jitter, n_theta, q, coin < q, &mut |_| {});
    est.rays += probe_rays;
    est
}

/// Which families of curves sample the boundary, for the crossing densities: lines
/// alone (Eq. 48), rings alone (Θ: the range of θ_r), or both (balance heuristic).
#[derive(Clone, Copy, Debug)]
enum Families {
    Line,
    Ring(f32),
    /// Θ, and the probability that the ring was marched (the penumbra gate).
    Both(f32, f32),
}

impl Families {
    /// The density per unit arc length with which the families cross a silhouette
    /// point at polar angle θ whose normal m has components m_θ, m_φ; `None` where
    /// a lone family runs (nearly) along the silhouette (footnote 3: the crossing
    /// slides along the curve and its derivative is unbounded; it is left out).
    fn density(self, m_theta: f32, m_phi: f32, sin_theta: f32) -> Option<f32> {
        let p_line = m_theta / (TAU * sin_theta);
        match self {
            Families::Line if m_theta < 1e-4 => None,
            Families::Line => Some(p_line),
            Families::Ring(_) if m_phi < 1e-4 => None,
            Families::Ring(big) => Some(m_phi / big),
            Families::Both(big, q) => Some(p_line + q * m_phi / big),
        }
    }
}

/// A line (parameter θ, at azimuth direction `e`) or a ring (parameter φ, at `theta`).
#[derive(Clone, Copy, Debug)]
enum Curve {
    Line { e: Vec3 },
    Ring { theta: f32 },
}

/// Rays on the ring at θ_r: as many as keep its spacing, 2π sin θ_r / n, that of
/// the line, Θ / `n_line` (a blocker narrower than the spacing is missed), at most
/// 4 `n_line`. Over the hemisphere that is 2.5 `n_line` on average.
fn ring_rays(n_line: u32, theta_r: f32, big: f32) -> u32 {
    let n = n_line as f32 * TAU * theta_r.sin() / big;
    (n.round() as u32).clamp(1, 4 * n_line.max(1))
}

/// One ring alone (no line, no MIS): `n_phi` shadow rays at θ_r = Θ · `u_theta`
/// starting at φ0, its φ-jumps weighted by the ring's crossing density alone —
/// Eq. 48 with θ and φ exchanged. For tests that integrate it over θ_r.
#[allow(clippy::too_many_arguments)]
pub fn trace_ring(
    scene: &Scene,
    accel: &Accel,
    at: SurfacePoint,
    domain: &Domain,
    phi0: f32,
    u_theta: f32,
    n_phi: u32,
    refine_steps: u32,
    dx: [Vec3; 2],
    transport: &dyn Fn(Vec3) -> Vec3,
) -> LineEstimate {
    let m = Marcher::new(scene, accel, at, domain, refine_steps, dx, transport);
    let big = m.ring_extent();
    if big.is_nan() || big <= 0.0 {
        return LineEstimate::default();
    }
    m.ring(big * u_theta, phi0, n_phi, Families::Ring(big))
    // (`n_phi` as given: the tests choose the spacing.)
}

/// The shared state of one shading point's line and ring.
struct Marcher<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    x: Vec3,
    ng: Vec3,
    /// `x`'s error bound: shadow rays leave by the one spawning rule
    /// (`accel::offset`), with the hit's own bound, not a default.
    p_error: Vec3,
    domain: &'a Domain,
    frame: Frame,
    refine: u32,
    dx: [Vec3; 2],
    transport: &'a dyn Fn(Vec3) -> Vec3,
}

impl<'a> Marcher<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        at: SurfacePoint,
        domain: &'a Domain,
        refine: u32,
        dx: [Vec3; 2],
        transport: &'a dyn Fn(Vec3) -> Vec3,
    ) -> Self {
        let frame = match domain {
            Domain::Cone { frame, .. } | Domain::Rect { frame, .. } => *frame,
        };
        Self {
            scene,
            accel,
            x: at.p,
            ng: at.n_geo,
            p_error: at.p_error,
            domain,
            frame,
            refine,
            dx,
            transport,
        }
    }

    /// The shadow ray along `w` and the point it reaches on the light; `None` below
    /// the geometric horizon (the receiver itself blocks) or off the light.
    fn shadow_ray(&self, w: Vec3) -> Option<(Ray, Option<(Vec3, Vec3)>)> {
        let (t_max, lp) = light_extent(self.domain, self.x, w);
        if t_max <= 0.0 || w.dot(self.ng) <= 0.0 {
            return None;
        }
        // The segment must end short of the light as seen from the offset origin,
        // not from x: the offset moves the origin toward the light.
        let o = offset_ray_origin_with_error(self.x, self.p_error, self.ng, w);
        let t_o = light_extent(self.domain, o, w).0;
        // An offset across the light's plane leaves no segment: not a visible ray.
        if t_o.is_nan() || t_o <= 0.0 {
            return None;
        }
        Some((Ray::segment(o, w, t_o * (1.0 - 1e-4)), lp))
    }

    /// Visible?, and the point on the light. An any-hit query suffices; the
    /// blocker itself is only looked up at jumps.
    fn probe(&self, w: Vec3) -> (bool, Option<(Vec3, Vec3)>) {
        match self.shadow_ray(w) {
            Some((ray, lp)) => (!self.accel.occluded(&ray), lp),
            None => (false, None),
        }
    }

    fn blocker(&self, w: Vec3) -> BlockerHit {
        let (ray, _) = self.shadow_ray(w)?;
        self.accel.intersect(&ray).map(|h| (h.t, h.prim))
    }

    /// The unit direction at azimuth φ in the frame's tangent plane.
    fn azimuth(&self, phi: f32) -> Vec3 {
        let (sp, cp) = phi.sin_cos();
        self.frame.s * cp + self.frame.t * sp
    }

    /// θmax of the line at azimuth direction `e`.
    fn theta_max(&self, e: Vec3) -> f32 {
        match *self.domain {
            Domain::Cone { theta_max, .. } => theta_max,
            Domain::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => rect_exit_angle(self.x, self.frame.n, e, corner, edge_u, edge_v),
        }
    }

    /// Θ, the largest θ of the domain: the range rings are drawn from.
    fn ring_extent(&self) -> f32 {
        match *self.domain {
            Domain::Cone { theta_max, .. } => theta_max,
            Domain::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => [
                corner,
                corner + edge_u,
                corner + edge_v,
                corner + edge_u + edge_v,
            ]
            .iter()
            .map(|&p| {
                let q = p - self.x;
                cross(q, self.frame.n).length().atan2(q.dot(self.frame.n))
            })
            .fold(0.0, f32::max),
        }
    }

    /// The φ-line at `phi` and, when `ring`, its ring at θ_r = Θ · frac(jitter + ½)
    /// (lines alone where the domain has no Θ), combined by the balance heuristic
    /// with the ring's crossing density scaled by `q`, the probability that it was
    /// marched.
    fn line_and_ring(
        &self,
        phi: f32,
        jitter: f32,
        n: u32,
        q: f32,
        ring: bool,
        on_point: &mut dyn FnMut(&LinePoint),
    ) -> LineEstimate {
        let ring_max = self.ring_extent();
        if ring_max.is_nan() || ring_max <= 0.0 {
            return self.line(phi, jitter, n, Families::Line, on_point);
        }
        let both = Families::Both(ring_max, q);
        let mut est = self.line(phi, jitter, n, both, on_point);
        if ring {
            let theta_r = ring_max * (jitter + 0.5).fract();
            let ring = self.ring(theta_r, phi, ring_rays(n, theta_r, ring_max), both);
            for k in 0..2 {
                est.vis[k] += ring.vis[k];
            }
            est.rays += ring.rays;
            est.jumps += ring.jumps;
        }
        est
    }

    /// The φ-line: `n` stratified rays along θ ∈ [0, θmax(φ)].
    fn line(
        &self,
        phi: f32,
        jitter: f32,
        n: u32,
        families: Families,
        on_point: &mut dyn FnMut(&LinePoint),
    ) -> LineEstimate {
        let curve = Curve::Line {
            e: self.azimuth(phi),
        };
        let mut out = LineEstimate::default();
        let theta_max = self.theta_max(self.azimuth(phi));
        if theta_max.is_nan() || theta_max <= 0.0 || n == 0 {
            return out;
        }
        let step = theta_max / n as f32;
        // (θ, visible) of the previous sample on the line.
        let mut prev: Option<(f32, bool)> = None;
        for i in 0..n {
            let theta = (i as f32 + jitter) * step;
            let wi = self.dir(&curve, theta);
            let (visible, lp) = self.probe(wi);
            out.rays += 1;
            let pdf = 1.0 / (TAU * theta.sin().max(1e-12) * step);
            on_point(&LinePoint {
                wi,
                pdf,
                light_point: lp,
                visible,
            });
            if let Some((theta0, vis0)) = prev {
                if vis0 != visible {
                    self.jump(&curve, theta0, theta, vis0, families, &mut out);
                }
            }
            prev = Some((theta, visible));
        }
        out
    }

    /// The ring at θ_r: `n` rays at φ = φ0 + 2π j / n, a closed loop (each sample
    /// compared with the next, the last with the first); samples outside the
    /// light's domain (a rectangle's corners) break the loop.
    fn ring(&self, theta_r: f32, phi0: f32, n: u32, families: Families) -> LineEstimate {
        let mut out = LineEstimate::default();
        if theta_r.is_nan() || theta_r <= 0.0 || n == 0 {
            return out;
        }
        let curve = Curve::Ring { theta: theta_r };
        let in_domain = |phi: f32| theta_r < self.theta_max(self.azimuth(phi));
        let step = TAU / n as f32;
        let rm = families;
        let mut first: Option<(f32, bool)> = None;
        let mut prev: Option<(f32, bool)> = None;
        for j in 0..n {
            let phi = phi0 + j as f32 * step;
            if !in_domain(phi) {
                prev = None;
                continue;
            }
            let (visible, _) = self.probe(self.dir(&curve, phi));
            out.rays += 1;
            if j == 0 {
                first = Some((phi, visible));
            }
            if let Some((phi_prev, vis0)) = prev {
                if vis0 != visible {
                    self.jump(&curve, phi_prev, phi, vis0, rm, &mut out);
                }
            }
            prev = Some((phi, visible));
        }
        if let (Some((phi_last, vis_last)), Some((phi_first, vis_first))) = (prev, first) {
            if n > 1 && vis_last != vis_first {
                self.jump(&curve, phi_last, phi_first + TAU, vis_last, rm, &mut out);
            }
        }
        out
    }

    /// The direction at parameter `t` of a line (t = θ) or ring (t = φ).
    fn dir(&self, curve: &Curve, t: f32) -> Vec3 {
        let axis = self.frame.n;
        match *curve {
            Curve::Line { e } => {
                let (st, ct) = t.sin_cos();
                axis * ct + e * st
            }
            Curve::Ring { theta } => {
                let (st, ct) = theta.sin_cos();
                axis * ct + self.azimuth(t) * st
            }
        }
    }

    /// The unit tangent ∂ω/∂t (normalised) at `t`.
    fn tangent(&self, curve: &Curve, t: f32) -> Vec3 {
        let (st, ct) = t.sin_cos();
        match *curve {
            Curve::Line { e } => e * ct - self.frame.n * st,
            Curve::Ring { .. } => self.frame.t * ct - self.frame.s * st,
        }
    }

    /// The parameters in the open interval between `a` and `b` where the curve
    /// crosses the plane through x with normal `nu`.
    fn plane_crossings(&self, curve: &Curve, nu: Vec3, a: f32, b: f32) -> Vec<f32> {
        let (lo, hi) = (a.min(b), a.max(b));
        let base: Vec<(f32, f32)> = match *curve {
            // cos θ (axis·ν) + sin θ (e·ν) = 0: θ0 + kπ.
            Curve::Line { e } => {
                let t0 = (-self.frame.n.dot(nu)).atan2(e.dot(nu));
                vec![(t0, std::f32::consts::PI)]
            }
            // sin θr (cos φ s·ν + sin φ t·ν) = −cos θr (axis·ν): two roots per turn.
            Curve::Ring { theta } => {
                let (st, ct) = theta.sin_cos();
                let (p, q) = (st * self.frame.s.dot(nu), st * self.frame.t.dot(nu));
                let r = p.hypot(q);
                let c = -ct * self.frame.n.dot(nu);
                if r <= 1e-12 || c.abs() > r {
                    return Vec::new();
                }
                let (mid, spread) = (q.atan2(p), (c / r).acos());
                vec![(mid - spread, TAU), (mid + spread, TAU)]
            }
        };
        let mut out = Vec::new();
        for (t0, period) in base {
            let mut t = t0 + ((lo - t0) / period).ceil() * period;
            while t < hi {
                if t > lo {
                    out.push(t);
                }
                t += period;
            }
        }
        out
    }

    /// The exact crossing of a polygon silhouette between the blocked and the
    /// visible sample: from the blocked end, the edge through which the curve leaves
    /// the hit triangle (solved in closed form on the edge's plane through x); if the
    /// curve is still blocked just past it (an inner edge of the mesh, or another
    /// blocker behind), the walk goes on from there. Returns (t, m, D) of Eq. 72's
    /// edge, or `None` (a curved blocker, or no edge found) to fall back to the
    /// bracket's midpoint.
    fn polygon_crossing(
        &self,
        curve: &Curve,
        visible_t: f32,
        blocked_t: f32,
        out: &mut LineEstimate,
    ) -> Option<(f32, Vec3, f32)> {
        let mut from = blocked_t;
        let toward = (visible_t - blocked_t).signum();
        let eps = 1e-4 * (visible_t - blocked_t).abs();
        for _ in 0..4 {
            out.rays += 1;
            let (_, prim) = self.blocker(self.dir(curve, from))?;
            let PrimRef::Triangle { mesh, tri } = prim else {
                return None;
            };
            let m = &self.scene.meshes[mesh as usize];
            let v = m.triangles[tri as usize].map(|i| m.positions[i as usize] - self.x);
            // The nearest exit along the curve toward the visible end.
            let mut exit: Option<(f32, Vec3, Vec3)> = None;
            for e in 0..3 {
                let (a, b) = (v[e], v[(e + 1) % 3]);
                let nu = cross(a, b);
                if nu.length_squared() < 1e-20 {
                    continue;
                }
                for t in self.plane_crossings(curve, nu, from, visible_t) {
                    let w = self.dir(curve, t);
                    // Between the edge's endpoints, in front of x.
                    let inside = cross(a, w).dot(nu) >= 0.0 && cross(w, b).dot(nu) >= 0.0;
                    if !inside || w.dot(a + b) <= 0.0 {
                        continue;
                    }
                    if exit.is_none_or(|(te, ..)| (t - from).abs() < (te - from).abs()) {
                        exit = Some((t, a, b));
                    }
                }
            }
            let (t, a, b) = exit?;
            let past = t + toward * eps;
            out.rays += 1;
            if self.probe(self.dir(curve, past)).0 {
                let w = self.dir(curve, t);
                let k = (b - a).normalize_or_zero();
                let (_, d) = ray_line_distance(Vec3::ZERO, w, a, k);
                let m = cross(w, k).normalize_or_zero();
                return (m != Vec3::ZERO && d > 0.0).then_some((t, m, d));
            }
            from = past;
            if (visible_t - from) * toward <= 0.0 {
                return None;
            }
        }
        None
    }

    /// A visibility jump between the samples at `lo` (visibility `vis0`) and `hi`
    /// of `curve`: located (bisection if asked, then exactly on a polygon edge), its
    /// silhouette's geometry found, and its crossing added to `out`.
    fn jump(
        &self,
        curve: &Curve,
        lo: f32,
        hi: f32,
        vis0: bool,
        families: Families,
        out: &mut LineEstimate,
    ) {
        let (mut lo, mut hi) = (lo, hi);
        for _ in 0..self.refine {
            let mid = 0.5 * (lo + hi);
            let (v, _) = self.probe(self.dir(curve, mid));
            out.rays += 1;
            if v == vis0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (visible_t, blocked_t) = if vis0 { (lo, hi) } else { (hi, lo) };
        let found = match self.polygon_crossing(curve, visible_t, blocked_t, out) {
            Some(c) => Some(c),
            None => {
                // The midpoint and the blocker's nearest silhouette (spheres, or a
                // polygon walk that did not close).
                let at = 0.5 * (lo + hi);
                out.rays += 1;
                self.blocker(self.dir(curve, blocked_t))
                    .and_then(|(t, prim)| {
                        silhouette_geometry(self.scene, self.x, self.dir(curve, at), t, prim)
                            .map(|(m, d)| (at, m, d))
                    })
            }
        };
        let Some((at, m, d)) = found else {
            return;
        };
        let w = self.dir(curve, at);
        let axis = self.frame.n;
        let sin_t = cross(w, axis).length();
        if sin_t < 1e-6 {
            return;
        }
        let e_phi = cross(axis, w) / sin_t;
        let e_theta = cross(e_phi, w);
        let m_theta = m.dot(e_theta).abs();
        // Crossing density per unit arc length of the silhouette (see
        // `trace_line_and_ring`).
        let Some(density) = families.density(m_theta, m.dot(e_phi).abs(), sin_t) else {
            return;
        };
        // σ = +1 where the visible side lies along +m.
        let c = self.tangent(curve, at);
        let toward_visible = if vis0 { -c } else { c };
        let sigma = if m.dot(toward_visible) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let v_rel = self.relative_velocity(w, m, d);
        let tr = (self.transport)(w);
        for (v, vn) in out.vis.iter_mut().zip(v_rel) {
            *v += tr * (-sigma * vn / density);
        }
        out.jumps += 1;
    }

    /// The silhouette's normal velocity (along m) per displacement dx[k], relative to
    /// the light's sample points as the shading lanes hold them: the blocker's own
    /// −(δ·m)/D (Eq. 44 / 72: the grazing point stays on the blocker's tangent plane
    /// or its edge), minus the motion of what it is seen against. The environment's
    /// directions do not move; a rectangle's points, fixed in area measure, move by
    /// −(δ·m)/R (R the distance to the light along w): the relative motion is
    /// (1 − D/R) of the blocker's. A sphere light's samples are fixed in cone
    /// coordinates (`sphere_light`) and move with its flow.
    fn relative_velocity(&self, w: Vec3, m: Vec3, d: f32) -> [f32; 2] {
        let blocker = self.dx.map(|delta| -delta.dot(m) / d);
        match *self.domain {
            Domain::Cone { sphere: None, .. } => blocker,
            Domain::Rect { .. } => {
                let r = light_extent(self.domain, self.x, w).0;
                let parallax = if r.is_finite() && r > 0.0 {
                    (1.0 - d / r).max(0.0)
                } else {
                    1.0
                };
                blocker.map(|v| v * parallax)
            }
            Domain::Cone {
                sphere: Some((c, r)),
                ..
            } => match cone_flow(self.x, c, r, w, ConeLaw::Line, self.dx) {
                Some(f) => [0, 1].map(|k| blocker[k] - f.dw[k].dot(m)),
                None => blocker,
            },
        }
    }
}

/// The silhouette at a jump along `w`: its unit normal m on the sphere of
/// directions (m ⊥ w) and the distance D to the grazing point. For a sphere the
/// grazing point is the ray's closest approach to the centre and m the sphere's
/// normal there (Eq. 44); for a triangle the silhouette is the edge nearest to the
/// grazing ray, k, and m ∝ w × k (Eq. 72: the edge's plane through x).
fn silhouette_geometry(
    scene: &Scene,
    x: Vec3,
    w: Vec3,
    t_hit: f32,
    prim: PrimRef,
) -> Option<(Vec3, f32)> {
    let (m, d) = match prim {
        PrimRef::Sphere(i) => {
            let s = &scene.spheres[i as usize];
            let d = (s.center - x).dot(w);
            let p = x + w * d;
            ((p - s.center).normalize_or_zero(), d)
        }
        PrimRef::Triangle { mesh, tri } => {
            let mesh = &scene.meshes[mesh as usize];
            let v = mesh.triangles[tri as usize].map(|i| mesh.positions[i as usize]);
            let mut best = (f32::INFINITY, Vec3::ZERO, t_hit);
            for e in 0..3 {
                let (a, b) = (v[e], v[(e + 1) % 3]);
                let k = (b - a).normalize_or_zero();
                let (dist, tk) = ray_line_distance(x, w, a, k);
                if dist < best.0 {
                    best = (dist, k, tk);
                }
            }
            (cross(w, best.1).normalize_or_zero(), best.2)
        }
    };
    (d.is_finite() && d > 0.0 && m != Vec3::ZERO && m.is_finite()).then_some((m, d))
}

/// Distance between the ray x + t w and the line a + s k, and the ray parameter
/// of the closest approach.
fn ray_line_distance(x: Vec3, w: Vec3, a: Vec3, k: Vec3) -> (f32, f32) {
    let n = cross(w, k);
    let nn = n.length_squared();
    if nn < 1e-12 {
        let t = (a - x).dot(w);
        return (((a - x) - w * t).length(), t);
    }
    let r = a - x;
    let dist = r.dot(n).abs() / nn.sqrt();
    // t = ((a − x) × k) · n / |n|²
    let t = cross(r, k).dot(n) / nn;
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
            let n = cross(edge_u, edge_v).normalize();
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
    let n = cross(edge_u, edge_v);
    let centre = corner + 0.5 * (edge_u + edge_v);
    // Direction of the cut, oriented the way growing θ moves the hit point.
    let mut m = cross(n, cross(axis, d));
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
    let sin = cross(to_exit, axis).length();
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
        let tr = transport(w.as_vec3a());
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
    let rule = GaussLegendre::new(16);
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
            for (&t, &wt) in rule.nodes().iter().zip(rule.weights()) {
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
    ([(g[0] * inv).as_vec3a(), (g[1] * inv).as_vec3a()], b as f32)
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
    use crate::math::Vec3 as V;
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
                let n = cross(eu, ev);
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
