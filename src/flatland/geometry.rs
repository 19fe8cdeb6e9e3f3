//! Blockers of the flatland scene and the two things we ask of them: the angular
//! interval each one blocks as seen from a receiver point (object space, used by the
//! exact shading and the analytic gradient) and the nearest hit along a ray (image
//! space, used by the semianalytic gradient and the brute-force checks).
//!
//! Angle convention for the whole module: a direction leaving the receiver point
//! `(x, 0)` at angle `θ` is `(sin θ, cos θ)`, i.e. `θ` is measured from the receiver
//! normal (+y) towards +x, and the visible hemisphere is `θ ∈ (−π/2, π/2)`.

use crate::{Error, Result};

/// An axis-aligned rectangle ("box" in the paper's Fig. 9a) given by its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect2 {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

/// A circle blocker (the curved blocker of Fig. 7b and Appendix D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    pub center: [f64; 2],
    pub radius: f64,
}

/// One blocker. A closed set of shapes, so an enum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Blocker {
    Rect(Rect2),
    Circle(Circle),
}

/// Which geometric feature of which blocker defines a visibility discontinuity:
/// a corner index (0..4: `(min,min)`, `(max,min)`, `(max,max)`, `(min,max)`) of a
/// rectangle, or the side (0 = lower angle, 1 = upper angle) of a circle's tangent.
/// Two receiver points whose discontinuities have the same owners lie on the same
/// smooth piece of `B(x)`; a change of owner is a kink of `B`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Feature {
    pub blocker: usize,
    pub index: u8,
}

/// One end of a blocked angular interval: the angle `α`, the distance `D` from the
/// receiver point to the blocker point that defines it (Eq. 36/37), and its owner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Endpoint {
    pub angle: f64,
    pub distance: f64,
    pub feature: Feature,
}

/// A blocked angular interval `[lo.angle, hi.angle]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: Endpoint,
    pub hi: Endpoint,
}

impl Blocker {
    /// Checks that the blocker is finite, non-degenerate and strictly above the
    /// receiver line `y = 0`: the interval logic relies on every blocker being seen
    /// inside the open hemisphere, never wrapping around the horizon.
    pub fn validate(&self, index: usize) -> Result<()> {
        let bad = |message: String| {
            Err(Error::Option {
                option: format!("flatland blocker {index}"),
                message,
            })
        };
        match *self {
            Blocker::Rect(r) => {
                let all = [r.min[0], r.min[1], r.max[0], r.max[1]];
                if all.iter().any(|v| !v.is_finite()) {
                    return bad("rectangle corners must be finite".into());
                }
                if r.max[0] <= r.min[0] || r.max[1] <= r.min[1] {
                    return bad(format!(
                        "rectangle needs max > min on both axes, got min {:?} max {:?}",
                        r.min, r.max
                    ));
                }
                if r.min[1] <= 0.0 {
                    return bad(format!(
                        "rectangle must lie strictly above the receiver (min y > 0), got {}",
                        r.min[1]
                    ));
                }
            }
            Blocker::Circle(c) => {
                if !(c.center[0].is_finite() && c.center[1].is_finite() && c.radius.is_finite()) {
                    return bad("circle centre and radius must be finite".into());
                }
                if c.radius <= 0.0 {
                    return bad(format!("circle radius must be > 0, got {}", c.radius));
                }
                if c.center[1] - c.radius <= 0.0 {
                    return bad(format!(
                        "circle must lie strictly above the receiver (centre y > radius), got centre y {} radius {}",
                        c.center[1], c.radius
                    ));
                }
            }
        }
        Ok(())
    }

    /// The angular interval this blocker covers as seen from `(x, 0)`, computed in
    /// object space.
    ///
    /// Rectangle: the blocker is convex and above the receiver, so its angular extent
    /// is spanned by the extreme corner angles; `D` is the distance to that corner.
    /// Circle: centre angle `θ_c ± asin(r/d)`; `D = sqrt(d² − r²)` is the distance to
    /// the tangent point (Appendix D shows the same `dα/dx` as for a point blocker).
    pub fn interval(&self, x: f64, index: usize) -> Interval {
        match *self {
            Blocker::Rect(r) => {
                let corners = [
                    [r.min[0], r.min[1]],
                    [r.max[0], r.min[1]],
                    [r.max[0], r.max[1]],
                    [r.min[0], r.max[1]],
                ];
                let ends: [Endpoint; 4] = std::array::from_fn(|i| {
                    let (dx, dy) = (corners[i][0] - x, corners[i][1]);
                    Endpoint {
                        angle: dx.atan2(dy),
                        distance: dx.hypot(dy),
                        feature: Feature {
                            blocker: index,
                            index: i as u8,
                        },
                    }
                });
                let mut lo = ends[0];
                let mut hi = ends[0];
                for e in &ends[1..] {
                    if e.angle < lo.angle {
                        lo = *e;
                    }
                    if e.angle > hi.angle {
                        hi = *e;
                    }
                }
                Interval { lo, hi }
            }
            Blocker::Circle(c) => {
                let (dx, dy) = (c.center[0] - x, c.center[1]);
                let d = dx.hypot(dy);
                let centre = dx.atan2(dy);
                let half = (c.radius / d).asin();
                let tangent = (d * d - c.radius * c.radius).sqrt();
                let end = |s: f64, i: u8| Endpoint {
                    angle: centre + s * half,
                    distance: tangent,
                    feature: Feature {
                        blocker: index,
                        index: i,
                    },
                };
                Interval {
                    lo: end(-1.0, 0),
                    hi: end(1.0, 1),
                }
            }
        }
    }

    /// Nearest hit distance `t > 0` of the ray `(x, 0) + t (sin θ, cos θ)`, if any.
    pub fn hit(&self, x: f64, theta: f64) -> Option<f64> {
        let (s, c) = theta.sin_cos();
        match *self {
            Blocker::Rect(r) => {
                // Slab test; the origin is below the box so the entry distance is the hit.
                let mut t0 = 0.0f64;
                let mut t1 = f64::INFINITY;
                for (o, d, lo, hi) in [(x, s, r.min[0], r.max[0]), (0.0, c, r.min[1], r.max[1])] {
                    if d == 0.0 {
                        if o < lo || o > hi {
                            return None;
                        }
                    } else {
                        let (a, b) = ((lo - o) / d, (hi - o) / d);
                        t0 = t0.max(a.min(b));
                        t1 = t1.min(a.max(b));
                    }
                }
                (t0 <= t1 && t1 > 0.0).then_some(t0)
            }
            Blocker::Circle(cir) => {
                let (ox, oy) = (x - cir.center[0], -cir.center[1]);
                let b = ox * s + oy * c;
                let q = ox * ox + oy * oy - cir.radius * cir.radius;
                let disc = b * b - q;
                if disc < 0.0 {
                    return None;
                }
                let t = -b - disc.sqrt();
                (t > 0.0).then_some(t)
            }
        }
    }
}

/// Merges per-blocker intervals into the union of blocked angles (Sec. 8.1: "the
/// receiver point sees only two (and not four) discontinuities"). Overlapping or
/// touching intervals fuse; the merged interval keeps the outermost endpoints with
/// their own distances and owners.
pub fn merge(mut intervals: Vec<Interval>) -> Vec<Interval> {
    intervals.sort_by(|a, b| a.lo.angle.total_cmp(&b.lo.angle));
    let mut out: Vec<Interval> = Vec::with_capacity(intervals.len());
    for iv in intervals {
        match out.last_mut() {
            Some(last) if iv.lo.angle <= last.hi.angle => {
                if iv.hi.angle > last.hi.angle {
                    last.hi = iv.hi;
                }
            }
            _ => out.push(iv),
        }
    }
    out
}
