//! samples → pixels: Delaunay triangulation of the sample positions (spade) and
//! interpolation at every pixel centre, linear or gradient-aware C1 (Sec. 8.1, 9.1).
//!
//! * [`Interpolation::Linear`]: barycentric interpolation in the Delaunay triangle that
//!   contains the pixel centre — the paper's "simple linear interpolation" baseline.
//! * [`Interpolation::Gradient`]: Sibson's C1 natural-neighbour interpolant (flatness
//!   0.5) fed with the samples' analytic gradients ∂I/∂u, ∂I/∂v. It reproduces linear
//!   functions (exactly but for the vertex nudge below) and follows the first-order
//!   Taylor expansion near every sample, which is what makes sparse gradient samples
//!   worth more than plain values (Fig. 13).
//!
//! **Silhouettes.** A pixel is never interpolated across surfaces. Two samples are on
//! the same surface when they have the same object id, lie on the same side of a bump
//! map's terminator (`SampleValue::surface_id`), are both background or both not, do
//! not lie on two facets of a flat-shaded surface (a crease) and have no depth step
//! between them (read off their tangent planes with `SampleSet::depth_tolerance`):
//! `adaptive::surfaces_differ`, the same test the quadtree uses to force
//! refinement. Of the samples that would contribute (the triangle's corners, or
//! the natural neighbours), the pixel takes the surface that carries the largest share
//! of the interpolation weight (each contributing sample is tried as the anchor of a
//! group; ties go to the heavier anchor), keeps only that surface's samples and
//! renormalises their weights. Where all contributors share a surface nothing changes.
//!
//! **The image border.** Samples whose cells touch the border are mirrored across it
//! (`add_border_ghosts`), so the hull covers every pixel centre of a quadtree or
//! stratified set. **Gradients** are Barth–Jespersen limited first (`limit_gradients`)
//! so that one noisy Monte Carlo gradient cannot paint a blob.
//!
//! **Outside the convex hull** of the samples (only for sets whose cells do not tile
//! the image) the image is extrapolated from the nearest sample `s`:
//! `Linear` extends the plane of the best-shaped triangle around `s` whose corners all
//! lie on `s`'s surface (the one whose smallest barycentric weight is largest), or
//! takes `s`'s value if there is none; `Gradient` blends the first-order Taylor
//! expansions `I_k + J_k (p − p_k)` of `s` and its same-surface Delaunay neighbours with
//! weights `1/|p − p_k|²`. Both are exact on linear images (up to the vertex nudge
//! below: |∇I|·2⁻²⁰ px).
//!
//! **Determinism and speed.** Rows run in parallel; inside a row the pixels are located
//! in scanline order (first in the previous pixel's triangle, else by a walk from a
//! vertex of the previous pixel's answer), and each row starts from a hint computed
//! sequentially beforehand. A walk then depends only on the row, never on which thread
//! ran it, so the image is bit-identical for any thread count. The triangulation's
//! vertices are nudged by at most 2⁻²⁰ px (`Node::new`) so that the lattice of
//! quadtree samples has no cocircular quadruples for the in-circle test to resolve
//! exactly; natural-neighbour weights come from `natural` (spade's algorithm with
//! each triangle's circumcircle computed once); a pixel centre that carries a sample
//! takes its value directly.

mod hint;
mod natural;
pub mod poisson;

use crate::adaptive::{surfaces_differ, SampleSet, SurfacePoint};
use crate::math::sampler::hash2;
use crate::math::{Vec2, Vec3};
use crate::{Error, Result};
use glam::{DVec2, DVec3};
use hint::ScanlineHint;
use natural::Circumcentres;
use rayon::prelude::*;
use spade::handles::{
    FixedFaceHandle, FixedUndirectedEdgeHandle, FixedVertexHandle, InnerTag, VertexHandle,
};
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};

/// How pixel values are interpolated from the samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Interpolation {
    /// Barycentric (piecewise linear over the Delaunay triangles); ignores gradients.
    Linear,
    /// Sibson C1 natural-neighbour interpolation with the samples' analytic gradients.
    Gradient,
}

impl Interpolation {
    pub const ALL: [Interpolation; 2] = [Interpolation::Linear, Interpolation::Gradient];

    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Linear => "linear",
            Interpolation::Gradient => "gradient",
        }
    }
}

/// The reconstructed image and the sample-density plane, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Reconstruction {
    pub width: usize,
    pub height: usize,
    pub image: Vec<Vec3>,
    /// Samples per pixel (`SampleSet::density`): the `samples.density` EXR plane.
    pub density: Vec<f32>,
}

/// The largest shift of a triangulation vertex along each axis, in pixels (2⁻²⁰).
const NUDGE: f64 = 1.0 / (1u64 << 20) as f64;

/// A triangulation vertex: a sample position and the sample's index.
#[derive(Clone, Copy, Debug)]
struct Node {
    pos: Point2<f64>,
    idx: u32,
}

impl Node {
    /// The vertex of sample `idx` at `p`, moved by at most 2⁻²⁰ px (the same way for
    /// the same position, so duplicates stay duplicates).
    ///
    /// Quadtree samples sit on regular lattices, so four of them are often exactly
    /// cocircular; spade's robust in-circle test then cannot decide in floating point
    /// and falls back to exact arithmetic, which was two thirds of the triangulation's
    /// cost. A perturbation far below any pixel feature makes every such test
    /// decidable at once; the triangulation is then one of the equally valid choices
    /// for the degenerate input, and natural-neighbour weights, which are continuous
    /// in the positions, move by ~1e-6. The C1 formula and the extrapolations read
    /// the exact positions (`Data::pos`); barycentric and natural-neighbour weights
    /// come from the nudged ones, so linear mode reproduces a linear image to
    /// |∇I|·2⁻²⁰·√2 rather than to rounding.
    fn new(p: DVec2, idx: u32) -> Self {
        let (x, y) = ((p.x as f32).to_bits(), (p.y as f32).to_bits());
        let h = hash2(x, y.rotate_left(7) ^ 0x5bd1_e995);
        // Two signed bytes, in units of NUDGE / 128.
        let step = |b: u32| f64::from(b as u8 as i8) * (NUDGE / 128.0);
        Self {
            pos: Point2::new(p.x + step(h), p.y + step(h >> 8)),
            idx,
        }
    }
}

impl HasPosition for Node {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

type Dt = DelaunayTriangulation<Node, (), (), (), ScanlineHint>;
type VHandle<'a> = VertexHandle<'a, Node, (), (), ()>;

/// Per-sample data the interpolation reads, in f64.
struct Data {
    pos: Vec<DVec2>,
    value: Vec<DVec3>,
    grad_u: Vec<DVec3>,
    grad_v: Vec<DVec3>,
    /// Surface id, inverse depth, tangent plane and facet normal of each sample, for
    /// [`surfaces_differ`].
    surface: Vec<SurfacePoint>,
    /// `SampleSet::depth_tolerance` (see `surfaces_differ`).
    tolerance: f32,
    /// Whether a sample has a Delaunay neighbour on another surface (filled by the
    /// slope limiter, or after the ghosts are in where it does not run). A pixel
    /// whose contributing samples all have none lies away from every boundary and
    /// keeps them all.
    near_boundary: Vec<bool>,
}

impl Data {
    /// Whether samples `a` and `b` lie on different surfaces (the quadtree's test).
    fn differ(&self, a: usize, b: usize) -> bool {
        surfaces_differ(&self.surface[a], &self.surface[b], self.tolerance)
    }
}

/// Interpolates the samples to every pixel centre `(x + 0.5, y + 0.5)`.
///
/// Errors: an empty image or sample set, a non-finite sample position, or positions
/// spade rejects (magnitudes beyond ~1e20 or below ~1e-20 other than zero).
pub fn reconstruct(set: &SampleSet, mode: Interpolation) -> Result<Reconstruction> {
    reconstruct_with(set, mode, &Options::default())
}

/// Switches of [`reconstruct_with`]; the default is what the renderer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Barth–Jespersen limiting of the sample gradients before `Gradient`
    /// interpolation (see `limit_gradients`); off gives Sibson's interpolant with
    /// the gradients exactly as sampled.
    pub slope_limiter: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            slope_limiter: true,
        }
    }
}

/// [`reconstruct`] with explicit [`Options`].
pub fn reconstruct_with(
    set: &SampleSet,
    mode: Interpolation,
    options: &Options,
) -> Result<Reconstruction> {
    let (w, h) = (set.width as usize, set.height as usize);
    let bad = |message: String| Error::Option {
        option: "samples".into(),
        message,
    };
    if w == 0 || h == 0 || set.samples.is_empty() {
        return Err(bad(format!(
            "cannot reconstruct a {w}x{h} image from {} samples",
            set.samples.len()
        )));
    }
    if let Some(s) = set.samples.iter().find(|s| !s.pos.is_finite()) {
        return Err(bad(format!("sample position {} is not finite", s.pos)));
    }
    let d = |v: Vec3| v.as_dvec3();
    let mut data = Data {
        pos: set.samples.iter().map(|s| s.pos.as_dvec2()).collect(),
        value: set.samples.iter().map(|s| d(s.value.radiance)).collect(),
        grad_u: set.samples.iter().map(|s| d(s.value.grad_u)).collect(),
        grad_v: set.samples.iter().map(|s| d(s.value.grad_v)).collect(),
        surface: set
            .samples
            .iter()
            .map(|s| s.value.surface_point(s.pos))
            .collect(),
        tolerance: set.depth_tolerance,
        near_boundary: Vec::new(),
    };
    let nodes: Vec<Node> = data
        .pos
        .iter()
        .enumerate()
        .map(|(i, &p)| Node::new(p, i as u32))
        .collect();
    // `bulk_load_stable` keeps the first of duplicate positions, so a duplicated
    // sample simply does not take part.
    let mut dt =
        Dt::bulk_load_stable(nodes).map_err(|e| bad(format!("triangulation failed: {e:?}")))?;
    let limited = mode == Interpolation::Gradient && options.slope_limiter;
    if limited {
        limit_gradients(&dt, &mut data);
    }
    let first_ghost = dt.num_vertices();
    add_border_ghosts(set, &mut dt, &mut data, mode)
        .map_err(|e| bad(format!("triangulation failed: {e:?}")))?;
    if limited {
        mark_ghost_edges(&dt, &mut data, first_ghost);
    } else {
        mark_boundaries(&dt, &mut data);
    }

    let centre = |x: usize, y: usize| Point2::new(x as f64 + 0.5, y as f64 + 0.5);
    let (centres, (row_start, at_centre)) = rayon::join(
        || Circumcentres::new(&dt),
        || {
            let mut row_start = Vec::with_capacity(h);
            let mut hint = FixedVertexHandle::from_index(0);
            for y in 0..h {
                hint = vertex_of(&dt, dt.locate_with_hint(centre(0, y), hint)).unwrap_or(hint);
                row_start.push(hint);
            }
            // Samples exactly at a pixel centre (every sample of a one-pixel quadtree
            // cell) give that pixel their value in either mode; no query needed.
            let mut at_centre = vec![None; w * h];
            for v in dt.vertices() {
                let p = data.pos[v.data().idx as usize];
                let (x, y) = (p.x.floor(), p.y.floor());
                if p.x - x == 0.5 && p.y - y == 0.5 && x >= 0.0 && y >= 0.0 {
                    let (x, y) = (x as usize, y as usize);
                    if x < w && y < h {
                        at_centre[y * w + x] = Some(v.fix());
                    }
                }
            }
            (row_start, at_centre)
        },
    );

    let mut image = vec![Vec3::ZERO; w * h];
    image.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut ctx = Ctx::new(&dt, &data, &centres);
        let mut hint = row_start[y];
        for (x, out) in row.iter_mut().enumerate() {
            let (value, next) = match at_centre[y * w + x] {
                Some(v) => (data.value[ctx.sample(v)], v),
                None => {
                    let (value, next) = ctx.pixel(centre(x, y), hint, mode);
                    (value, next.unwrap_or(hint))
                }
            };
            hint = next;
            *out = value.as_vec3a();
        }
    });
    Ok(Reconstruction {
        width: w,
        height: h,
        image,
        density: set.density(),
    })
}

/// Barth–Jespersen slope limiting of the sample gradients (Barth & Jespersen 1989,
/// the standard limiter on unstructured meshes), per colour channel.
///
/// A Monte Carlo gradient is noisy, and the visibility term is heavy-tailed (a line
/// grazing a blocker); one outlier, expanded over a large quadtree cell by the C1
/// interpolant's Taylor terms, paints a bright or negative blob. The limiter scales
/// each sample's gradient by the largest φ ∈ [0, 1] for which its first-order
/// expansion, evaluated at the midpoint of every Delaunay edge to a same-surface
/// neighbour, stays within the range of the values of the sample and those
/// neighbours. Linear images pass unchanged (φ = 1), as do smooth slopes; only
/// expansions that overshoot every neighbour are cut back.
///
/// It reads every Delaunay edge of every sample anyway, so it also fills
/// `Data::near_boundary` for the samples.
fn limit_gradients(dt: &Dt, data: &mut Data) {
    let d = &*data;
    let adjacency = Adjacency::new(dt, d);
    // Independent per sample, so it runs in parallel (and stays deterministic: the
    // range and the factor are a minimum and maximum, whatever the order).
    let limited: Vec<(bool, DVec3)> = (0..d.pos.len())
        .into_par_iter()
        .map(|i| {
            let links = adjacency.of(i);
            let near = links.iter().any(|&(_, cross)| cross);
            let same = || links.iter().filter(|l| !l.1).map(|&(j, _)| j as usize);
            let (lo, hi) = same().fold((d.value[i], d.value[i]), |(lo, hi), j| {
                (lo.min(d.value[j]), hi.max(d.value[j]))
            });
            let mut f = DVec3::ONE;
            for j in same() {
                let half = (d.pos[j] - d.pos[i]) * 0.5;
                let delta = d.grad_u[i] * half.x + d.grad_v[i] * half.y;
                for c in 0..3 {
                    let room = if delta[c] > 0.0 { hi[c] } else { lo[c] } - d.value[i][c];
                    if delta[c] != 0.0 {
                        f[c] = f[c].min((room / delta[c]).clamp(0.0, 1.0));
                    }
                }
            }
            (near, f)
        })
        .collect();
    let mut near_boundary = Vec::with_capacity(limited.len());
    for (i, (near, f)) in limited.into_iter().enumerate() {
        near_boundary.push(near);
        data.grad_u[i] *= f;
        data.grad_v[i] *= f;
    }
    data.near_boundary = near_boundary;
}

/// The Delaunay neighbours of every sample, each with whether the edge to it
/// crosses a surface boundary: read once from spade's edge list (contiguous), each
/// edge tested once, then laid out per sample (compressed rows).
struct Adjacency {
    start: Vec<u32>,
    links: Vec<(u32, bool)>,
}

impl Adjacency {
    fn new(dt: &Dt, d: &Data) -> Self {
        let edges: Vec<[u32; 2]> = dt
            .undirected_edges()
            .map(|e| e.vertices().map(|v| v.data().idx))
            .collect();
        let cross: Vec<bool> = edges
            .par_iter()
            .map(|&[a, b]| d.differ(a as usize, b as usize))
            .collect();
        let mut start = vec![0u32; d.pos.len() + 1];
        for &[a, b] in &edges {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for k in 1..start.len() {
            start[k] += start[k - 1];
        }
        let mut next = start.clone();
        let mut links = vec![(0, false); 2 * edges.len()];
        for (&[a, b], &x) in edges.iter().zip(&cross) {
            for (from, to) in [(a, b), (b, a)] {
                links[next[from as usize] as usize] = (to, x);
                next[from as usize] += 1;
            }
        }
        Self { start, links }
    }

    fn of(&self, i: usize) -> &[(u32, bool)] {
        &self.links[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// Extends `Data::near_boundary` over the ghosts (vertices from `first_ghost` on):
/// every edge their insertion made touches one of them. Edges it removed may leave
/// a flag behind, which only sends a pixel through the full surface test.
fn mark_ghost_edges(dt: &Dt, data: &mut Data, first_ghost: usize) {
    data.near_boundary.resize(data.pos.len(), false);
    for k in first_ghost..dt.num_vertices() {
        let v = dt.vertex(FixedVertexHandle::from_index(k));
        let g = v.data().idx as usize;
        for e in v.out_edges() {
            let j = e.to().data().idx as usize;
            if data.differ(g, j) {
                data.near_boundary[g] = true;
                data.near_boundary[j] = true;
            }
        }
    }
}

/// Fills `Data::near_boundary` from the Delaunay edges (each tested once, in
/// parallel: three tests per sample instead of several per pixel).
fn mark_boundaries(dt: &Dt, data: &mut Data) {
    let d = &*data;
    let edges: Vec<FixedUndirectedEdgeHandle> = dt.fixed_undirected_edges().collect();
    let crossing: Vec<[usize; 2]> = edges
        .into_par_iter()
        .filter_map(|k| {
            let e = dt.undirected_edge(k);
            let [a, b] = e.vertices().map(|v| v.data().idx as usize);
            d.differ(a, b).then_some([a, b])
        })
        .collect();
    let mut near = vec![false; d.pos.len()];
    for i in crossing.into_iter().flatten() {
        near[i] = true;
    }
    data.near_boundary = near;
}

/// Mirror images ("ghosts") of the samples whose cells touch the image border,
/// reflected across that border (and across both at a corner).
///
/// Without them the convex hull of the samples stops up to half a block inside the
/// image, and the Delaunay triangles along it are long slivers: a pixel in that strip
/// gets natural neighbours (or a triangle) from far along the border, possibly from
/// another surface — dark or negative columns at the image edge. With the ghosts the
/// hull covers every pixel centre and each border pixel is interpolated from the
/// samples next to it. A ghost sits on its source's surface and carries the source's
/// extension to its position, so both modes stay exact on linear images: the
/// first-order Taylor expansion (`Gradient`), or the plane of the best-shaped
/// same-surface triangle around the source (`Linear`, which must not use gradients).
fn add_border_ghosts(
    set: &SampleSet,
    dt: &mut Dt,
    data: &mut Data,
    mode: Interpolation,
) -> std::result::Result<(), spade::InsertionError> {
    let (w, h) = (set.width as f64, set.height as f64);
    let mut ghosts: Vec<(usize, FixedVertexHandle, DVec2, DVec3)> = Vec::new();
    {
        // Ghost values are extrapolations: no natural-neighbour query, no table.
        let none = Circumcentres::default();
        let ctx = Ctx::new(dt, data, &none);
        for v in dt.vertices() {
            let i = v.data().idx as usize;
            let s = &set.samples[i];
            let p = data.pos[i];
            let xs = mirrored(p.x, s.cell_min.x, s.cell_max.x, w);
            let ys = mirrored(p.y, s.cell_min.y, s.cell_max.y, h);
            let mut push = |q: DVec2| {
                // A sample on the border line itself is its own mirror image.
                if q == p {
                    return;
                }
                let value = ctx.extrapolate(v, Point2::new(q.x, q.y), mode, false);
                ghosts.push((i, v.fix(), q, value));
            };
            for &mx in xs.iter().flatten() {
                push(DVec2::new(mx, p.y));
                for &my in ys.iter().flatten() {
                    push(DVec2::new(mx, my));
                }
            }
            for &my in ys.iter().flatten() {
                push(DVec2::new(p.x, my));
            }
        }
    }
    for (src, near, q, value) in ghosts {
        // Start the insertion walk at the source sample, next to its mirror image.
        ScanlineHint::set(near);
        let idx = data.pos.len() as u32;
        data.pos.push(q);
        data.value.push(value);
        data.grad_u.push(data.grad_u[src]);
        data.grad_v.push(data.grad_v[src]);
        // The source's tangent plane extended to the ghost, so that the two read as
        // one surface (a mirrored depth would fold at the border).
        let source = data.surface[src];
        let pos = q.as_vec2();
        let inv = source.inv_depth + source.inv_depth_grad.dot(pos - source.pos);
        let extended = source.inv_depth > 0.0 && inv > 0.0 && inv.is_finite();
        data.surface.push(SurfacePoint {
            pos,
            inv_depth: if extended { inv } else { source.inv_depth },
            inv_depth_grad: if extended {
                source.inv_depth_grad
            } else {
                Vec2::ZERO
            },
            ..source
        });
        dt.insert(Node::new(q, idx))?;
    }
    Ok(())
}

/// Coordinate `x` mirrored across each end of `[0, extent]` that its cell `[lo, hi]`
/// touches.
fn mirrored(x: f64, lo: f32, hi: f32, extent: f64) -> [Option<f64>; 2] {
    [
        (lo <= 0.0).then_some(-x),
        (hi as f64 >= extent).then_some(2.0 * extent - x),
    ]
}

/// A vertex of a locate answer, used as the next walk's start.
fn vertex_of(dt: &Dt, loc: PositionInTriangulation) -> Option<FixedVertexHandle> {
    match loc {
        PositionInTriangulation::OnVertex(v) => Some(v),
        PositionInTriangulation::OnEdge(e) | PositionInTriangulation::OutsideOfConvexHull(e) => {
            Some(dt.directed_edge(e).from().fix())
        }
        PositionInTriangulation::OnFace(f) => Some(dt.face(f).vertices()[0].fix()),
        PositionInTriangulation::NoTriangulation => None,
    }
}

/// Per-row scratch state.
struct Ctx<'a> {
    dt: &'a Dt,
    data: &'a Data,
    centres: &'a Circumcentres,
    scratch: natural::Scratch,
    weights: Vec<(FixedVertexHandle, f64)>,
    kept: Vec<(usize, f64)>,
    /// The triangle of the previous pixel, tried before walking.
    last_face: Option<FixedFaceHandle<InnerTag>>,
}

impl<'a> Ctx<'a> {
    /// `centres` must be `dt`'s (or empty where no natural-neighbour query is made).
    fn new(dt: &'a Dt, data: &'a Data, centres: &'a Circumcentres) -> Self {
        Self {
            dt,
            data,
            centres,
            scratch: natural::Scratch::default(),
            weights: Vec::with_capacity(16),
            kept: Vec::with_capacity(16),
            last_face: None,
        }
    }

    fn sample(&self, v: FixedVertexHandle) -> usize {
        self.dt.vertex(v).data().idx as usize
    }

    /// The value at `p` and the vertex to start the next walk from.
    fn pixel(
        &mut self,
        p: Point2<f64>,
        hint: FixedVertexHandle,
        mode: Interpolation,
    ) -> (DVec3, Option<FixedVertexHandle>) {
        self.weights.clear();
        let loc = self.locate(p, hint);
        let next = vertex_of(self.dt, loc);
        match mode {
            Interpolation::Linear => self.barycentric(p, loc),
            Interpolation::Gradient => {
                let (dt, centres) = (self.dt, self.centres);
                natural::weights(dt, centres, &mut self.scratch, p, loc, &mut self.weights);
            }
        }
        if self.weights.is_empty() {
            let (value, nearest) = self.outside(p, hint, mode);
            return (value, nearest.or(next));
        }
        self.keep_majority_surface();
        let value = match mode {
            Interpolation::Linear => self
                .kept
                .iter()
                .fold(DVec3::ZERO, |acc, &(i, w)| acc + self.data.value[i] * w),
            Interpolation::Gradient => self.sibson_c1(p),
        };
        (value, next)
    }

    /// Where `p` lies. Neighbouring pixels mostly fall in the same triangle, so the
    /// previous pixel's is tried first, then its three neighbours (strictly inside,
    /// so the answer is the one the walk would give); otherwise the walk starts at
    /// `hint`, the previous pixel's neighbourhood, so it is short and depends only
    /// on the row, not on the thread.
    fn locate(&mut self, p: Point2<f64>, hint: FixedVertexHandle) -> PositionInTriangulation {
        let inside = |c: [f64; 3]| c.iter().all(|&w| w > 1e-9);
        if let Some(f) = self.last_face {
            let face = self.dt.face(f);
            if inside(face.barycentric_interpolation(p)) {
                return PositionInTriangulation::OnFace(f);
            }
            // Else `p` has mostly crossed one edge into the next triangle.
            for e in face.adjacent_edges() {
                if let Some(g) = e.rev().face().as_inner() {
                    if inside(g.barycentric_interpolation(p)) {
                        self.last_face = Some(g.fix());
                        return PositionInTriangulation::OnFace(g.fix());
                    }
                }
            }
        }
        let mut loc = self.dt.locate_with_hint(p, hint);
        if let PositionInTriangulation::OutsideOfConvexHull(e) = loc {
            // A point on the hull of the exact positions (all samples on one line:
            // the nudge turns the line into slivers) can fall just outside the
            // nudged hull; it is on that edge, as before the nudge.
            let [a, b] = self
                .dt
                .directed_edge(e)
                .positions()
                .map(|q| DVec2::new(q.x, q.y));
            let (ab, ap) = (b - a, DVec2::new(p.x, p.y) - a);
            let t = ap.dot(ab) / ab.length_squared();
            if (0.0..=1.0).contains(&t) && (ap - ab * t).length() <= NUDGE * 4.0 {
                loc = PositionInTriangulation::OnEdge(e);
            }
        }
        self.last_face = match loc {
            PositionInTriangulation::OnFace(f) => Some(f),
            _ => None,
        };
        loc
    }

    /// Barycentric weights of `p` in the located element.
    fn barycentric(&mut self, p: Point2<f64>, loc: PositionInTriangulation) {
        match loc {
            PositionInTriangulation::OnVertex(v) => self.weights.push((v, 1.0)),
            PositionInTriangulation::OnEdge(e) => {
                let [a, b] = self.dt.directed_edge(e).vertices();
                let (pa, pb) = (a.position(), b.position());
                let ab = DVec2::new(pb.x - pa.x, pb.y - pa.y);
                let ap = DVec2::new(p.x - pa.x, p.y - pa.y);
                let t = (ap.dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                self.weights.extend([(a.fix(), 1.0 - t), (b.fix(), t)]);
            }
            PositionInTriangulation::OnFace(f) => {
                let face = self.dt.face(f);
                let c = face.barycentric_interpolation(p);
                let v = face.vertices();
                self.weights
                    .extend([(v[0].fix(), c[0]), (v[1].fix(), c[1]), (v[2].fix(), c[2])]);
            }
            _ => {}
        }
    }

    /// Keeps the samples of the surface with the largest total weight and
    /// renormalises their weights into `kept`. A surface is the set of samples
    /// compatible with an anchor sample (`Data::differ` is false); every contributing
    /// sample is tried as the anchor and the heaviest group wins (ties: the heavier
    /// anchor, then the earlier one).
    fn keep_majority_surface(&mut self) {
        self.kept.clear();
        for k in 0..self.weights.len() {
            let (v, w) = self.weights[k];
            self.kept.push((self.sample(v), w));
        }
        let data = self.data;
        // Common case first: away from every boundary nothing is dropped (the
        // contributing samples are joined by Delaunay edges, none of which crosses
        // one). Then: the first sample's group is everyone.
        if self.kept.iter().all(|&(i, _)| !data.near_boundary[i]) {
            return;
        }
        let first = self.kept[0].0;
        if self.kept.iter().all(|&(b, _)| !data.differ(first, b)) {
            return;
        }
        let mut best = (f64::NEG_INFINITY, f64::NEG_INFINITY, 0usize);
        for &(a, wa) in &self.kept {
            let group: f64 = self
                .kept
                .iter()
                .filter(|&&(b, _)| !data.differ(a, b))
                .map(|&(_, wb)| wb)
                .sum();
            if group > best.0 || (group == best.0 && wa > best.1) {
                best = (group, wa, a);
            }
        }
        let anchor = best.2;
        self.kept.retain(|&(b, _)| !data.differ(anchor, b));
        let sum: f64 = self.kept.iter().map(|k| k.1).sum();
        if sum > 0.0 {
            for k in &mut self.kept {
                k.1 /= sum;
            }
        }
    }

    /// Sibson's C1 interpolant with flatness 0.5 on the kept natural neighbours, per
    /// colour channel — the formula of spade's `interpolate_gradient` (Sibson 1981;
    /// Flötotto's thesis §4.1), written out so that it runs on a filtered neighbour set
    /// and on three channels at once:
    /// `ζ_i = I_i + ∇I_i·(p − p_i)`, `c_i = λ_i / r_i`, `α = Σ c_i r_i² / Σ c_i`,
    /// `β = Σ λ_i r_i²`, `I = (α Σ λ_i I_i + β Σ c_i ζ_i / Σ c_i) / (α + β)`.
    fn sibson_c1(&self, p: Point2<f64>) -> DVec3 {
        let p = DVec2::new(p.x, p.y);
        let (mut sum_c0, mut sum_c1) = (DVec3::ZERO, DVec3::ZERO);
        let (mut sum_c1_w, mut alpha, mut beta) = (0.0, 0.0, 0.0);
        for &(i, w) in &self.kept {
            let diff = p - self.data.pos[i];
            let r2 = diff.length_squared();
            if r2 == 0.0 {
                return self.data.value[i];
            }
            let c1_w = w / r2.sqrt();
            let zeta =
                self.data.value[i] + self.data.grad_u[i] * diff.x + self.data.grad_v[i] * diff.y;
            alpha += c1_w * r2;
            beta += w * r2;
            sum_c1_w += c1_w;
            sum_c1 += zeta * c1_w;
            sum_c0 += self.data.value[i] * w;
        }
        if sum_c1_w.is_nan() || sum_c1_w <= 0.0 {
            return sum_c0;
        }
        alpha /= sum_c1_w;
        sum_c1 /= sum_c1_w;
        let denom = alpha + beta;
        if denom.is_nan() || denom <= 0.0 {
            return sum_c0;
        }
        (sum_c0 * alpha + sum_c1 * beta) / denom
    }

    /// Extrapolation outside the convex hull (see the module documentation).
    fn outside(
        &mut self,
        p: Point2<f64>,
        hint: FixedVertexHandle,
        mode: Interpolation,
    ) -> (DVec3, Option<FixedVertexHandle>) {
        ScanlineHint::set(hint);
        let Some(s) = self.dt.nearest_neighbor(p) else {
            return (DVec3::ZERO, None);
        };
        (self.extrapolate(s, p, mode, true), Some(s.fix()))
    }

    /// The value at `p` (outside the hull) extended from sample `s`: for `Gradient`,
    /// `s`'s own Taylor expansion, blended with its same-surface neighbours' when
    /// `blend` is set.
    fn extrapolate(
        &self,
        s: VHandle<'_>,
        p: Point2<f64>,
        mode: Interpolation,
        blend: bool,
    ) -> DVec3 {
        let si = s.data().idx as usize;
        let pd = DVec2::new(p.x, p.y);
        match mode {
            Interpolation::Linear => self.extend_plane(s, pd).unwrap_or(self.data.value[si]),
            Interpolation::Gradient if !blend => {
                let diff = pd - self.data.pos[si];
                self.data.value[si] + self.data.grad_u[si] * diff.x + self.data.grad_v[si] * diff.y
            }
            Interpolation::Gradient => {
                let mut acc = DVec3::ZERO;
                let mut wsum = 0.0;
                let neighbours = s.out_edges().map(|e| e.to().data().idx as usize);
                for k in std::iter::once(si).chain(neighbours) {
                    if self.data.differ(si, k) {
                        continue;
                    }
                    let diff = pd - self.data.pos[k];
                    let r2 = diff.length_squared();
                    let taylor = self.data.value[k]
                        + self.data.grad_u[k] * diff.x
                        + self.data.grad_v[k] * diff.y;
                    if r2 == 0.0 {
                        return taylor;
                    }
                    acc += taylor / r2;
                    wsum += 1.0 / r2;
                }
                acc / wsum
            }
        }
    }

    /// Linear extrapolation with the plane of the best-shaped same-object triangle
    /// around `s` (largest smallest barycentric weight of `p`).
    fn extend_plane(&self, s: VHandle<'_>, p: DVec2) -> Option<DVec3> {
        let si = s.data().idx as usize;
        let mut best: Option<(f64, [usize; 3], [f64; 3])> = None;
        for e in s.out_edges() {
            let Some(face) = e.face().as_inner() else {
                continue;
            };
            let idx = face.vertices().map(|v| v.data().idx as usize);
            if idx.iter().any(|&i| self.data.differ(si, i)) {
                continue;
            }
            let [a, b, c] = idx.map(|i| self.data.pos[i]);
            let det = (b - a).perp_dot(c - a);
            if det == 0.0 {
                continue;
            }
            let l1 = (p - a).perp_dot(c - a) / det;
            let l2 = (b - a).perp_dot(p - a) / det;
            let l = [1.0 - l1 - l2, l1, l2];
            let score = l[0].min(l[1]).min(l[2]);
            if best.is_none_or(|b| score > b.0) {
                best = Some((score, idx, l));
            }
        }
        best.map(|(_, idx, l)| {
            (0..3).fold(DVec3::ZERO, |acc, k| acc + self.data.value[idx[k]] * l[k])
        })
    }
}
