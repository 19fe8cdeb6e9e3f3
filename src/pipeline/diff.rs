//! `gradtrace diff A.exr B.exr` (like pbrt-v4's `imgtool diff`): two EXRs' beauty
//! → RMSE, relMSE (also trimmed), FLIP, an error-map PNG, and pass/fail against
//! a threshold. `B` is the reference: relMSE divides by B², FLIP's reference is B.

use crate::math::Vec3;
use crate::output::colormap::viridis8;
use crate::output::metrics::{self, RELMSE_EPS};
use crate::output::names::RGB;
use crate::output::{read_exr_input, stage_png_rgb8};
use crate::{Error, Result};
use std::fmt;
use std::path::{Path, PathBuf};

/// The share of pixels with the highest error the trimmed relMSE leaves out
/// (0.01 %): enough to drop a few fireflies, too few to hide a real difference.
pub const TRIM_FRACTION: f64 = 1e-4;

/// The metric `--threshold` applies to, and the one the error map shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiffMetric {
    Rmse,
    Relmse,
    Flip,
}

impl DiffMetric {
    pub const ALL: [DiffMetric; 3] = [DiffMetric::Rmse, DiffMetric::Relmse, DiffMetric::Flip];

    pub fn name(self) -> &'static str {
        match self {
            DiffMetric::Rmse => "rmse",
            DiffMetric::Relmse => "relmse",
            DiffMetric::Flip => "flip",
        }
    }
}

/// What `diff` is asked to do besides measuring.
#[derive(Clone, Debug)]
pub struct DiffOptions {
    pub metric: DiffMetric,
    /// Fail (exit status 1) when the metric is above this.
    pub threshold: Option<f32>,
    /// The error-map PNG \[default: `<A's stem>.diff.png` beside A\].
    pub error_map: Option<PathBuf>,
}

/// The figures of one comparison.
#[derive(Clone, Debug)]
pub struct DiffReport {
    pub image: PathBuf,
    pub reference: PathBuf,
    pub width: usize,
    pub height: usize,
    pub rmse: f32,
    /// With ε = [`RELMSE_EPS`].
    pub relmse: f32,
    /// relMSE without the [`TRIM_FRACTION`] of pixels with the highest error.
    pub relmse_trimmed: f32,
    /// Mean LDR-FLIP at exposure 0.
    pub flip: f32,
    pub metric: DiffMetric,
    pub threshold: Option<f32>,
    pub error_map: PathBuf,
    /// The per-pixel error that maps to the top of the colour scale.
    pub error_map_scale: f32,
}

impl DiffReport {
    /// The value of the thresholded metric.
    pub fn value(&self) -> f32 {
        match self.metric {
            DiffMetric::Rmse => self.rmse,
            DiffMetric::Relmse => self.relmse,
            DiffMetric::Flip => self.flip,
        }
    }

    /// Whether the metric is above the threshold (the run then fails).
    pub fn exceeds_threshold(&self) -> bool {
        self.threshold.is_some_and(|t| self.value() > t)
    }

    /// Why the run fails, when the metric is above the threshold.
    pub fn threshold_error(&self) -> Option<String> {
        self.exceeds_threshold().then(|| {
            format!(
                "{} differs from {}: {} {:.6e} is above --threshold {}",
                self.image.display(),
                self.reference.display(),
                self.metric.name(),
                self.value(),
                self.threshold.unwrap_or_default()
            )
        })
    }
}

impl fmt::Display for DiffReport {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        writeln!(
            f,
            "{} against {} (reference), {}x{}",
            self.image.display(),
            self.reference.display(),
            self.width,
            self.height
        )?;
        writeln!(f, "rmse            {:.6e}", self.rmse)?;
        writeln!(
            f,
            "relmse          {:.6e}  (eps = {RELMSE_EPS})",
            self.relmse
        )?;
        writeln!(
            f,
            "relmse_trimmed  {:.6e}  ({}% highest pixels left out)",
            self.relmse_trimmed,
            TRIM_FRACTION * 100.0
        )?;
        writeln!(
            f,
            "flip            {:.6e}  (LDR-FLIP, exposure 0)",
            self.flip
        )?;
        write!(
            f,
            "error map       {} ({} per pixel, viridis 0 to {:.3e})",
            self.error_map.display(),
            self.metric.name(),
            self.error_map_scale
        )?;
        if let Some(t) = self.threshold {
            let verdict = if self.exceeds_threshold() {
                "above"
            } else {
                "within"
            };
            write!(
                f,
                "\n{} {:.6e} is {verdict} the threshold {t}",
                self.metric.name(),
                self.value()
            )?;
        }
        Ok(())
    }
}

/// Reads both EXRs, measures `image` against `reference` and writes the error
/// map. Every input problem (unreadable file, no `R,G,B`, non-finite pixels,
/// different sizes) is one error naming the file, found before anything is
/// written.
pub fn run(image: &Path, reference: &Path, opts: &DiffOptions) -> Result<DiffReport> {
    if let Some(t) = opts.threshold.filter(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(Error::Option {
            option: "--threshold".into(),
            message: format!("must be a finite number >= 0, got {t}"),
        });
    }
    let map_path = error_map_path(image, reference, opts.error_map.as_deref())?;
    let (a, w, h, wa) = read_beauty(image, &map_path)?;
    let (b, wb, hb, wr) = read_beauty(reference, &map_path)?;
    if (w, h) != (wb, hb) {
        return Err(Error::Asset {
            path: reference.to_path_buf(),
            message: format!(
                "is {wb}x{hb} but {} is {w}x{h}; diff needs two images of one size",
                image.display()
            ),
        });
    }
    // Two tiles of one size at different places are different pixels.
    if wa != wr {
        let at = |(d, o): DataWindow| {
            format!(
                "pixels {},{},{},{} of a {}x{} image",
                o.0,
                o.1,
                o.0 + w,
                o.1 + h,
                d.0,
                d.1
            )
        };
        return Err(Error::Asset {
            path: reference.to_path_buf(),
            message: format!(
                "covers {} but {} covers {}; diff needs two images of one data window",
                at(wr),
                image.display(),
                at(wa)
            ),
        });
    }
    let (per_pixel, scale) = per_pixel_error(&a, &b, w, h, opts.metric)?;
    let rgb8: Vec<u8> = per_pixel.iter().flat_map(|e| viridis8(e / scale)).collect();
    stage_png_rgb8(&map_path, &rgb8, w, h)?.commit()?;
    Ok(DiffReport {
        image: image.to_path_buf(),
        reference: reference.to_path_buf(),
        width: w,
        height: h,
        rmse: metrics::rmse(&a, &b)?,
        relmse: metrics::relmse(&a, &b)?,
        relmse_trimmed: metrics::relmse_trimmed(&a, &b, TRIM_FRACTION)?,
        flip: metrics::flip(&a, &b, w, h)?,
        metric: opts.metric,
        threshold: opts.threshold,
        error_map: map_path,
        error_map_scale: scale,
    })
}

/// `--error-map`, or `<A's stem>.diff.png` beside A; never one of the inputs.
fn error_map_path(image: &Path, reference: &Path, given: Option<&Path>) -> Result<PathBuf> {
    let path = match given {
        Some(p) => p.to_path_buf(),
        None => {
            let stem = image
                .file_stem()
                .map_or("image".into(), |s| s.to_string_lossy());
            image.with_file_name(format!("{stem}.diff.png"))
        }
    };
    let option_err = |message: String| Error::Option {
        option: "--error-map".into(),
        message,
    };
    if path.file_name().is_none() || path.is_dir() {
        return Err(option_err(format!(
            "{}: does not name a file",
            path.display()
        )));
    }
    if path == image || path == reference {
        return Err(option_err(format!(
            "{}: is one of the inputs",
            path.display()
        )));
    }
    // The same file under another spelling (`./a.exr`) is caught when the
    // inputs are opened, by device and inode.
    crate::output::input::check_output_target(&path, "--error-map")?;
    Ok(path)
}

/// An image's display window size and its data window's origin in it.
type DataWindow = ((usize, usize), (usize, usize));

/// The beauty `R,G,B` of an EXR, checked finite, and its data window; errors
/// name the file. `map` is the error map, which it must not be.
fn read_beauty(path: &Path, map: &Path) -> Result<(Vec<Vec3>, usize, usize, DataWindow)> {
    let (img, header) = read_exr_input(path, &[map])?;
    let display = header.display_or(img.width, img.height);
    let asset_err = |message: String| Error::Asset {
        path: path.to_path_buf(),
        message,
    };
    let Some(rgb) = img.vec3("", RGB) else {
        let mut names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
        names.truncate(8);
        return Err(asset_err(format!(
            "has no beauty channels R, G, B (it holds: {})",
            names.join(", ")
        )));
    };
    if let Some(i) = rgb.iter().position(|p| !p.is_finite()) {
        return Err(asset_err(format!(
            "pixel ({}, {}) of R, G, B is not finite ({})",
            i % img.width,
            i / img.width,
            rgb[i]
        )));
    }
    Ok((rgb, img.width, img.height, (display, header.origin)))
}

/// The per-pixel error of `metric` and the value shown at the top of the
/// colour scale: FLIP is already in [0, 1]; RMSE (root of the channel mean of
/// squares) and relMSE (channel mean of squared ratios) use their 99th
/// percentile, so a few fireflies cannot turn the rest of the map black, or
/// their maximum where fewer than 1 % of the pixels differ.
fn per_pixel_error(
    a: &[Vec3],
    b: &[Vec3],
    w: usize,
    h: usize,
    metric: DiffMetric,
) -> Result<(Vec<f32>, f32)> {
    let eps = RELMSE_EPS;
    let errors: Vec<f32> = match metric {
        DiffMetric::Flip => return Ok((metrics::flip_map(a, b, w, h, 0.0)?, 1.0)),
        DiffMetric::Rmse => a
            .iter()
            .zip(b)
            .map(|(x, r)| (metrics::sq_dist_f64(*x, *r) / 3.0).sqrt() as f32)
            .collect(),
        DiffMetric::Relmse => a
            .iter()
            .zip(b)
            .map(|(x, r)| {
                let sum: f64 = (0..3)
                    .map(|k| {
                        let (x, r) = (f64::from(x[k]), f64::from(r[k]));
                        (x - r) * (x - r) / (r * r + f64::from(eps))
                    })
                    .sum();
                (sum / 3.0) as f32
            })
            .collect(),
    };
    let mut sorted = errors.clone();
    let k = ((sorted.len() as f64 * 0.99) as usize).min(sorted.len() - 1);
    let p99 = *sorted.select_nth_unstable_by(k, f32::total_cmp).1;
    let max = sorted
        .iter()
        .copied()
        .filter(|e| e.is_finite())
        .fold(0.0, f32::max);
    let usable = |s: &f32| *s > 0.0 && s.is_finite();
    let scale = [p99, max].into_iter().find(usable).unwrap_or(1.0);
    Ok((errors, scale))
}
