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
    /// The sample index bit-reversed and Owen-shuffled (`sobol_burley`'s first
    /// step, the same for every dimension set of this sample): computed once.
    shuffled_rev_index: u32,
    dim: u32,
    /// The dimension set (dim / 4) held in `cache`, or u32::MAX.
    cached_set: u32,
    cache: [f32; 4],
}

impl PixelSampler {
    /// `pixel` is the linear pixel index, `sample` the sample number within the pixel.
    pub fn new(pixel: u32, sample: u32, seed: u32) -> Self {
        let seed = hash2(pixel, seed);
        Self {
            index: sample,
            seed,
            shuffled_rev_index: sobol_burley::parts::owen_scramble_rev(
                sample.reverse_bits(),
                sobol_burley::parts::hash(seed ^ 0x79c6_8e4a),
            ),
            dim: 0,
            cached_set: u32::MAX,
            cache: [0.0; 4],
        }
    }

    /// The next value in [0, 1). Inlined (a path draws ~20 of them); the Sobol
    /// set is computed out of line, once per four dimensions.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        let set = d / 4;
        if self.sobol_serves(set) {
            if set != self.cached_set {
                self.fill_cache(set);
            }
            self.cache[(d % 4) as usize]
        } else {
            let h = hash2(hash2(self.index, d), self.seed);
            (h >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
        }
    }

    /// Whether dimension set `set` (dimensions 4·set .. 4·set + 3) comes from
    /// Sobol rather than the hashed stream: the first [`SOBOL_SETS`] sets, for
    /// sample indices the 16 direction vectors cover.
    #[inline]
    fn sobol_serves(&self, set: u32) -> bool {
        set < SOBOL_SETS as u32 && self.index < (1 << 16)
    }

    #[inline(never)]
    fn fill_cache(&mut self, set: u32) {
        self.cache = self.sobol_4d(set);
        self.cached_set = set;
    }

    /// The next two values, drawn from consecutive dimensions (a 2D Sobol pair).
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let a = self.next_1d();
        let b = self.next_1d();
        Vec2::new(a, b)
    }

    /// The values of dimensions `dim` and `dim + 1`, without moving the cursor.
    #[inline]
    pub fn next_2d_at(&mut self, dim: u32) -> Vec2 {
        let cursor = self.dim;
        self.dim = dim;
        let v = self.next_2d();
        self.dim = cursor;
        v
    }

    /// Dimensions `dim .. dim + 8` at once (`dim` a multiple of four), the values
    /// [`Self::next_1d`] would give them, without moving the cursor or the cache.
    /// A path vertex reads its eight dimensions through this: two Sobol sets, or
    /// past them eight hashes in lanes, in one call instead of seven cursor steps
    /// with their bounds and cache checks (cornell: −4.6 % of the render's instructions).
    #[inline]
    pub fn block8(&self, dim: u32) -> [f32; 8] {
        let [a, b] = [dim, dim + 4].map(|d| self.block4(d));
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
    }

    /// Dimensions `dim .. dim + 4` (`dim` a multiple of four): one Sobol set
    /// or four hashes, the first half of [`Self::block8`].
    #[inline]
    pub fn block4(&self, dim: u32) -> [f32; 4] {
        debug_assert!(dim.is_multiple_of(4));
        let set = dim / 4;
        if self.sobol_serves(set) {
            self.sobol_4d(set)
        } else {
            self.hashed_4d(dim)
        }
    }

    /// The hashed stream of dimensions `dim .. dim + 4` in lanes: [`hash2`] of
    /// [`hash2`], bit for bit as [`Self::next_1d`] computes it one at a time.
    fn hashed_4d(&self, dim: u32) -> [f32; 4] {
        use wide::u32x4;
        let dims = u32x4::splat(dim) + u32x4::new([0, 1, 2, 3]);
        let h = hash2_x4(
            hash2_x4(u32x4::splat(self.index), dims),
            u32x4::splat(self.seed),
        );
        (h >> 8_i32)
            .to_array()
            .map(|v| v as f32 * (1.0 / (1u32 << 24) as f32))
    }

    /// `sobol_burley::sample_4d(index, set, seed)`, bit for bit, with the Sobol
    /// matrix product written without branches: the crate loops over the set bits
    /// of the shuffled index, whose number is random, so the loop's exit was a
    /// mispredicted branch per call (the sampler was 12 % of a cornell profile);
    /// here four table lookups, one per nibble of the index.
    fn sobol_4d(&self, set: u32) -> [f32; 4] {
        use sobol_burley::parts::{hash_int4, owen_scramble_int4_rev, Int4};
        use wide::u32x4;
        // The Sobol matrix times the index, as the XOR of one table entry per
        // nibble of the (reversed, shuffled) index: four loads instead of sixteen
        // masked XORs, same bits (the product is linear over XOR).
        let tables = &nibble_tables()[set as usize];
        let r = self.shuffled_rev_index;
        let mut sobol = u32x4::ZERO;
        for (k, table) in tables.iter().enumerate() {
            sobol ^= u32x4::new(table[((r >> (28 - 4 * k)) & 0xf) as usize]);
        }
        // The crate's Owen scramble of the point, unchanged.
        let scramble = {
            let seed: Int4 = [self.seed.wrapping_mul(0x9c8f_2d3b); 4].into();
            let ds: Int4 = [set; 4].into();
            seed ^ ds ^ [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into()
        };
        owen_scramble_int4_rev(sobol.to_array().into(), hash_int4(scramble))
            .reverse_bits()
            .to_f32_norm()
    }

    /// Moves the cursor to dimension `dim`.
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }
}

/// Per Sobol dimension set, per nibble of the reversed index (most significant
/// first), the XOR of the direction vectors its set bits select: 16 entries of
/// four lanes, 1 KiB per set.
type NibbleTables = [[[[u32; 4]; 16]; 4]; SOBOL_SETS];

fn nibble_tables() -> &'static NibbleTables {
    static TABLE: std::sync::OnceLock<NibbleTables> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let vectors = direction_vectors();
        let mut t = [[[[0; 4]; 16]; 4]; SOBOL_SETS];
        for (set, nibbles) in t.iter_mut().enumerate() {
            for (k, table) in nibbles.iter_mut().enumerate() {
                for (value, entry) in table.iter_mut().enumerate() {
                    for bit in 0..4 {
                        // Bit 3 - bit of the nibble is bit 31 - (4k + bit) of the
                        // reversed index, which selects direction vector 4k + bit.
                        if value & (8 >> bit) != 0 {
                            let v = vectors[set][4 * k + bit];
                            for lane in 0..4 {
                                entry[lane] ^= v[lane];
                            }
                        }
                    }
                }
            }
        }
        t
    })
}

/// Dimension sets (of four) served by Sobol.
const SOBOL_SETS: usize = (SOBOL_DIMS_USED as usize).div_ceil(4);
// Whole sets, all within the crate's dimensions.
const _: () = assert!(SOBOL_DIMS_USED.is_multiple_of(4) && SOBOL_DIMS_USED <= SOBOL_DIMS);

/// `sobol_burley`'s (bit-reversed) direction vectors of the first [`SOBOL_SETS`]
/// dimension sets, 16 per dimension (indices below 2^16). The crate keeps its table
/// private, so they are read back through its public `sobol_rev`: an index with the
/// single bit 31 - i set selects vector i. Read once, into [`nibble_tables`].
fn direction_vectors() -> [[[u32; 4]; 16]; SOBOL_SETS] {
    let mut t = [[[0; 4]; 16]; SOBOL_SETS];
    for (set, vecs) in t.iter_mut().enumerate() {
        for (i, v) in vecs.iter_mut().enumerate() {
            for (k, lane) in v.iter_mut().enumerate() {
                let dim = (set * 4 + k) as u32;
                *lane = sobol_burley::parts::sobol_rev(1 << (31 - i), dim);
            }
        }
    }
    t
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

/// [`hash2`] in four lanes.
fn hash2_x4(a: wide::u32x4, b: wide::u32x4) -> wide::u32x4 {
    let m = b * wide::u32x4::splat(0x9e37_79b9);
    let mut x = a ^ ((m << 16_i32) | (m >> 16_i32));
    x ^= x >> 16_i32;
    x *= wide::u32x4::splat(0x7feb_352d);
    x ^= x >> 15_i32;
    x *= wide::u32x4::splat(0x846c_a68b);
    x ^= x >> 16_i32;
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
    fn blocks_of_eight_equal_the_cursor_bit_for_bit() {
        // Sobol sets, the hashed stream past them, and indices past 2^16 (hashed
        // from dimension 0), for several pixels and seeds.
        for (pixel, index, seed) in [
            (0, 0, 0),
            (5, 9, 3),
            (1 << 20, 65535, 7),
            (3, 1 << 16, 1),
            (77, 300_001, 9),
        ] {
            let mut p = PixelSampler::new(pixel, index, seed);
            let stream: Vec<f32> = (0..64).map(|_| p.next_1d()).collect();
            for dim in (0..56).step_by(4) {
                let block = p.block8(dim);
                let want = &stream[dim as usize..dim as usize + 8];
                assert_eq!(
                    block.as_slice(),
                    want,
                    "pixel {pixel} index {index} dim {dim}"
                );
            }
        }
    }

    #[test]
    fn branchless_sobol_equals_the_crate_bit_for_bit() {
        // Indices across the whole 16-bit range (the shuffle fills every bit), many
        // seeds, every dimension set served.
        for index in (0..1u32 << 16).step_by(97).chain([0, 1, 65535]) {
            for pixel in [0u32, 3, 1 << 20] {
                let p = PixelSampler::new(pixel, index, 11);
                for set in 0..SOBOL_SETS as u32 {
                    let want = sobol_burley::sample_4d(index, set, p.seed);
                    assert_eq!(
                        p.sobol_4d(set),
                        want,
                        "index {index} pixel {pixel} set {set}"
                    );
                }
            }
        }
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
