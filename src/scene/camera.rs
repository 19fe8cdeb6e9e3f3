//! Pinhole look-at camera: pixel position → primary ray.

use crate::math::{cross, Ray, Vec2, Vec3};

/// A pinhole camera. `fov_y` is the full vertical field of view in degrees; image
/// x grows to the right and y grows downwards (row 0 is the top row).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub from: Vec3,
    pub to: Vec3,
    pub up: Vec3,
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
    // Derived basis, kept so ray generation is a few multiply-adds.
    right: Vec3,
    true_up: Vec3,
    forward: Vec3,
    tan_half: f32,
}

impl Camera {
    /// Builds the camera; fails (with a message for the caller to place) when the
    /// look-at is degenerate.
    pub fn new(
        from: Vec3,
        to: Vec3,
        up: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, String> {
        let forward = (to - from).normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err("`from` and `to` must differ".into());
        }
        let right = cross(forward, up).normalize_or_zero();
        if right == Vec3::ZERO {
            return Err("`up` must not be parallel to the viewing direction".into());
        }
        if !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(format!("`fov` must be in (0, 180) degrees, got {fov_y}"));
        }
        if width == 0 || height == 0 {
            return Err("resolution must be at least 1×1".into());
        }
        let true_up = cross(right, forward);
        Ok(Self {
            from,
            to,
            up,
            fov_y,
            width,
            height,
            right,
            true_up,
            forward,
            tan_half: (fov_y.to_radians() * 0.5).tan(),
        })
    }

    /// Same camera at another resolution (the vertical field of view is kept).
    pub fn with_resolution(&self, width: u32, height: u32) -> Result<Self, String> {
        Self::new(self.from, self.to, self.up, self.fov_y, width, height)
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Unit direction through the image-plane point `p` (in pixels, (0,0) = top-left
    /// corner of the image, (width, height) = bottom-right).
    pub fn direction(&self, p: Vec2) -> Vec3 {
        let ndc_x = (2.0 * p.x / self.width as f32 - 1.0) * self.tan_half * self.aspect();
        let ndc_y = (1.0 - 2.0 * p.y / self.height as f32) * self.tan_half;
        (self.forward + ndc_x * self.right + ndc_y * self.true_up).normalize()
    }

    /// Derivatives of the (unnormalised) direction with respect to the pixel
    /// coordinates; ray differentials for the gradient stages start from these.
    pub fn direction_derivatives(&self) -> [Vec3; 2] {
        let dx = self.right * (2.0 * self.tan_half * self.aspect() / self.width as f32);
        let dy = -self.true_up * (2.0 * self.tan_half / self.height as f32);
        [dx, dy]
    }

    pub fn generate_ray(&self, p: Vec2) -> Ray {
        Ray::new(self.from, self.direction(p))
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// `x − from` in the camera's frame (right, up, forward), in f64: the
    /// rasteriser's input (`preview::raster`), whose depth is the forward component.
    pub fn view_coordinates(&self, x: Vec3) -> glam::DVec3 {
        let d = x.as_dvec3() - self.from.as_dvec3();
        glam::DVec3::new(
            d.dot(self.right.as_dvec3()),
            d.dot(self.true_up.as_dvec3()),
            d.dot(self.forward.as_dvec3()),
        )
    }

    /// The continuous pixel position of a point given in view coordinates with a
    /// positive depth.
    pub fn view_to_pixel(&self, v: glam::DVec3) -> glam::DVec2 {
        let slopes = self.frustum_slopes().as_dvec2();
        let sx = v.x / (v.z * slopes.x);
        let sy = v.y / (v.z * slopes.y);
        glam::DVec2::new(
            (sx + 1.0) * 0.5 * self.width as f64,
            (1.0 - sy) * 0.5 * self.height as f64,
        )
    }

    /// Half-extents of the image plane at unit depth (x, y): the view frustum.
    pub fn frustum_slopes(&self) -> Vec2 {
        Vec2::new(self.tan_half * self.aspect(), self.tan_half)
    }

    /// Projects a world point to image coordinates (pixels); `None` if behind.
    pub fn project(&self, x: Vec3) -> Option<Vec2> {
        let v = self.view_coordinates(x);
        (v.z > 0.0).then(|| self.view_to_pixel(v).as_vec2())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_forward_and_projection_inverts() {
        let c = Camera::new(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 64, 32).unwrap();
        let d = c.direction(Vec2::new(32.0, 16.0));
        assert!((d - c.forward()).length() < 1e-6);
        let p = Vec2::new(10.5, 3.25);
        let x = c.from + 3.0 * c.direction(p);
        assert!((c.project(x).unwrap() - p).length() < 1e-3);
        // Top edge is fov/2 above the axis.
        let top = c.direction(Vec2::new(32.0, 0.0));
        assert!((top.dot(c.forward()).acos().to_degrees() - 20.0).abs() < 1e-3);
    }

    #[test]
    fn degenerate_cameras_are_rejected() {
        assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0, 8, 8).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 8, 8).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 8, 8).is_err());
    }
}
