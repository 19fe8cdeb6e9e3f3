//! Random numbers addressed by (pixel, sample index, dimension, seed) rather than
//! drawn from per-thread state, so that an image is bit-identical for any number of
//! threads. Backed by Owen-scrambled Sobol points (`sobol_burley`) for low
//! discrepancy in the first dimensions, decorrelated per pixel by hashing.

use super::Vec2;

/// How many Sobol dimensions `sobol_burley` provides; dimensions past this fall back
/// to a hashed stream (their contribution is at high path depth, where
/// stratification hardly matters).
const SOBOL_DIMS: u32 = sobol_burley::NUM_DIMENSIONS;

/// Dimensions served by Sobol; later ones use the hashed stream. Stratification
/// pays off for the camera jitter and the first two path vertices (direct light
/// and its first bounce); deeper vertices contribute little variance and the
/// hash is several times cheaper than a scrambled Sobol point.
const SOBOL_DIMS_USED: u32 = 20;

/// The sampler of one (pixel, sample) pair: hands out dimensions in order.
/// Sobol values are computed four dimensions at a time (`sample_4d`, SIMD) and
/// cached, since consecutive dimensions are almost always consumed together.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    index: u32,
    seed: u32,
    dim: u32,
    /// The dimension set (dim / 4) held in `cache`, or u32::MAX.
    cached_set: u32,
    cache: [f32; 4],
}

impl PixelSampler {
    /// `pixel` is the linear pixel index, `sample` the sample number within the pixel.
    pub fn new(pixel: u32, sample: u32, seed: u32) -> Self {
        Self {
            index: sample,
            seed: hash2(pixel, seed),
            dim: 0,
            cached_set: u32::MAX,
            cache: [0.0; 4],
        }
    }

    /// The next value in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        if d < SOBOL_DIMS.min(SOBOL_DIMS_USED) && self.index < (1 << 16) {
            let set = d / 4;
            if set != self.cached_set {
                self.cache = sobol_burley::sample_4d(self.index, set, self.seed);
                self.cached_set = set;
            }
            self.cache[(d % 4) as usize]
        } else {
            let h = hash2(hash2(self.index, d), self.seed);
            (h >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
        }
    }

    /// The next two values, drawn from consecutive dimensions (a 2D Sobol pair).
    pub fn next_2d(&mut self) -> Vec2 {
        let a = self.next_1d();
        let b = self.next_1d();
        Vec2::new(a, b)
    }

    /// Skips to a fixed dimension so that the number of values drawn by one path
    /// vertex does not shift the dimensions of the next (keeps paths comparable
    /// between e.g. a run with and without some optional estimate).
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }
}

/// A 32-bit integer hash (the "lowbias32" finaliser by C. Wellons) of two words.
pub fn hash2(a: u32, b: u32) -> u32 {
    let mut x = a ^ b.wrapping_mul(0x9e37_79b9).rotate_left(16);
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampler_is_deterministic_and_in_range() {
        let mut a = PixelSampler::new(17, 3, 42);
        let mut b = PixelSampler::new(17, 3, 42);
        for _ in 0..600 {
            let x = a.next_1d();
            assert_eq!(x, b.next_1d());
            assert!((0.0..1.0).contains(&x));
        }
    }

    #[test]
    fn cached_4d_values_equal_single_dimension_values() {
        let mut p = PixelSampler::new(5, 9, 3);
        let seed = hash2(5, 3);
        for d in 0..SOBOL_DIMS_USED {
            assert_eq!(p.next_1d(), sobol_burley::sample(9, d, seed), "dim {d}");
        }
        // Past the Sobol dimensions: the hashed stream, still in [0, 1).
        let x = p.next_1d();
        assert!((0.0..1.0).contains(&x) && x != sobol_burley::sample(9, SOBOL_DIMS_USED, seed));
        p.set_dimension(13);
        assert_eq!(p.next_1d(), sobol_burley::sample(9, 13, seed));
    }

    #[test]
    fn sampler_is_roughly_uniform_past_sobol_dims() {
        // Mean and variance of the hashed stream match U(0,1) within 4 sigma.
        let n = 20_000u32;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let mut p = PixelSampler::new(i, 0, 1);
            p.set_dimension(SOBOL_DIMS + 5);
            let x = p.next_1d() as f64;
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!((mean - 0.5).abs() < 4.0 * (1.0 / 12.0 / n as f64).sqrt());
        assert!((var - 1.0 / 12.0).abs() < 0.005);
    }
}
