//! Lobes as stored for every (vertex, view direction): μ octahedral-encoded in
//! 2 × 16 bits, κ and α in half floats — 12 bytes against 28 in f32, as the
//! paper's 16-bit storage. μ is then within 7e-5 rad (0.45 % of the standard
//! deviation of a κ = 4096 lobe, the sharpest prefiltered level) and κ, α within
//! half a half-float ulp (2⁻¹¹ relative): far below the slices' own noise.

use super::slice::{Lobe, Slice};
use crate::math::Vec3;
use half::f16;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PackedLobe {
    pub oct: [u16; 2],
    /// κ, then α's three channels, as half-float bits: adjacent so that one
    /// F16C instruction converts them (a frame unpacks 12 lobes per vertex).
    pub kappa_alpha: [u16; 4],
}

pub type PackedSlice = [PackedLobe; 4];

/// Largest finite half float: κ and α beyond it saturate rather than become ∞.
const HALF_MAX: f32 = 65504.0;

fn to_half(x: f32) -> u16 {
    f16::from_f32(x.clamp(-HALF_MAX, HALF_MAX)).to_bits()
}

fn sign(x: f32) -> f32 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// The octahedral map of a unit direction onto [−1, 1]², lower hemisphere folded
/// over the diagonals, each coordinate quantised to 16 bits.
fn oct_encode(d: Vec3) -> [u16; 2] {
    let l1 = (d.x.abs() + d.y.abs() + d.z.abs()).max(1e-30);
    let (mut x, mut y) = (d.x / l1, d.y / l1);
    if d.z < 0.0 {
        (x, y) = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
    }
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0).round() as u16;
    [q(x), q(y)]
}

fn oct_decode(o: [u16; 2]) -> Vec3 {
    let f = |q: u16| q as f32 / 65535.0 * 2.0 - 1.0;
    let (mut x, mut y) = (f(o[0]), f(o[1]));
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        (x, y) = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
    }
    Vec3::new(x, y, z).normalize_or(Vec3::Z)
}

impl PackedLobe {
    pub fn pack(l: &Lobe) -> Self {
        Self {
            oct: oct_encode(l.mu),
            kappa_alpha: [l.kappa, l.alpha.x, l.alpha.y, l.alpha.z].map(to_half),
        }
    }

    pub fn unpack(&self) -> Lobe {
        use half::slice::{HalfBitsSliceExt, HalfFloatSliceExt};
        let mut ka = [0f32; 4];
        self.kappa_alpha
            .reinterpret_cast::<f16>()
            .convert_to_f32_slice(&mut ka);
        Lobe {
            mu: oct_decode(self.oct),
            kappa: ka[0],
            alpha: Vec3::new(ka[1], ka[2], ka[3]),
        }
    }
}

pub fn pack_slice(s: &Slice) -> PackedSlice {
    s.map(|l| PackedLobe::pack(&l))
}

pub fn unpack_slice(s: &PackedSlice) -> Slice {
    s.map(|l| l.unpack())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::cross;

    #[test]
    fn directions_round_trip_within_the_stated_angle_everywhere() {
        let mut worst = 0f32;
        let n = 20_000;
        for k in 0..n {
            // A Fibonacci sphere, plus the poles and the octahedron's folds.
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let phi = k as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            for d in [
                d,
                Vec3::Z,
                -Vec3::Z,
                Vec3::X,
                -Vec3::Y,
                Vec3::new(1.0, 1.0, 0.0).normalize(),
            ] {
                let back = oct_decode(oct_encode(d));
                // atan2(|a × b|, a · b): acos of an f32 dot near 1 is off by ~3e-4.
                worst = worst.max(cross(back, d).length().atan2(back.dot(d)));
                assert!((back.length() - 1.0).abs() < 1e-6);
            }
        }
        assert!(worst < 7e-5, "worst angle {worst} rad");
        assert!(worst > 0.0, "16-bit directions cannot be exact");
    }

    #[test]
    fn kappa_and_weights_keep_half_precision_and_saturate() {
        let l = Lobe {
            mu: Vec3::new(0.3, -0.4, 0.866).normalize(),
            kappa: 1234.5,
            alpha: Vec3::new(0.731, 1e-3, 2.5),
        };
        let u = PackedLobe::pack(&l).unpack();
        assert!((u.kappa / l.kappa - 1.0).abs() <= 2f32.powi(-11));
        for (a, b) in u.alpha.to_array().iter().zip(l.alpha.to_array()) {
            assert!((a / b - 1.0).abs() <= 2f32.powi(-11), "{a} vs {b}");
        }
        let big = Lobe { kappa: 1e9, ..l };
        assert_eq!(PackedLobe::pack(&big).unpack().kappa, HALF_MAX);
        let empty = PackedLobe::pack(&Lobe::default()).unpack();
        assert_eq!(empty.alpha, Vec3::ZERO);
        assert!(empty.mu.angle_between(Vec3::Z) < 5e-5);
    }
}
