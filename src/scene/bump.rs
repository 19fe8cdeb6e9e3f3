//! Procedural bump maps with analytic first and second derivatives.
//!
//! The height field displaces the surface along its normal, h(u, v) in world units,
//! over the shape's own (u, v) parameterisation. The shading normal of the bumped
//! surface needs ∂h/∂u, ∂h/∂v; its derivative — the curvature term n_x of the
//! first-order paper (Sec. 4.2, "Gradients for Normal or Bump Maps") — needs the
//! second derivatives as well, so they are exact here rather than finite differences.

use crate::math::Vec2;
use std::f32::consts::TAU;

/// One sinusoid a · sin(2π (f_u u + f_v v) + φ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sinusoid {
    pub amplitude: f32,
    pub frequency: Vec2,
    pub phase: f32,
}

/// A bump map: a sum of sinusoids. On a sphere, `frequency.x` must be an integer
/// for the height to be continuous across the φ = 0 seam (the parser checks this).
#[derive(Clone, Debug, PartialEq)]
pub struct Bump {
    pub name: String,
    pub terms: Vec<Sinusoid>,
}

/// Height and its derivatives at one (u, v).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeightJet {
    pub h: f32,
    pub h_u: f32,
    pub h_v: f32,
    pub h_uu: f32,
    pub h_uv: f32,
    pub h_vv: f32,
}

impl Bump {
    /// Evaluates h and its first and second partial derivatives at `uv`.
    pub fn eval(&self, uv: Vec2) -> HeightJet {
        let mut j = HeightJet::default();
        for t in &self.terms {
            let w = TAU * t.frequency;
            let arg = w.dot(uv) + t.phase;
            let (s, c) = arg.sin_cos();
            let a = t.amplitude;
            j.h += a * s;
            j.h_u += a * c * w.x;
            j.h_v += a * c * w.y;
            j.h_uu -= a * s * w.x * w.x;
            j.h_uv -= a * s * w.x * w.y;
            j.h_vv -= a * s * w.y * w.y;
        }
        j
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_central_differences() {
        let b = Bump {
            name: "b".into(),
            terms: vec![
                Sinusoid {
                    amplitude: 0.02,
                    frequency: Vec2::new(8.0, 3.0),
                    phase: 0.3,
                },
                Sinusoid {
                    amplitude: 0.01,
                    frequency: Vec2::new(-2.0, 11.0),
                    phase: 1.1,
                },
            ],
        };
        let p = Vec2::new(0.31, 0.67);
        let e = 1e-3f32;
        let j = b.eval(p);
        let du = |q: Vec2| (b.eval(q + Vec2::X * e).h - b.eval(q - Vec2::X * e).h) / (2.0 * e);
        let dv = |q: Vec2| (b.eval(q + Vec2::Y * e).h - b.eval(q - Vec2::Y * e).h) / (2.0 * e);
        let close = |a: f32, b: f32, scale: f32| (a - b).abs() <= 2e-2 * scale;
        assert!(close(j.h_u, du(p), j.h_u.abs().max(0.1)));
        assert!(close(j.h_v, dv(p), j.h_v.abs().max(0.1)));
        let huu = (b.eval(p + Vec2::X * e).h_u - b.eval(p - Vec2::X * e).h_u) / (2.0 * e);
        let huv = (b.eval(p + Vec2::Y * e).h_u - b.eval(p - Vec2::Y * e).h_u) / (2.0 * e);
        let hvv = (b.eval(p + Vec2::Y * e).h_v - b.eval(p - Vec2::Y * e).h_v) / (2.0 * e);
        assert!(close(j.h_uu, huu, j.h_uu.abs().max(1.0)));
        assert!(close(j.h_uv, huv, j.h_uv.abs().max(1.0)));
        assert!(close(j.h_vv, hvv, j.h_vv.abs().max(1.0)));
    }
}
