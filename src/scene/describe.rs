//! The `info` report of a scene: one fact per line, each beside the type it
//! describes (materials in `brdf`, the environment and the scene here).

use super::{Environment, Integrator, Scene};
use crate::brdf::display::V3;
use crate::math::Vec3;
use std::fmt::{self, Write};

impl fmt::Display for Environment {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Environment::Constant { radiance } => write!(f, "constant radiance={}", V3(*radiance)),
            Environment::Image {
                width,
                height,
                scale,
                ..
            } => write!(f, "image {width}x{height} scale={scale}"),
            Environment::GaussianSky {
                direction,
                sharpness,
                peak,
                ambient,
            } => write!(
                f,
                "gaussian_sky direction={} sharpness={sharpness} peak={} ambient={}",
                V3(*direction),
                V3(*peak),
                V3(*ambient)
            ),
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Scene {
    /// Geometry, materials, emitters, environment, bump maps, camera and render
    /// settings, one fact per line (`info` adds the renderer's and the BVH's).
    pub fn describe(&self) -> String {
        let mut o = String::new();
        // Writing to a String cannot fail.
        let _ = self.write_description(&mut o);
        o
    }

    fn write_description(&self, o: &mut String) -> fmt::Result {
        let s = self;
        let with_normals = s.stats.meshes_with_normals;
        writeln!(o, "scene: {}", s.path.display())?;
        writeln!(
            o,
            "triangles: {} ({} degenerate skipped)",
            s.stats.triangles, s.stats.degenerate_triangles
        )?;
        writeln!(o, "spheres: {}", s.spheres.len())?;
        writeln!(
            o,
            "meshes: {} ({with_normals} with normals, {} without)",
            s.meshes.len(),
            s.meshes.len() - with_normals
        )?;
        // World space, after each shape's transform: where a mesh ended up is
        // what a misplaced model needs to be found by.
        for m in &s.meshes {
            let (lo, hi) = m.positions.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            writeln!(
                o,
                "  {}: {} triangles, bounds {} to {}",
                m.name,
                m.triangles.len(),
                V3(lo),
                V3(hi)
            )?;
        }
        writeln!(o, "materials: {}", s.materials.len())?;
        for (i, m) in s.materials.iter().enumerate() {
            let name = s.material_names.get(i).map(String::as_str).unwrap_or("?");
            writeln!(o, "  {name}: {m}")?;
        }
        writeln!(o, "emitters: {}", s.emitter_count())?;
        for m in s.meshes.iter().filter(|m| m.emission != Vec3::ZERO) {
            let shape = if m.rect.is_some() { "rect" } else { "mesh" };
            let (n, e) = (m.triangles.len(), V3(m.emission));
            writeln!(o, "  {} ({shape}, {n} triangles): radiance={e}", m.name)?;
        }
        for sp in s.spheres.iter().filter(|sp| sp.emission != Vec3::ZERO) {
            let e = V3(sp.emission);
            writeln!(o, "  {} (sphere r={}): radiance={e}", sp.name, sp.radius)?;
        }
        match &s.environment {
            None => writeln!(o, "environment: none (black)")?,
            Some(e) => writeln!(o, "environment: {e}")?,
        }
        writeln!(o, "bump maps: {}", s.bumps.len())?;
        for (i, b) in s.bumps.iter().enumerate() {
            let users: Vec<&str> = s
                .meshes
                .iter()
                .filter(|m| m.bump == Some(i as u32))
                .map(|m| m.name.as_str())
                .chain(
                    s.spheres
                        .iter()
                        .filter(|sp| sp.bump == Some(i as u32))
                        .map(|sp| sp.name.as_str()),
                )
                .collect();
            let (name, n) = (&b.name, b.terms.len());
            writeln!(o, "  {name}: {n} sinusoids, used by [{}]", users.join(", "))?;
        }
        let c = &s.camera;
        writeln!(
            o,
            "camera: from={} to={} up={} fov_y={} deg, {}x{}",
            V3(c.from),
            V3(c.to),
            V3(c.up),
            c.fov_y,
            c.width,
            c.height
        )?;
        let r = &s.settings;
        writeln!(
            o,
            "render: spp={} max_depth={} seed={} integrator={} rr_depth={}",
            r.spp, r.max_depth, r.seed, r.integrator, r.rr_depth
        )
    }
}
