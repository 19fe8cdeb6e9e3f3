//! Sibson's natural-neighbour coordinates on a finished triangulation, with the
//! circumcentre of every Delaunay triangle computed once.
//!
//! This is spade's `NaturalNeighbor::get_weights` (same cavity search, same polygon
//! areas, same order of the neighbours), written out because it was the largest cost
//! of reconstruction: spade recomputes the circumcentre of each triangle of the
//! insertion cavity once for every one of its three corners, per query, and goes
//! through `RefCell` buffers. Here the triangles' circumcentres are a table built once
//! per triangulation, so a query computes only the circumcentres of its new Voronoi
//! cell. The test `matches_spades_natural_neighbour_weights` holds the two equal.

use super::{Dt, Node};
use glam::DVec2;
use rayon::prelude::*;
use spade::handles::{
    DirectedEdgeHandle, FixedDirectedEdgeHandle, FixedFaceHandle, FixedVertexHandle, InnerTag,
};
use spade::{Point2, PositionInTriangulation, Triangulation};

type Edge<'a> = DirectedEdgeHandle<'a, Node, (), (), ()>;

/// The circumcircle of every triangle of one triangulation, by face index.
#[derive(Default)]
pub(super) struct Circumcentres(Vec<Circle>);

#[derive(Clone, Copy, Default)]
struct Circle {
    centre: DVec2,
    /// Squared radius; NaN where the triangle is so flat that its centre is not
    /// accurate enough for [`Circumcentres::holds`] (the exact test decides there).
    r2: f64,
}

impl Circle {
    fn of([a, b, c]: [DVec2; 3]) -> Self {
        // From the corner opposite the longest edge: its angle is the largest, so
        // once the radius is bounded below its sine is too, and the centre is
        // accurate (from a needle's sharp corner it is not).
        let (o, u, v) = [(a, b, c), (b, c, a), (c, a, b)]
            .into_iter()
            .max_by(|x, y| {
                x.1.distance_squared(x.2)
                    .total_cmp(&y.1.distance_squared(y.2))
            })
            .expect("three corners");
        let longest = u.distance_squared(v);
        let rel = circumcentre(u - o, v - o);
        let r2 = rel.length_squared();
        Self {
            centre: o + rel,
            // R = longest / (2 sin O): this keeps sin O ≥ 1/20.
            r2: if r2 <= 100.0 * longest { r2 } else { f64::NAN },
        }
    }
}

impl Circumcentres {
    /// The table of `dt`'s triangles (computed in parallel).
    pub(super) fn new(dt: &Dt) -> Self {
        let faces: Vec<FixedFaceHandle<InnerTag>> = dt.fixed_inner_faces().collect();
        let computed: Vec<Circle> = faces
            .par_iter()
            .map(|&f| Circle::of(dt.face(f).positions().map(dvec)))
            .collect();
        let mut circles = vec![Circle::default(); dt.num_all_faces()];
        for (f, c) in faces.iter().zip(computed) {
            circles[f.index()] = c;
        }
        Self(circles)
    }

    /// Whether `p` lies strictly inside the circumcircle of `face`, where a plain
    /// distance test is certain: `None` within a band of rounding around the circle
    /// (well-shaped triangles: centre error ~1e-15 of the radius, the band 1e-9).
    fn holds(&self, face: usize, p: DVec2) -> Option<bool> {
        let c = self.0[face];
        let d = (p - c.centre).length_squared() - c.r2;
        let band = 1e-9 * c.r2 + 1e-12 * c.r2.sqrt() * (1.0 + c.centre.abs().max_element());
        if d > band {
            Some(false)
        } else if d < -band {
            Some(true)
        } else {
            None
        }
    }
}

/// Per-thread scratch space of the queries.
#[derive(Default)]
pub(super) struct Scratch {
    stack: Vec<FixedDirectedEdgeHandle>,
    boundary: Vec<FixedDirectedEdgeHandle>,
    cell: Vec<DVec2>,
}

/// Fills `out` with the natural-neighbour coordinates of `p` (summing to one), or
/// leaves it empty outside the convex hull. `loc` is where `p` lies in `dt`.
pub(super) fn weights(
    dt: &Dt,
    centres: &Circumcentres,
    scratch: &mut Scratch,
    p: Point2<f64>,
    loc: PositionInTriangulation,
    out: &mut Vec<(FixedVertexHandle, f64)>,
) {
    out.clear();
    let boundary = &mut scratch.boundary;
    boundary.clear();
    match loc {
        PositionInTriangulation::OnVertex(v) => {
            out.push((v, 1.0));
            return;
        }
        PositionInTriangulation::OnEdge(e) => {
            let e = dt.directed_edge(e);
            if e.is_part_of_convex_hull() {
                // On the hull only the edge's two ends are natural neighbours.
                let [a, b] = e.positions().map(dvec);
                let t = (dvec(p) - a).dot(b - a) / (b - a).length_squared();
                out.extend([(e.from().fix(), 1.0 - t), (e.to().fix(), t)]);
                return;
            }
            for start in [e, e.rev()] {
                cavity(dt, centres, &mut scratch.stack, boundary, start, p);
            }
        }
        PositionInTriangulation::OnFace(f) => {
            let edges = dt.face(f).adjacent_edges();
            for start in edges.into_iter().rev().map(|e| e.rev()) {
                cavity(dt, centres, &mut scratch.stack, boundary, start, p);
            }
        }
        _ => return,
    }
    boundary.reverse();
    let p = dvec(p);

    // The new Voronoi cell of `p`: one corner per cavity boundary edge, the
    // circumcentre of `p` and that edge (relative to `p`).
    let cell = &mut scratch.cell;
    cell.clear();
    cell.extend(boundary.iter().map(|&e| {
        let [from, to] = dt.directed_edge(e).positions().map(dvec);
        circumcentre(to - p, from - p)
    }));

    // Each neighbour loses to `p` the polygon between two consecutive corners of the
    // new cell and the old Voronoi vertices (circumcentres of the cavity's triangles
    // around it). Shoelace areas, the positive and negative parts summed apart.
    let mut total = 0.0;
    let mut last_edge = dt.directed_edge(*boundary.last().expect("a cavity has edges"));
    let mut last = *cell.last().expect("a cavity has edges");
    for (&stop, &first) in boundary.iter().zip(cell.iter()) {
        let stop = dt.directed_edge(stop);
        let mut positive = first.x * last.y;
        let mut negative = first.y * last.x;
        loop {
            let face = last_edge.face().fix().index();
            let current = centres.0[face].centre - p;
            positive += last.x * current.y;
            negative += last.y * current.x;
            last_edge = last_edge.next().rev();
            last = current;
            if last_edge == stop.rev() {
                positive += current.x * first.y;
                negative += current.y * first.x;
                break;
            }
        }
        let area = positive - negative;
        total += area;
        out.push((stop.from().fix(), area));
        last = first;
        last_edge = stop;
    }
    for w in out.iter_mut() {
        w.1 /= total;
    }
}

/// Grows the insertion cavity of `p` across `start` (directed away from it) and
/// appends the edges that bound it, in spade's order: a triangle whose circumcircle
/// holds `p` joins the cavity and its two far edges are examined in turn.
fn cavity(
    dt: &Dt,
    centres: &Circumcentres,
    stack: &mut Vec<FixedDirectedEdgeHandle>,
    boundary: &mut Vec<FixedDirectedEdgeHandle>,
    start: Edge<'_>,
    p: Point2<f64>,
) {
    stack.clear();
    stack.push(start.fix());
    while let Some(e) = stack.pop() {
        let e = dt.directed_edge(e);
        // The triangle beyond `e` (on its left), if any.
        let inside = e.opposite_vertex().is_some_and(|far| {
            let face = e.face().fix().index();
            centres.holds(face, dvec(p)).unwrap_or_else(|| {
                // robust's in-circle test wants the triangle clockwise: to, from, far.
                let c = |q: Point2<f64>| robust::Coord { x: q.x, y: q.y };
                let [from, to] = e.positions();
                robust::incircle(c(to), c(from), c(far.position()), c(p)) < 0.0
            })
        });
        if inside {
            stack.push(e.next().rev().fix());
            stack.push(e.prev().rev().fix());
        } else {
            boundary.push(e.rev().fix());
        }
    }
}

/// Circumcentre of the triangle (0, b, c), relative to its first corner.
fn circumcentre(b: DVec2, c: DVec2) -> DVec2 {
    let d = 2.0 * (b.x * c.y - c.x * b.y);
    let (lb, lc) = (b.length_squared(), c.length_squared());
    DVec2::new(lb * c.y - lc * b.y, lc * b.x - lb * c.x) / d
}

fn dvec(p: Point2<f64>) -> DVec2 {
    DVec2::new(p.x, p.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampler::hash2;

    fn unit(i: u32, k: u32) -> f64 {
        f64::from(hash2(i, k)) / f64::from(u32::MAX)
    }

    /// The reconstruction's triangulation of `points` (nudged vertices).
    fn triangulate(points: &[DVec2]) -> Dt {
        let nodes = points
            .iter()
            .enumerate()
            .map(|(i, &p)| Node::new(p, i as u32))
            .collect();
        Dt::bulk_load_stable(nodes).unwrap()
    }

    /// Largest difference from spade's natural-neighbour weights over `queries`
    /// (same neighbours in the same order), and how many queries had neighbours.
    fn compare(points: &[DVec2], queries: &[DVec2]) -> (f64, usize) {
        let dt = triangulate(points);
        let centres = Circumcentres::new(&dt);
        let nn = dt.natural_neighbor();
        let (mut scratch, mut ours, mut theirs) = (Scratch::default(), vec![], vec![]);
        let (mut worst, mut inside) = (0.0f64, 0);
        for &q in queries {
            let q = Point2::new(q.x, q.y);
            weights(&dt, &centres, &mut scratch, q, dt.locate(q), &mut ours);
            nn.get_weights(q, &mut theirs);
            assert_eq!(ours.len(), theirs.len(), "neighbour count at {q:?}");
            inside += usize::from(!ours.is_empty());
            let sum: f64 = ours.iter().map(|w| w.1).sum();
            if !ours.is_empty() {
                assert!((sum - 1.0).abs() < 1e-12, "weights sum to {sum} at {q:?}");
            }
            for (a, b) in ours.iter().zip(&theirs) {
                assert_eq!(a.0, b.0, "neighbour order at {q:?}");
                worst = worst.max((a.1 - b.1).abs());
            }
        }
        (worst, inside)
    }

    #[test]
    fn matches_spades_natural_neighbour_weights() {
        // Scattered points, queried anywhere (some outside the hull).
        let points: Vec<DVec2> = (0..400)
            .map(|i| DVec2::new(unit(i, 1), unit(i, 2)) * 100.0)
            .collect();
        let queries: Vec<DVec2> = (0..4000)
            .map(|i| DVec2::new(unit(i, 3), unit(i, 4)) * 110.0 - 5.0)
            .collect();
        let (worst, inside) = compare(&points, &queries);
        assert!(inside > 3000, "{inside} queries inside the hull");
        assert!(worst < 1e-9, "largest weight difference {worst:e}");

        // A quadtree-like lattice (8 px blocks, some split to 4 and 2 px: cocircular
        // quadruples everywhere) queried at every pixel centre, on samples included.
        let mut lattice = vec![];
        for by in 0..8 {
            for bx in 0..8 {
                let o = DVec2::new(bx as f64, by as f64) * 8.0;
                lattice.push(o + 4.0);
                if (bx + by) % 3 == 0 {
                    for (dx, dy) in [(2.0, 2.0), (6.0, 2.0), (2.0, 6.0), (6.0, 6.0)] {
                        lattice.push(o + DVec2::new(dx, dy));
                    }
                    for (dx, dy) in [(1.0, 1.0), (3.0, 1.0), (1.0, 3.0), (3.0, 3.0)] {
                        lattice.push(o + DVec2::new(dx, dy));
                    }
                }
            }
        }
        let pixels: Vec<DVec2> = (0..64 * 64)
            .map(|i| DVec2::new((i % 64) as f64 + 0.5, (i / 64) as f64 + 0.5))
            .chain(lattice.iter().copied())
            .collect();
        let (worst, inside) = compare(&lattice, &pixels);
        assert!(inside > 3000, "{inside} queries inside the hull");
        assert!(worst < 1e-9, "largest weight difference {worst:e}");
    }

    /// Wherever the distance test decides, it agrees with the exact in-circle test,
    /// also on needles (two vertices 1e-9..1e-8 px apart, the others px away),
    /// for points within 1e-12..1e-5 of a radius of each circle. Computed from the
    /// needle's sharp corner, the centre was off by more than the band: thousands of
    /// disagreements.
    #[test]
    fn the_distance_test_agrees_with_the_exact_in_circle_test() {
        let (mut decided, mut wrong) = (0, 0);
        for cfg in 0..40u32 {
            let base = DVec2::new(40.3 + f64::from(cfg) * 7.13, 40.7 + f64::from(cfg) * 3.1);
            let sep = [1e-9, 3e-9, 1e-8][cfg as usize % 3];
            let dir = unit(cfg, 9) * std::f64::consts::TAU;
            let mut points = vec![base, base + DVec2::from_angle(dir) * sep];
            for k in 0..7 {
                let a = f64::from(k) * 0.9 + unit(cfg, 10 + k) * 0.5;
                points.push(base + DVec2::from_angle(a) * (3.0 + 20.0 * unit(cfg, 30 + k)));
            }
            let dt = triangulate(&points);
            let centres = Circumcentres::new(&dt);
            for face in dt.inner_faces() {
                let [a, b, c] = face.positions().map(dvec);
                // The queries ring the circle as computed from every corner in turn
                // (from at least one of them it is accurate).
                let circles = [(a, b, c), (b, c, a), (c, a, b)].map(|(o, u, v)| {
                    let rel = circumcentre(u - o, v - o);
                    (o + rel, rel.length())
                });
                for j in 0..600u32 {
                    let (centre, r) = circles[j as usize % 3];
                    let phi = unit(j, 77 + cfg) * std::f64::consts::TAU;
                    let offset = 10f64.powf(-12.0 + 7.0 * unit(j, 91 + cfg));
                    let scale = if j % 2 == 0 {
                        1.0 + offset
                    } else {
                        1.0 - offset
                    };
                    let q = centre + DVec2::from_angle(phi) * r * scale;
                    let rc = |p: DVec2| robust::Coord { x: p.x, y: p.y };
                    // `a, b, c` counter-clockwise: positive means inside.
                    let exact = robust::incircle(rc(a), rc(b), rc(c), rc(q)) > 0.0;
                    if let Some(fast) = centres.holds(face.fix().index(), q) {
                        decided += 1;
                        wrong += usize::from(fast != exact);
                    }
                }
            }
        }
        assert!(decided > 10_000, "only {decided} queries decided");
        assert_eq!(wrong, 0, "{wrong} of {decided} decided queries disagree");
    }
}
