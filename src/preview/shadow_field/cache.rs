//! Precomputed fields ↔ bytes, for the on-disk cache. The layout (entities, grids,
//! vertex counts) follows from the scene and the settings, which key the cache, so
//! only the coefficient arrays are stored, each with its length; a file that does
//! not fit is reported as `None` and recomputed.

use super::field::{ConeMap, Field};
use super::precompute::{grid_for, Entity, EntityFields, EntityKind};
use super::{Fields, Settings};
use crate::math::sh::{ShF, COEFFS};
use crate::scene::Scene;

const MAGIC: &[u8; 8] = b"GTSHFLD2";

fn put_block(out: &mut Vec<u8>, data: &[ShF]) {
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    for c in data {
        for x in c {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// Serialises every coefficient array of `fields`.
pub fn to_bytes(fields: &Fields) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    for f in &fields.fields {
        let empty: &[ShF] = &[];
        put_block(&mut out, f.occlusion.as_ref().map_or(empty, |o| &o.data));
        for c in 0..3 {
            put_block(&mut out, f.radiance.as_ref().map_or(empty, |r| &r[c].data));
        }
        out.extend_from_slice(&(f.self_occlusion.len() as u64).to_le_bytes());
        for s in &f.self_occlusion {
            put_block(&mut out, s);
        }
        let bits = f.visibility.as_ref().map_or(&[][..], |v| &v.bits[..]);
        out.extend_from_slice(&(bits.len() as u64).to_le_bytes());
        for w in bits {
            out.extend_from_slice(&w.to_le_bytes());
        }
    }
    out
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn u64(&mut self) -> Option<u64> {
        let b = self.bytes.get(self.at..self.at + 8)?;
        self.at += 8;
        Some(u64::from_le_bytes(b.try_into().ok()?))
    }

    fn words(&mut self, want: usize) -> Option<Vec<u64>> {
        if self.u64()? as usize != want {
            return None;
        }
        (0..want).map(|_| self.u64()).collect()
    }

    fn block(&mut self, want: usize) -> Option<Vec<ShF>> {
        if self.u64()? as usize != want {
            return None;
        }
        let n = want * COEFFS * 4;
        let b = self.bytes.get(self.at..self.at + n)?;
        self.at += n;
        let mut out = Vec::with_capacity(want);
        for chunk in b.chunks_exact(COEFFS * 4) {
            let mut c = [0.0f32; COEFFS];
            for (k, x) in chunk.chunks_exact(4).enumerate() {
                c[k] = f32::from_le_bytes(x.try_into().ok()?);
            }
            if !c.iter().all(|x| x.is_finite()) {
                return None;
            }
            out.push(c);
        }
        Some(out)
    }
}

/// Reads fields serialised by [`to_bytes`] for `entities` of `scene` under
/// `settings`; `None` when anything does not fit.
pub fn from_bytes(
    bytes: &[u8],
    scene: &Scene,
    entities: &[Entity],
    settings: &Settings,
) -> Option<Fields> {
    if bytes.get(..8)? != MAGIC {
        return None;
    }
    let mut r = Reader { bytes, at: 8 };
    let mut out = Vec::with_capacity(entities.len());
    for e in entities {
        let grid = grid_for(e, settings);
        let has_occ = !matches!(e.kind, EntityKind::Quad(_));
        let is_light = e.kind == EntityKind::Light;
        let field = |r: &mut Reader, present: bool| -> Option<Option<Field>> {
            let data = r.block(if present { grid.len() } else { 0 })?;
            Some(present.then_some(Field { grid, data }))
        };
        let occlusion = field(&mut r, has_occ)?;
        let rr = field(&mut r, is_light)?;
        let g = field(&mut r, is_light)?;
        let b = field(&mut r, is_light)?;
        let radiance = match (rr, g, b) {
            (Some(rr), Some(g), Some(b)) => Some([rr, g, b]),
            _ => None,
        };
        let verts: Vec<usize> = if e.kind == EntityKind::Occluder {
            e.meshes
                .iter()
                .map(|&m| scene.meshes[m].positions.len())
                .collect()
        } else {
            Vec::new()
        };
        if r.u64()? as usize != verts.len() {
            return None;
        }
        let mut self_occlusion = Vec::with_capacity(verts.len());
        for n in verts {
            self_occlusion.push(r.block(n)?);
        }
        let side = settings.rays;
        let words = if has_occ {
            grid.len() * ConeMap::words(side)
        } else {
            0
        };
        let bits = r.words(words)?;
        out.push(EntityFields {
            occlusion,
            radiance,
            self_occlusion,
            visibility: has_occ.then_some(ConeMap { grid, side, bits }),
        });
    }
    (r.at == bytes.len()).then(|| Fields {
        entities: entities.to_vec(),
        fields: out,
    })
}
