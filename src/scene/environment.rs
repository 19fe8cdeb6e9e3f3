//! Distant lighting at infinity: constant, lat-long image, or an analytic
//! "gaussian sky" (a Gaussian lobe around a direction plus a constant — the
//! lighting used throughout the first-order paper, Fig. 9 and Fig. 13).
//!
//! Lat-long convention (the same as Mitsuba 3's `envmap`, so scenes compare
//! exactly): for a world direction d = (x, y, z) with y up,
//! u = atan2(x, −z) / 2π wrapped to [0, 1), v = acos(y) / π; row 0 is the zenith
//! and u = 0 looks along −z. Texel placement also follows Mitsuba (see [`bilinear`]).

use crate::math::scalar::{dot_const, Scalar};
use crate::math::{luminance, Vec2, Vec3};
use std::f32::consts::{PI, TAU};
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    Constant {
        radiance: Vec3,
    },
    /// An equirectangular image, row-major, `width × height` linear RGB texels,
    /// multiplied by `scale`.
    Image {
        width: usize,
        height: usize,
        texels: Vec<Vec3>,
        scale: f32,
    },
    /// L(ω) = ambient + peak · exp(sharpness · (ω·direction − 1)).
    GaussianSky {
        direction: Vec3,
        sharpness: f32,
        peak: Vec3,
        ambient: Vec3,
    },
}

/// Direction → lat-long (u, v) ∈ [0,1)². `libm`'s `atan2f` (musl's): on an
/// image-sky render, the platform's took ~4 % of the time after the light
/// samples stopped calling it, `libm`'s 2–3 % less of the whole.
pub fn direction_to_latlong(d: Vec3) -> Vec2 {
    let mut u = libm::atan2f(d.x, -d.z) / TAU;
    if u < 0.0 {
        u += 1.0;
    }
    // atan2 rather than acos: accurate near the poles, where y rounds to ±1.
    let v = libm::atan2f((d.x * d.x + d.z * d.z).sqrt(), d.y) / PI;
    Vec2::new(u.min(1.0 - f32::EPSILON), v.min(1.0 - f32::EPSILON))
}

/// Lat-long (u, v) → unit direction; inverse of [`direction_to_latlong`].
pub fn latlong_to_direction(uv: Vec2) -> Vec3 {
    let phi = uv.x * TAU;
    let theta = uv.y * PI;
    let (sp, cp) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    Vec3::new(sp * st, ct, -cp * st)
}

impl Environment {
    /// Radiance arriving from direction `d` (unit, pointing away from the scene).
    pub fn eval(&self, d: Vec3) -> Vec3 {
        Vec3::from_array(self.radiance(d.to_array()))
    }

    /// A lat-long image's radiance at (u, v): [`Self::eval`]'s bits for the
    /// (u, v) that [`direction_to_latlong`] gives its direction, for callers that
    /// have (u, v) already; `None` for the other environments.
    pub fn eval_latlong(&self, uv: Vec2) -> Option<Vec3> {
        match self {
            &Environment::Image {
                width,
                height,
                ref texels,
                scale,
            } => Some(bilinear(texels, width, height, uv) * scale),
            _ => None,
        }
    }

    /// Radiance arriving from the unit direction `d`, for any scalar type: the one
    /// implementation of every environment, used by [`eval`](Self::eval) (f32) and
    /// by the gradient stage over duals (whose lanes then carry ∂L/∂d · ∂d).
    pub fn radiance<T: Scalar>(&self, d: [T; 3]) -> [T; 3] {
        match self {
            Environment::Constant { radiance } => {
                radiance.to_array().map(|c| T::constant(c as f64))
            }
            Environment::Image {
                width,
                height,
                texels,
                scale,
            } => image_radiance(texels, *width, *height, *scale, d),
            Environment::GaussianSky {
                direction,
                sharpness,
                peak,
                ambient,
            } => {
                let lobe = dot_const(d, direction.to_array())
                    .add_const(-1.0)
                    .mul_const(*sharpness as f64)
                    .exp();
                [0, 1, 2].map(|c| lobe.mul_const(peak[c] as f64).add_const(ambient[c] as f64))
            }
        }
    }
}

impl Environment {
    /// Mean luminance over the sphere of directions (the environment's power per
    /// unit solid angle, for choosing lights in proportion to power).
    pub fn mean_luminance(&self) -> f32 {
        match self {
            Environment::Constant { radiance } => luminance(*radiance),
            Environment::Image {
                width,
                height,
                texels,
                scale,
            } => {
                let mut s = 0.0f64;
                let mut wsum = 0.0f64;
                for y in 0..*height {
                    let st = ((y as f64 + 0.5) / *height as f64 * std::f64::consts::PI).sin();
                    for x in 0..*width {
                        s += luminance(texels[y * width + x]) as f64 * st;
                        wsum += st;
                    }
                }
                (*scale as f64 * s / wsum.max(1e-30)) as f32
            }
            Environment::GaussianSky {
                sharpness,
                peak,
                ambient,
                ..
            } => {
                luminance(*ambient)
                    + luminance(*peak) * gaussian_lobe_integral(*sharpness) / (4.0 * PI)
            }
        }
    }
}

/// ∫ exp(κ (ω·d − 1)) dω over the sphere = 2π (1 − e^{−2κ}) / κ.
pub fn gaussian_lobe_integral(sharpness: f32) -> f32 {
    let k = sharpness.max(1e-4);
    2.0 * PI * (-(-2.0 * k).exp_m1()) / k
}

/// `scale ·` the bilinear lookup of a lat-long image along `d`; over duals the
/// lookup's exact derivative inside the current cell is chained with those of the
/// lat-long coordinates (u, v) (same convention as [`direction_to_latlong`]).
fn image_radiance<T: Scalar>(
    texels: &[Vec3],
    width: usize,
    height: usize,
    scale: f32,
    d: [T; 3],
) -> [T; 3] {
    let dir = Vec3::from_array(d.map(|c| c.value() as f32));
    let uv = direction_to_latlong(dir);
    let (val, dl_du, dl_dv) = bilinear_with_derivatives(texels, width, height, uv);
    let val = (val * scale).to_array();
    if !T::HAS_DERIVATIVES {
        return val.map(|c| T::constant(c as f64));
    }
    let (dl_du, dl_dv) = ((dl_du * scale).to_array(), (dl_dv * scale).to_array());
    let u = d[0].atan2(-d[2]).mul_const((1.0 / TAU) as f64);
    let v = (d[0] * d[0] + d[2] * d[2])
        .sqrt()
        .atan2(d[1])
        .mul_const((1.0 / PI) as f64);
    [0, 1, 2].map(|c| T::chain2(val[c] as f64, u, dl_du[c] as f64, v, dl_dv[c] as f64))
}

/// Bilinear lookup as Mitsuba 3's `envmap` does it: column i is centred at
/// u = (i + ½)/width and wraps around; row j sits at v = j/(height − 1), so the
/// first and last rows are exactly the poles.
pub fn bilinear(texels: &[Vec3], width: usize, height: usize, uv: Vec2) -> Vec3 {
    bilinear_with_derivatives(texels, width, height, uv).0
}

/// [`bilinear`] and its derivatives ∂L/∂u, ∂L/∂v inside the current cell (the
/// gradient stage differentiates environment radiance through them).
pub fn bilinear_with_derivatives(
    texels: &[Vec3],
    width: usize,
    height: usize,
    uv: Vec2,
) -> (Vec3, Vec3, Vec3) {
    let x = uv.x * width as f32 - 0.5;
    let rows = (height.max(2) - 1) as f32;
    let y = (uv.y * rows).clamp(0.0, (height - 1) as f32);
    let x0 = x.floor();
    let y0 = y.floor().min((height.max(2) - 2) as f32);
    let fx = x - x0;
    let fy = y - y0;
    let xi0 = (x0 as i64).rem_euclid(width as i64) as usize;
    let xi1 = (xi0 + 1) % width;
    let yi0 = y0 as usize;
    let yi1 = (yi0 + 1).min(height - 1);
    let t = |xx: usize, yy: usize| texels[yy * width + xx];
    let (t00, t10, t01, t11) = (t(xi0, yi0), t(xi1, yi0), t(xi0, yi1), t(xi1, yi1));
    let value = (t00 * (1.0 - fx) + t10 * fx) * (1.0 - fy) + (t01 * (1.0 - fx) + t11 * fx) * fy;
    let d_u = ((t10 - t00) * (1.0 - fy) + (t11 - t01) * fy) * width as f32;
    let d_v = ((t01 - t00) * (1.0 - fx) + (t11 - t10) * fx) * rows;
    (value, d_u, d_v)
}

/// The most texels an environment image may have (2²⁷, e.g. 16384 × 8192):
/// dimensions are checked from the file's header *before* any pixel memory is
/// allocated, so a header claiming 100000² pixels is an error, not an abort.
pub const MAX_TEXELS: u64 = 1 << 27;

fn check_dimensions(path: &Path, width: u64, height: u64) -> crate::Result<()> {
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_TEXELS {
        return Err(crate::Error::Asset {
            path: path.to_path_buf(),
            message: format!(
                "the header declares {width}×{height} texels; an environment image must have \
                 between 1 and {MAX_TEXELS} (scene::environment::MAX_TEXELS)"
            ),
        });
    }
    Ok(())
}

/// A Radiance `.hdr` image: the header is read and checked (dimensions, and the
/// file's length against what such an image can take) before any pixel data, so a
/// huge or lying file is refused without being read.
fn read_hdr(path: &Path) -> crate::Result<(usize, usize, Vec<Vec3>)> {
    use std::io::{BufReader, Read};
    let io = |source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let asset = |message: String| crate::Error::Asset {
        path: path.to_path_buf(),
        message,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut reader = BufReader::new(file);
    let mut signature = Vec::with_capacity(7);
    (&mut reader)
        .take(7)
        .read_to_end(&mut signature)
        .map_err(io)?;
    // Radiance files may start with "#?RGBE" (Mitsuba and others write it) as well
    // as "#?RADIANCE"; the `image` decoder accepts only the latter.
    if signature == b"#?RGBE\n" {
        signature = b"#?RADIANCE\n".to_vec();
    }
    let stream = BufReader::new(std::io::Cursor::new(signature).chain(reader));
    let decoder = image::codecs::hdr::HdrDecoder::new(stream)
        .map_err(|e| asset(format!("invalid .hdr image: {e}")))?;
    let meta = decoder.metadata();
    let (w, h) = (u64::from(meta.width), u64::from(meta.height));
    check_dimensions(path, w, h)?;
    // At most 4 bytes a texel, plus a 4-byte run-length header a scanline and one
    // count byte per 128 bytes of literal data; a header of at most 64 KiB.
    let most = 4 * w * h + (4 * w * h).div_ceil(128) + 4 * h + (64 << 10);
    if len > most {
        return Err(asset(format!(
            "the file is {len} bytes, more than a {w}×{h} Radiance image can take ({most})"
        )));
    }
    let img = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| asset(format!("invalid .hdr image: {e}")))?
        .into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let texels = img.pixels().map(|p| Vec3::from(p.0)).collect();
    Ok((w, h, texels))
}

/// The EXR's header sizes, read without touching pixel data.
fn check_exr_header(path: &Path) -> crate::Result<()> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| match e {
        exr::error::Error::Io(source) => crate::Error::Io {
            path: path.to_path_buf(),
            source,
        },
        other => crate::Error::Asset {
            path: path.to_path_buf(),
            message: format!("invalid .exr image: {other}"),
        },
    })?;
    for h in &meta.headers {
        check_dimensions(
            path,
            h.layer_size.width() as u64,
            h.layer_size.height() as u64,
        )?;
    }
    Ok(())
}

/// Reads a lat-long environment image: `.hdr` (Radiance RGBE, via `image`) or
/// `.exr` (RGB of the first layer, via `exr`). Row 0 is the zenith (see the
/// convention above). Texels must be finite and non-negative: one NaN texel would
/// otherwise poison every path that escapes towards it.
pub fn load_latlong(path: &Path, scale: f32) -> crate::Result<Environment> {
    let asset = |message: String| crate::Error::Asset {
        path: path.to_path_buf(),
        message,
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let (width, height, texels) = match ext.as_str() {
        "hdr" => read_hdr(path)?,
        "exr" => {
            check_exr_header(path)?;
            use exr::prelude::*;
            let img = read_first_rgba_layer_from_file(
                path,
                |res: exr::math::Vec2<usize>, _: &RgbaChannels| {
                    (res.width(), vec![Vec3::ZERO; res.width() * res.height()])
                },
                |(w, texels): &mut (usize, Vec<Vec3>),
                 pos: exr::math::Vec2<usize>,
                 (r, g, b, _a): (f32, f32, f32, f32)| {
                    texels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
                },
            )
            .map_err(|e| asset(format!("invalid .exr image: {e}")))?;
            let size = img.layer_data.size;
            let (_, texels) = img.layer_data.channel_data.pixels;
            (size.width(), size.height(), texels)
        }
        _ => {
            return Err(asset(format!(
                "unsupported environment image extension `.{ext}`; expected `.hdr` or `.exr`"
            )))
        }
    };
    if width == 0 || height == 0 || texels.len() != width * height {
        return Err(asset(format!(
            "empty or truncated image ({width}×{height})"
        )));
    }
    if let Some(i) = texels
        .iter()
        .position(|t| !(t.is_finite() && t.min_element() >= 0.0))
    {
        return Err(asset(format!(
            "texel ({}, {}) is {:?}; radiance must be finite and non-negative",
            i % width,
            i / width,
            texels[i]
        )));
    }
    Ok(Environment::Image {
        width,
        height,
        texels,
        scale,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_hits_texels_and_poles_and_derivatives_match() {
        let (w, h) = (4usize, 3usize);
        let texels: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::splat(i as f32 * i as f32))
            .collect();
        // Row 0 at the zenith, the last row at the nadir, columns at (i + ½)/w.
        assert_eq!(bilinear(&texels, w, h, Vec2::new(0.125, 0.0)), texels[0]);
        assert_eq!(
            bilinear(&texels, w, h, Vec2::new(0.375, 1.0)),
            texels[2 * w + 1]
        );
        assert_eq!(
            bilinear(&texels, w, h, Vec2::new(0.625, 0.5)),
            texels[w + 2]
        );
        let p = Vec2::new(0.41, 0.63);
        let (_, du, dv) = bilinear_with_derivatives(&texels, w, h, p);
        let e = 1e-3;
        let fd_u = (bilinear(&texels, w, h, p + Vec2::X * e)
            - bilinear(&texels, w, h, p - Vec2::X * e))
            / (2.0 * e);
        let fd_v = (bilinear(&texels, w, h, p + Vec2::Y * e)
            - bilinear(&texels, w, h, p - Vec2::Y * e))
            / (2.0 * e);
        assert!((fd_u - du).length() < 1e-2 * du.length(), "{fd_u} vs {du}");
        assert!((fd_v - dv).length() < 1e-2 * dv.length(), "{fd_v} vs {dv}");
    }

    #[test]
    fn rgbe_signature_hdr_files_load() {
        let dir = std::env::temp_dir().join(format!("gradtrace-rgbe-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tiny.hdr");
        let mut bytes = b"#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
        bytes.extend_from_slice(&[128, 128, 128, 129, 128, 64, 32, 130]);
        std::fs::write(&path, bytes).unwrap();
        let env = load_latlong(&path, 1.0).unwrap();
        let Environment::Image {
            width,
            height,
            texels,
            ..
        } = env
        else {
            panic!("not an image")
        };
        assert_eq!((width, height), (2, 1));
        assert!(
            (texels[0] - Vec3::ONE).abs().max_element() < 0.01,
            "{:?}",
            texels[0]
        );
        assert!(
            (texels[1] - Vec3::new(2.0, 1.0, 0.5)).abs().max_element() < 0.02,
            "{:?}",
            texels[1]
        );
        // The same image followed by 1 MiB the header does not account for: refused
        // before the pixels are decoded, naming the sizes.
        let padded = dir.join("padded.hdr");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes.resize(bytes.len() + (1 << 20), 0);
        std::fs::write(&padded, bytes).unwrap();
        let msg = load_latlong(&padded, 1.0).unwrap_err().to_string();
        assert!(
            msg.contains("padded.hdr") && msg.contains("2×1 Radiance image"),
            "{msg}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn latlong_round_trip_and_mitsuba_convention() {
        for &d in &[
            Vec3::new(0.3, 0.5, -0.8).normalize(),
            Vec3::new(-0.7, -0.1, 0.2).normalize(),
            Vec3::new(0.0, 0.2, 1.0).normalize(),
        ] {
            let back = latlong_to_direction(direction_to_latlong(d));
            assert!((back - d).length() < 1e-5, "{d:?} -> {back:?}");
        }
        // u = 0 looks along −z; v = 0 is +y.
        assert!((latlong_to_direction(Vec2::new(0.0, 0.5)) - Vec3::NEG_Z).length() < 1e-6);
        assert!((latlong_to_direction(Vec2::new(0.25, 0.5)) - Vec3::X).length() < 1e-6);
        assert!(latlong_to_direction(Vec2::new(0.7, 0.0)).y > 0.999);
    }
}
